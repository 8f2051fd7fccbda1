/*
 * rp_track_feed.c - feeding a tracker from outside (rp_track.h): the second camera of a stereo
 * pair follows only the features matched into it from the pair's first camera (rp_pipe).
 * Apart from rp_track.c, which tests/test_track.c builds a second time (scalar kernels).
 */
#include <stddef.h>

#include "priv/rp_math.h"
#include "rigpose/rp_track.h"

rp_status_t rp_track_keep_owned(rp_tracker_t *trk, uint8_t owner, uint16_t *n_kept)
{
    if (trk == NULL || owner >= RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    uint16_t m = 0;
    for (uint16_t i = 0; i < trk->n; ++i) {
        if (rp_track_id_cam(trk->id[i]) == owner) {
            trk->id[m] = trk->id[i];
            trk->pos_q16[m][0] = trk->pos_q16[i][0];
            trk->pos_q16[m][1] = trk->pos_q16[i][1];
            ++m;
        }
    }
    trk->n = m;
    if (n_kept != NULL) {
        *n_kept = m;
    }
    return RP_OK;
}

rp_status_t rp_track_drop_ids(rp_tracker_t *trk, const uint32_t *ids, uint16_t n_ids,
                              uint16_t *n_dropped)
{
    if (trk == NULL || (n_ids > 0 && ids == NULL)) {
        return RP_E_ARG;
    }
    uint16_t m = 0;
    for (uint16_t i = 0; i < trk->n; ++i) {
        uint16_t j = 0;
        while (j < n_ids && ids[j] != trk->id[i]) {
            ++j;
        }
        if (j == n_ids) {
            trk->id[m] = trk->id[i];
            trk->pos_q16[m][0] = trk->pos_q16[i][0];
            trk->pos_q16[m][1] = trk->pos_q16[i][1];
            ++m;
        }
    }
    if (n_dropped != NULL) {
        *n_dropped = (uint16_t)(trk->n - m);
    }
    trk->n = m;
    return RP_OK;
}

rp_status_t rp_track_adopt(rp_tracker_t *trk, const rp_feat_t *f)
{
    if (trk == NULL || f == NULL) {
        return RP_E_ARG;
    }
    if (!rp_finite(f->uv[0]) || !rp_finite(f->uv[1])) {
        return RP_E_NAN;
    }
    if (trk->n >= RP_MAX_FEATS_PER_CAM) {
        return RP_E_FULL;
    }
    trk->id[trk->n] = f->id;
    trk->pos_q16[trk->n][0] = (int32_t)rp_floor(f->uv[0] * RP_C(65536.0) + RP_C(0.5));
    trk->pos_q16[trk->n][1] = (int32_t)rp_floor(f->uv[1] * RP_C(65536.0) + RP_C(0.5));
    trk->n++;
    return RP_OK;
}

rp_status_t rp_track_features(const rp_tracker_t *trk, rp_feat_t *out, uint16_t cap,
                              uint16_t *n)
{
    if (trk == NULL || (cap > 0 && out == NULL) || n == NULL) {
        return RP_E_ARG;
    }
    const uint16_t nw = trk->n < cap ? trk->n : cap;
    for (uint16_t i = 0; i < nw; ++i) {
        out[i].id = trk->id[i];
        out[i].uv[0] = (rp_real)trk->pos_q16[i][0] / RP_C(65536.0);
        out[i].uv[1] = (rp_real)trk->pos_q16[i][1] / RP_C(65536.0);
    }
    *n = nw;
    return trk->n > cap ? RP_E_FULL : RP_OK;
}

rp_status_t rp_track_next_serial(const rp_tracker_t *trk, uint32_t *k)
{
    if (trk == NULL || k == NULL) {
        return RP_E_ARG;
    }
    *k = trk->next_k;
    return RP_OK;
}

rp_status_t rp_track_set_next_serial(rp_tracker_t *trk, uint32_t k)
{
    if (trk == NULL || k > RP_TRACK_SERIAL_MASK) {
        return RP_E_ARG;
    }
    trk->next_k = k;
    return RP_OK;
}

rp_status_t rp_track_current_pyr(const rp_tracker_t *trk, const rp_pyr_t **pyr)
{
    if (trk == NULL || pyr == NULL) {
        return RP_E_ARG;
    }
    *pyr = &trk->pyr[trk->cur];
    return RP_OK;
}
