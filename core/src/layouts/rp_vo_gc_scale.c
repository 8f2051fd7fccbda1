/*
 * rp_vo_gc_scale.c - gc's metric scale (rp_vo_gc.h, step 6): the keyframes, the scalar filter on
 * the map's unit mu (map units per metre), and the window correction after an adjustment
 * (rp_gcba.h). The filter and the landmarks are rp_vo_gc.c's; this file changes them only
 * through a new unit (rp_vo_gc_set_mu, change_mu) and the correction (correct_pose).
 */
#include <string.h>

#include "priv/rp_math.h"
#include "priv/rp_select.h"
#include "priv/rp_sym3.h"
#include "priv/rp_vo_gc_scale.h"
#include "rigpose/rp_rot.h"

static rp_gcba_state_t ba_state(const rp_vo_gc_t *vo)
{
    rp_gcba_state_t st = RP_GCBA_IDLE;
    /* ignored: fails only on NULL / a bad index: ours */
    (void)rp_gcba_state(&vo->ba, &st);
    return st;
}

void rp_vo_gc_scale_reset(rp_vo_gc_t *vo)
{
    rp_vo_gc_set_mu(vo, RP_C(1.0));
    vo->mu_var = vo->cfg.mscale_sigma * vo->cfg.mscale_sigma;
    /* ignored: fails only on NULL / a bad index: ours */
    (void)rp_gcba_reset(&vo->ba,
                        vo->cfg.mscale_sigma > RP_C(0.0) ? vo->cfg.ba_kf : RP_VO_GC_BA_MIN_KF);
    vo->kf_since = 0;
    vo->n_ba = 0;
    vo->n_ba_rejected = 0;
    vo->ba_refused_run = 0;
    memset(&vo->ba_last, 0, sizeof(vo->ba_last));
}

/* The map's unit: mu map units per metre; the rig in map units has offsets D_k * mu. */
void rp_vo_gc_set_mu(rp_vo_gc_t *vo, rp_real mu)
{
    vo->rig_m = *vo->rig;
    vo->mu = mu;
    for (uint8_t k = 0; k < vo->rig_m.n_cams; ++k) {
        for (int a = 0; a < 3; ++a) {
            vo->rig_m.cam[k].D[a] = mu * vo->rig->cam[k].D[a];
        }
    }
}

/* A new map unit: offsets D_k * mu. Each landmark moves with its camera's centre at the
 * current pose (by R_j D_k (mu - mu_old)), so that its ray from that camera stays as it was:
 * the landmarks' depths were measured from the cameras, in map units. */
static void change_mu(rp_vo_gc_t *vo, rp_real mu)
{
    rp_pose_lin_t pl;
    const rp_real dmu = mu - vo->mu;
    if (rp_pose_lin_set(&pl, vo->ekf.x) == RP_OK) {
        for (uint16_t slot = 0; slot < RP_IDMAP_MAX_SLOTS; ++slot) {
            uint8_t cam;
            if (rp_lmtab_slot(&vo->lm, slot, NULL, &cam, NULL) != RP_OK) {
                continue;
            }
            rp_point3_t *pt = &vo->lm.pt[slot];
            const rp_real *D = vo->rig->cam[cam].D;
            for (int a = 0; a < 3; ++a) {
                pt->M[a] += dmu * (pl.R[a * 3 + 0] * D[0] + pl.R[a * 3 + 1] * D[1] +
                                     pl.R[a * 3 + 2] * D[2]);
            }
        }
    }
    rp_vo_gc_set_mu(vo, mu);
}

/* After an adjustment: the window's poses in map units (the oldest keyframe stays where it was,
 * the others follow the solution's motion from it, converted at the map unit the window itself
 * implies: the map keeps its own unit, the window only gives its shape) go back into the ring;
 * the correction T_c that takes the newest keyframe from the filter's pose to the solved one is
 * applied to every landmark and to the filter's pose now (the adjustment was spread over the
 * frames since that keyframe), so that the map keeps its place relative to the rig; then the
 * adjusted landmarks take the solution's positions. */
static rp_status_t correct_pose(rp_vo_gc_t *vo)
{
    /* Everything is computed before anything changes: a failure leaves the window, the map and
     * the filter as they were (never half corrected). */
    uint8_t nk;
    uint16_t n_lm;
    rp_real p0[6], s0[6], po[6], sk[6];
    rp_real pk[RP_GCBA_MAX_KF][6];
    if (rp_gcba_counts(&vo->ba, &nk, &n_lm) != RP_OK || nk < 2 || nk > RP_GCBA_MAX_KF ||
        rp_gcba_kf_pose(&vo->ba, 0, p0) != RP_OK || rp_gcba_solved_pose(&vo->ba, 0, s0) != RP_OK ||
        rp_gcba_kf_pose(&vo->ba, (uint8_t)(nk - 1), po) != RP_OK) {
        return RP_E_ARG; /* nothing to correct against (fewer than two keyframes) */
    }
    for (uint8_t k = 1; k < nk; ++k) {
        if (rp_gcba_solved_pose(&vo->ba, k, sk) != RP_OK) {
            return RP_E_ARG;
        }
        for (int a = 0; a < 3; ++a) {
            pk[k][a] = p0[a] + vo->ba_last.mu * (sk[a] - s0[a]);
            pk[k][3 + a] = sk[3 + a];
        }
    }
    /* the newest keyframe, as the filter had it (po) and as solved (pn): T_c = T_pn T_po^-1 */
    const rp_real *pn = pk[nk - 1];
    rp_real Ro[9], Rn[9], Rc[9], tc[3], t[3];
    rp_rot_from_angles(&po[3], Ro);
    rp_rot_from_angles(&pn[3], Rn);
    rp_rot_mul_a_bt(Rn, Ro, Rc);
    rp_rot_apply(Rc, po, t);
    for (int a = 0; a < 3; ++a) {
        tc[a] = pn[a] - t[a];
    }
    /* the filter's pose now (a frame or more after the keyframe) follows the same T_c */
    rp_real v[3], w[3], tx[3], Rj[9], Rnew[9], ang[3];
    rp_rot_from_angles(&vo->ekf.x[3], Rj);
    rp_rot_mul(Rc, Rj, Rnew);
    if (rp_rot_to_angles(Rnew, ang) != RP_OK || !rp_all_finite(tc, 3)) {
        return RP_E_NAN;
    }
    rp_rot_apply(Rc, vo->ekf.x, tx);
    rp_rot_apply(Rc, &vo->ekf.x[6], v);
    /* the world-frame angular rate turns with the world: (Rc R)' = [Rc omega]x Rc R */
    rp_rot_apply(Rc, &vo->ekf.x[9], w);

    /* ---- commit ---- */
    for (uint8_t k = 1; k < nk; ++k) {
        /* ignored: fails only on NULL / a bad index: ours (k < nk, checked above) */
        (void)rp_gcba_set_pose(&vo->ba, k, pk[k]);
    }
    for (uint16_t slot = 0; slot < RP_IDMAP_MAX_SLOTS; ++slot) {
        if (rp_lmtab_slot(&vo->lm, slot, NULL, NULL, NULL) != RP_OK) {
            continue;
        }
        rp_point3_t *pt = &vo->lm.pt[slot];
        rp_real M[3], C[9], T[9], Cn[9];
        rp_rot_apply(Rc, pt->M, M);
        for (int a = 0; a < 3; ++a) {
            pt->M[a] = M[a] + tc[a];
        }
        rp_sym3_unpack(pt->C, C);
        rp_rot_mul(Rc, C, T);
        rp_rot_mul_a_bt(T, Rc, Cn);
        rp_sym3_pack(Cn, pt->C);
    }
    /* the adjusted landmarks replace the filter's, in map units */
    for (uint16_t i = 0; i < n_lm; ++i) {
        uint32_t id;
        uint8_t cam;
        uint16_t slot;
        rp_real X[3], C[6];
        if (rp_gcba_landmark(&vo->ba, i, &id, &cam, X, C) != RP_OK ||
            rp_lmtab_find(&vo->lm, id, &slot) != RP_OK || vo->lm.map.slot_group[slot] != cam) {
            continue; /* a landmark the window holds and the map no longer does */
        }
        rp_point3_t *pt = &vo->lm.pt[slot];
        const rp_real m2 = vo->ba_last.mu * vo->ba_last.mu;
        for (int a = 0; a < 3; ++a) {
            pt->M[a] = p0[a] + vo->ba_last.mu * (X[a] - s0[a]);
        }
        for (int a = 0; a < 6; ++a) {
            pt->C[a] = m2 * C[a];
        }
    }
    for (int a = 0; a < 3; ++a) {
        vo->ekf.x[a] = tx[a] + tc[a];
        vo->ekf.x[3 + a] = ang[a];
        vo->ekf.x[6 + a] = v[a];
        vo->ekf.x[9 + a] = w[a];
    }
    return RP_OK;
}

/* select_lowest(h, idx, n, want): priv/rp_select.h */
RP_DEFINE_SELECT_LOWEST(select_lowest, uint32_t)

/* The adjustment under way is solved: its result into mu, the map and the pose. */
static void take_adjustment(rp_vo_gc_t *vo)
{
    rp_gcba_result_t *r = &vo->ba_last;
    const rp_status_t st = rp_gcba_finish(&vo->ba, r);
    const rp_real var_obs = r->mu_var * vo->cfg.ba_var_scale;
    const rp_real dm = r->mu - vo->mu;
    /* refused: a failed or unconverged adjustment (residuals well above the pixel noise), one
     * that took no step (its first one raised the cost: it ends where it began, at the unit it
     * started from, which it would then confirm with its own variance), or one more than
     * RP_VO_GC_BA_GATE_SIGMA sigma from the current unit; after RP_VO_GC_BA_MAX_REFUSED such
     * refusals in a row of converged adjustments the current unit is the suspect: it restarts
     * from the next one */
    if (st != RP_OK || r->rms_px > RP_VO_GC_BA_MAX_RMS * vo->cfg.ba.sigma_px ||
        !(r->rms_px < r->rms0_px)) {
        vo->n_ba_rejected++;
        return;
    }
    if (dm * dm >
        RP_VO_GC_BA_GATE_SIGMA * RP_VO_GC_BA_GATE_SIGMA * (vo->mu_var + var_obs)) {
        vo->n_ba_rejected++;
        if (++vo->ba_refused_run < RP_VO_GC_BA_MAX_REFUSED) {
            return;
        }
        vo->mu_var = vo->cfg.mscale_sigma * vo->cfg.mscale_sigma * vo->mu * vo->mu;
    }
    vo->ba_refused_run = 0;
    /* scalar Kalman update of mu with the window's value */
    const rp_real k = vo->mu_var / (vo->mu_var + var_obs);
    const rp_real mu = vo->mu + k * (r->mu - vo->mu);
    vo->mu_var = (RP_C(1.0) - k) * vo->mu_var;
    change_mu(vo, mu);
    vo->n_ba++;
    if (correct_pose(vo) != RP_OK) {
        vo->n_ba_rejected++; /* the scale was fused; the window's poses could not be applied */
    }
}

/* Step 6 (rp_vo_gc.h): keep this frame as a keyframe every ba_stride frames and, every ba_every
 * keyframes, fuse the map's unit that the window's adjustment implies. */
void rp_vo_gc_scale_step(rp_vo_gc_t *vo, const rp_frameset_t *fs, int busy)
{
    if (!(vo->cfg.mscale_sigma > RP_C(0.0))) {
        return;
    }
    vo->mu_var += vo->cfg.mscale_q * vo->mu * vo->mu;
    /* an adjustment under way advances by one piece per frame (start, steps, result), so no
     * frame pays for all of it; nor one that re-found its pose (rig RANSAC costs about a
     * piece): its piece waits a frame; a keyframe due before it is done finishes it first */
    if (!busy && (ba_state(vo) == RP_GCBA_STARTED || ba_state(vo) == RP_GCBA_ITERATING)) {
        if (rp_gcba_step(&vo->ba) != RP_OK) {
            vo->n_ba_rejected++;
        }
    }
    if (ba_state(vo) == RP_GCBA_SOLVED) {
        take_adjustment(vo);
    }
    if (vo->frame % vo->cfg.ba_stride != 0) {
        return;
    }
    if (ba_state(vo) != RP_GCBA_IDLE) {
        take_adjustment(vo);
    }
    /* per camera, the ba_per_cam landmarks whose ids hash lowest: mostly the same ones from
     * one keyframe to the next, as long as they live */
    rp_gcba_obs_t *o = vo->kf_obs;
    uint16_t m = 0;
    for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
        const uint8_t cam = vo->cfg.cams[k];
        uint16_t nc = 0;
        for (uint16_t f = 0; f < fs->n[cam]; ++f) {
            const rp_feat_t *ft = &fs->f[cam][f];
            uint16_t slot;
            if (!rp_all_finite(ft->uv, 2) || rp_lmtab_find(&vo->lm, ft->id, &slot) != RP_OK ||
                vo->lm.map.slot_group[slot] != cam || vo->taken[slot] != vo->frame + 1u) {
                continue;
            }
            vo->kf_hash[nc] = rp_idmap_hash(ft->id);
            vo->kf_feat[nc] = f;
            nc++;
        }
        const uint16_t want = vo->cfg.ba_per_cam;
        if (nc > want) {
            select_lowest(vo->kf_hash, vo->kf_feat, (int)nc, (int)want);
            nc = want;
        }
        for (uint16_t i = 0; i < nc && m < RP_GCBA_MAX_OBS_KF; ++i) {
            const rp_feat_t *ft = &fs->f[cam][vo->kf_feat[i]];
            o[m].id = ft->id;
            o[m].uv[0] = (float)ft->uv[0];
            o[m].uv[1] = (float)ft->uv[1];
            o[m].cam = cam;
            m++;
        }
    }
    /* each camera's images at its capture time (rp_ekf.h): stamp offset plus clock offset */
    rp_real cam_dt[RP_MAX_CAMS];
    for (uint8_t c = 0; c < RP_MAX_CAMS; ++c) {
        cam_dt[c] = (rp_real)fs->cam_dt_us[c] * RP_C(1e-6) + vo->ekf.toff[c];
    }
    if (rp_gcba_add_keyframe(&vo->ba, vo->ekf.x, o, m, vo->ekf.x + 6, cam_dt) != RP_OK) {
        return;
    }
    uint8_t n_kf = 0;
    uint16_t n_lm;
    /* ignored: fails only on NULL / a bad index: ours */
    (void)rp_gcba_counts(&vo->ba, &n_kf, &n_lm);
    if (++vo->kf_since < vo->cfg.ba_every || n_kf < RP_VO_GC_BA_MIN_KF) {
        return;
    }
    vo->kf_since = 0;
    if (rp_gcba_start(&vo->ba, vo->rig, vo->mu, &vo->cfg.ba) != RP_OK) {
        vo->n_ba_rejected++;
    }
}
