/*
 * rp_lmtab.c - the estimators' landmark table (see rp_lmtab.h).
 */
#include <string.h>

#include "priv/rp_math.h"
#include "rigpose/rp_lmtab.h"

rp_status_t rp_lmtab_clear(rp_lmtab_t *t)
{
    return t ? rp_idmap_clear(&t->map) : RP_E_ARG;
}

rp_status_t rp_lmtab_insert(rp_lmtab_t *t, uint32_t id, uint8_t group, const rp_point3_t *pt,
                            uint16_t *slot)
{
    if (!t || !pt) {
        return RP_E_ARG;
    }
    uint16_t s;
    const rp_status_t st = rp_idmap_insert(&t->map, id, group, &s);
    if (st == RP_OK) {
        t->pt[s] = *pt;
        if (slot) {
            *slot = s;
        }
    }
    return st;
}

rp_status_t rp_lmtab_find(const rp_lmtab_t *t, uint32_t id, uint16_t *slot)
{
    return t ? rp_idmap_find(&t->map, id, slot) : RP_E_ARG;
}

rp_status_t rp_lmtab_slot(const rp_lmtab_t *t, uint16_t slot, uint32_t *id, uint8_t *group,
                          rp_point3_t *pt)
{
    if (!t || slot >= RP_IDMAP_MAX_SLOTS) {
        return RP_E_ARG;
    }
    if (t->map.slot_id[slot] == RP_IDMAP_EMPTY) {
        return RP_E_NOT_FOUND;
    }
    if (id) {
        *id = t->map.slot_id[slot];
    }
    if (group) {
        *group = t->map.slot_group[slot];
    }
    if (pt) {
        *pt = t->pt[slot];
    }
    return RP_OK;
}

rp_status_t rp_lmtab_gather(const rp_lmtab_t *t, const rp_frameset_t *fs, const uint8_t *cams,
                            uint8_t n_cams, uint8_t own_group, rp_obs_t *obs, uint32_t *ids,
                            uint32_t cap, uint32_t *n)
{
    if (!t || !fs || (n_cams > 0 && !cams) || !obs || !ids || !n) {
        return RP_E_ARG;
    }
    uint32_t k = 0;
    *n = 0;
    for (uint8_t c = 0; c < n_cams; ++c) {
        const uint8_t cam = cams[c];
        if (cam >= RP_MAX_CAMS) {
            return RP_E_ARG;
        }
        const uint16_t nf = fs->n[cam] < RP_MAX_FEATS_PER_CAM ? fs->n[cam] : RP_MAX_FEATS_PER_CAM;
        for (uint16_t f = 0; f < nf; ++f) {
            const rp_feat_t *ft = &fs->f[cam][f];
            uint16_t s;
            if (!rp_all_finite(ft->uv, 2) || rp_idmap_find(&t->map, ft->id, &s) != RP_OK ||
                (own_group && t->map.slot_group[s] != cam)) {
                continue;
            }
            if (k == cap) {
                *n = k;
                return RP_E_FULL;
            }
            rp_obs_t *o = &obs[k];
            o->uv[0] = ft->uv[0];
            o->uv[1] = ft->uv[1];
            memcpy(o->M, t->pt[s].M, sizeof(o->M));
            o->w = RP_C(1.0);
            o->dt = (rp_real)fs->cam_dt_us[cam] * RP_C(1e-6);
            o->cam = cam;
            ids[k] = ft->id;
            k++;
        }
    }
    *n = k;
    return RP_OK;
}

rp_status_t rp_lmtab_mark_ids(rp_lmtab_t *t, const uint32_t *ids, const uint8_t *used,
                              uint32_t n)
{
    if (!t || (n > 0 && !ids)) {
        return RP_E_ARG;
    }
    for (uint32_t i = 0; i < n; ++i) {
        uint16_t s;
        if ((!used || used[i]) && rp_idmap_find(&t->map, ids[i], &s) == RP_OK) {
            /* ignored: only NULL arguments fail */
            (void)rp_idmap_mark(&t->map, s);
        }
    }
    return RP_OK;
}

rp_status_t rp_lmtab_drop_unmarked(rp_lmtab_t *t, uint32_t group_mask, uint16_t *n_dropped)
{
    return t ? rp_idmap_drop_unmarked(&t->map, group_mask, n_dropped) : RP_E_ARG;
}

rp_status_t rp_lmtab_refine(rp_lmtab_t *t, const rp_rig_t *rig, const rp_real p[6],
                            const rp_real xi[6], const rp_real toff[RP_MAX_CAMS],
                            const rp_obs_t *obs, const uint32_t *ids, const uint8_t *used,
                            uint32_t n, rp_real sigma_px, rp_real gate_chi2)
{
    if (!t || !rig || !p || (n > 0 && (!obs || !ids))) {
        return RP_E_ARG;
    }
    rp_pose_lin_t pl;
    rp_status_t st = rp_pose_lin_set(&pl, p);
    if (st != RP_OK) {
        return st;
    }
    rp_real delta = RP_C(0.0); /* of pl */
    for (uint32_t i = 0; i < n; ++i) {
        uint16_t s;
        if ((!used || used[i]) && rp_idmap_find(&t->map, ids[i], &s) == RP_OK) {
            const uint8_t c = obs[i].cam;
            const rp_real d = xi && toff && c < RP_MAX_CAMS ? obs[i].dt + toff[c] : RP_C(0.0);
            if (d != delta) {
                if (rp_pose_lin_at(&pl, p, xi, d) != RP_OK) {
                    continue; /* a non-finite stamp: this observation only */
                }
                delta = d;
            }
            /* ignored: a point its gate refuses stays as it was (the gate, not a fault) */
            (void)rp_struct_update(&t->pt[s], rig, obs[i].cam, &pl, obs[i].uv, sigma_px,
                                   gate_chi2);
        }
    }
    return RP_OK;
}
