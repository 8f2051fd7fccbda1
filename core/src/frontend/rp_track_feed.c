/*
 * rp_track_feed.c - feeding a tracker from outside (rp_track.h): the second camera of a stereo
 * pair follows only the features matched into it from the pair's first camera (rp_pipe).
 * Apart from rp_track.c, which tests/test_track.c builds a second time (scalar kernels).
 */
#include <stddef.h>

#include "priv/rp_math.h"
#include "rigpose/rp_track.h"

static void count_dormant(rp_tracker_t *trk)
{
    uint16_t d = 0;
    for (uint16_t i = 0; i < trk->n; ++i) {
        d = (uint16_t)(d + trk->dormant[i]);
    }
    trk->n_dormant = d;
}

/* Track i moved to slot m (m <= i). */
static void move_track(rp_tracker_t *trk, uint16_t m, uint16_t i)
{
    trk->id[m] = trk->id[i];
    trk->pos_q16[m][0] = trk->pos_q16[i][0];
    trk->pos_q16[m][1] = trk->pos_q16[i][1];
    trk->dormant[m] = trk->dormant[i];
}

static int listed(const uint32_t *ids, uint16_t n_ids, uint32_t id)
{
    for (uint16_t j = 0; j < n_ids; ++j) {
        if (ids[j] == id) {
            return 1;
        }
    }
    return 0;
}

/* Keeps, in their order, the tracks from camera owner (any camera for RP_MAX_CAMS) whose id is
 * not among ids[0..n_ids-1]; returns how many were dropped. */
static uint16_t keep_where(rp_tracker_t *trk, uint8_t owner, const uint32_t *ids, uint16_t n_ids)
{
    uint16_t m = 0;
    for (uint16_t i = 0; i < trk->n; ++i) {
        if ((owner == RP_MAX_CAMS || rp_track_id_cam(trk->id[i]) == owner) &&
            !listed(ids, n_ids, trk->id[i])) {
            move_track(trk, m++, i);
        }
    }
    const uint16_t dropped = (uint16_t)(trk->n - m);
    trk->n = m;
    count_dormant(trk);
    return dropped;
}

rp_status_t rp_track_keep_owned(rp_tracker_t *trk, uint8_t owner, uint16_t *n_kept)
{
    if (trk == NULL || owner >= RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    (void)keep_where(trk, owner, NULL, 0); /* the count: trk->n */
    if (n_kept != NULL) {
        *n_kept = trk->n;
    }
    return RP_OK;
}

rp_status_t rp_track_drop_ids(rp_tracker_t *trk, const uint32_t *ids, uint16_t n_ids,
                              uint16_t *n_dropped)
{
    if (trk == NULL || (n_ids > 0 && ids == NULL)) {
        return RP_E_ARG;
    }
    const uint16_t dropped = keep_where(trk, RP_MAX_CAMS, ids, n_ids);
    if (n_dropped != NULL) {
        *n_dropped = dropped;
    }
    return RP_OK;
}

rp_status_t rp_track_set_dormant(rp_tracker_t *trk, const uint32_t *ids, uint16_t n_ids,
                                 uint16_t *n_marked)
{
    if (trk == NULL || (n_ids > 0 && ids == NULL)) {
        return RP_E_ARG;
    }
    uint16_t marked = 0;
    for (uint16_t i = 0; i < trk->n; ++i) {
        if (!trk->dormant[i] && listed(ids, n_ids, trk->id[i])) {
            trk->dormant[i] = 1;
            ++marked;
        }
    }
    trk->n_dormant = (uint16_t)(trk->n_dormant + marked);
    if (n_marked != NULL) {
        *n_marked = marked;
    }
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
    trk->dormant[trk->n] = 0;
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
