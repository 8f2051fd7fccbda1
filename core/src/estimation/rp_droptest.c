/*
 * rp_droptest.c - Page's CUSUM drop test of landmarks' tracks (rp_droptest.h).
 */
#include "rigpose/rp_droptest.h"

#include <stddef.h>

#include "priv/rp_math.h"

rp_status_t rp_droptest_reset_slot(rp_droptest_t *dt, uint16_t slot)
{
    if (dt == NULL || slot >= RP_IDMAP_MAX_SLOTS) {
        return RP_E_ARG;
    }
    dt->s[slot] = RP_C(0.0);
    dt->was_in[slot] = 0;
    dt->seen[slot] = 0;
    return RP_OK;
}

rp_status_t rp_droptest_run(rp_droptest_t *dt, const uint16_t *slot, const uint8_t *in,
                            uint32_t n, uint32_t min_past, rp_real odds, uint8_t *keep)
{
    if (dt == NULL || (n > 0 && (slot == NULL || in == NULL || keep == NULL)) ||
        !(odds > RP_C(1.0)) || !rp_finite(odds)) {
        return RP_E_ARG;
    }
    uint32_t n_was = 0, n_was_out = 0, n_out = 0;
    for (uint32_t i = 0; i < n; ++i) {
        n_out += !in[i];
        if (slot[i] < RP_IDMAP_MAX_SLOTS && dt->was_in[slot[i]]) {
            n_was++;
            n_was_out += !in[i];
        }
    }
    /* eps: the share left out of the observations whose landmark the previous update took in
     * (Krichevsky-Trofimov: never 0); all observations while fewer than min_past have a past */
    const int past = n_was >= min_past;
    rp_real eps = ((rp_real)(past ? n_was_out : n_out) + RP_C(0.5)) /
                  ((rp_real)(past ? n_was : n) + RP_C(1.0));
    eps = eps < RP_C(0.5) ? eps : RP_C(0.5);
    const rp_real l_out = rp_log((RP_C(1.0) - RP_DROP_PASS) / eps);
    const rp_real l_in = rp_log(RP_DROP_PASS / (RP_C(1.0) - eps));
    const rp_real h = rp_log(odds);
    for (uint32_t i = 0; i < n; ++i) { /* this frame set's sum per landmark */
        const uint16_t s = slot[i];
        if (s < RP_IDMAP_MAX_SLOTS) {
            if (!dt->seen[s]) {
                dt->sum[s] = dt->s[s];
                dt->seen[s] = 1;
            }
            dt->sum[s] += in[i] ? l_in : l_out;
            dt->seen[s] = (uint8_t)(in[i] ? 2 : dt->seen[s]);
        }
    }
    for (uint32_t i = 0; i < n; ++i) {
        keep[i] = in[i];
        const uint16_t s = slot[i];
        if (s >= RP_IDMAP_MAX_SLOTS) {
            continue;
        }
        if (dt->seen[s]) { /* its first observation: the new S */
            dt->s[s] = dt->sum[s] > RP_C(0.0) ? dt->sum[s] : RP_C(0.0);
            dt->was_in[s] = (uint8_t)(dt->seen[s] == 2);
            dt->seen[s] = 0;
        }
        keep[i] = (uint8_t)(dt->s[s] <= h);
    }
    return RP_OK;
}
