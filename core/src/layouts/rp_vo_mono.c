/*
 * rp_vo_mono.c - one camera on its own (see rp_vo_mono.h; the step numbers are the paper's).
 */
#include <string.h>

#include "priv/rp_math.h"
#include "rigpose/rp_lowe.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_vo.h"
#include "rigpose/rp_vo_mono.h"

#define RANSAC_SEED 0x5EED5u /* any fixed value: the run is a function of its input */

rp_vo_mono_cfg_t rp_vo_mono_default_cfg(void)
{
    rp_vo_mono_cfg_t c;
    memset(&c, 0, sizeof(c));
    c.cam = 0;
    c.ekf = rp_ekf_default_params();
    c.min_tracked = 50;
    c.init_depth_m = RP_C(1.0);
    c.init_depth_sigma_m = RP_C(0.3);
    c.default_dt_s = RP_C(1.0) / RP_C(30.0);
    c.weight_by_structure = 1;
    c.one_point = 1; /* config/README.md, `one_point`: its cost and gain */
    c.ransac = 1;
    return c;
}

rp_status_t rp_vo_mono_init(rp_vo_mono_t *vo, const rp_rig_t *rig, const rp_vo_mono_cfg_t *cfg)
{
    rp_ekf_t idle;
    rp_status_t st = vo && cfg ? rp_vo_init_filter(rig, &cfg->ekf, &idle) : RP_E_ARG;
    if (st != RP_OK) {
        return st;
    }
    if (cfg->cam >= rig->n_cams || cfg->min_tracked < 6 || !(cfg->init_depth_m > RP_C(0.0)) ||
        !(cfg->init_depth_sigma_m > RP_C(0.0)) || !(cfg->default_dt_s > RP_C(0.0)) ||
        !rp_finite(cfg->init_depth_m) || !rp_finite(cfg->init_depth_sigma_m) ||
        cfg->one_point > 1 || cfg->ransac > 1) {
        return RP_E_ARG;
    }
    memset(vo, 0, sizeof(*vo));
    vo->rig = rig;
    vo->cfg = *cfg;
    vo->own.n_cams = 1;
    memset(vo->own.cam[0].R, 0, sizeof(vo->own.cam[0].R));
    vo->own.cam[0].R[0] = vo->own.cam[0].R[4] = vo->own.cam[0].R[8] = RP_C(1.0);
    vo->own.cam[0].cam = rig->cam[cfg->cam].cam;
    vo->ekf = idle;
    /* one camera: its offset is a known shift of its stamps, never a state (nothing to hold it
     * to); the filter's rig has it as camera 0 */
    rp_real off[RP_MAX_CAMS] = {0};
    off[0] = cfg->ekf.toff0_s[cfg->cam];
    st = rp_ekf_toff_set(&vo->ekf, 0, off, NULL, RP_C(0.0));
    if (st != RP_OK) {
        return st;
    }
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_clear(&vo->lm);
    (void)rp_ekf1pt_seed(&vo->op, RANSAC_SEED);
    /* ignored: only NULL arguments fail */
    (void)rp_ransac_seed(&vo->rs, RANSAC_SEED);
    return RP_OK;
}

rp_status_t rp_vo_mono_to_rig(const rp_rig_t *rig, uint8_t k, const rp_real p_own[6],
                              rp_real p_rig[6])
{
    if (!rig || !p_own || !p_rig || k >= rig->n_cams || k >= RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(p_own, 6)) {
        return RP_E_NAN;
    }
    const rp_real *Rk = rig->cam[k].R;
    const rp_real *Dk = rig->cam[k].D;
    rp_real r[9], Rj[9], l[3], RjD[3];
    rp_rot_from_angles(&p_own[3], r);
    rp_rot_mul(Rk, r, Rj);
    rp_rot_mul_a_bt(Rj, Rk, Rj); /* R_j = R_k r_kj R_k^T (eq. 3) */
    rp_rot_apply(Rk, p_own, l);
    rp_rot_apply(Rj, Dk, RjD);
    rp_real out[6];
    for (int i = 0; i < 3; ++i) {
        out[i] = l[i] + Dk[i] - RjD[i]; /* eq. 4 with unit scales */
    }
    rp_status_t st = rp_rot_to_angles(Rj, &out[3]);
    if (st != RP_OK) {
        return st;
    }
    memcpy(p_rig, out, sizeof(out));
    return RP_OK;
}

/* ---- step (1): orthographic initialisation ----------------------------------------------- */

/* Place feature uv on the plane z = init depth of the camera at own pose pl. */
static rp_status_t ortho_point(const rp_vo_mono_t *vo, const rp_pose_lin_t *pl,
                               const rp_real uv[2], rp_point3_t *pt)
{
    rp_real xn[2];
    rp_status_t st = rp_cam_unproject(&vo->own.cam[0].cam, uv, xn);
    if (st != RP_OK) {
        return st;
    }
    const rp_real z = vo->cfg.init_depth_m;
    const rp_real r[3] = {xn[0], xn[1], RP_C(1.0)};
    const rp_real P[3] = {xn[0] * z, xn[1] * z, z};
    st = rp_rig_world_point(&vo->own, 0, pl, P, pt->M);
    if (st != RP_OK) {
        return st;
    }
    /* Camera-frame covariance: sz^2 r r^T (depth along the ray) + sp^2 I (pixel noise across). */
    const rp_real f = vo->own.cam[0].cam.fx;
    const rp_real sp = vo->cfg.ekf.sigma_px * (z + vo->cfg.init_depth_sigma_m) / f;
    const rp_real sz2 = vo->cfg.init_depth_sigma_m * vo->cfg.init_depth_sigma_m;
    rp_real Cc[9], A[9], T[9], Cw[9];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            Cc[i * 3 + j] = sz2 * r[i] * r[j] + (i == j ? sp * sp : RP_C(0.0));
        }
    }
    /* World = R_j (camera), own camera at R = I. */
    memcpy(A, pl->R, sizeof(A));
    rp_rot_mul(A, Cc, T);
    rp_rot_mul_a_bt(T, A, Cw);
    pt->C[0] = Cw[0];
    pt->C[1] = Cw[1];
    pt->C[2] = Cw[2];
    pt->C[3] = Cw[4];
    pt->C[4] = Cw[5];
    pt->C[5] = Cw[8];
    return RP_OK;
}

/* 1 if id is among fs's features of camera cam. */
static int has_id(const rp_frameset_t *fs, uint8_t cam, uint32_t id)
{
    for (uint16_t g = 0; g < fs->n[cam]; ++g) {
        if (fs->f[cam][g].id == id) {
            return 1;
        }
    }
    return 0;
}

/* Add features f[0..n-1] (not yet held) at own pose p; with only_in, only those still tracked. */
static uint16_t add_features(rp_vo_mono_t *vo, const rp_feat_t *f, uint16_t n, const rp_real p[6],
                             const rp_frameset_t *only_in)
{
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, p) != RP_OK) {
        return 0;
    }
    uint16_t added = 0;
    for (uint16_t i = 0; i < n; ++i) {
        uint16_t slot;
        if (f[i].id == RP_VO_MONO_EMPTY_ID || !rp_all_finite(f[i].uv, 2) ||
            rp_lmtab_find(&vo->lm, f[i].id, &slot) == RP_OK ||
            (only_in && !has_id(only_in, vo->cfg.cam, f[i].id))) {
            continue;
        }
        rp_point3_t pt;
        if (ortho_point(vo, &pl, f[i].uv, &pt) != RP_OK) {
            continue;
        }
        if (rp_lmtab_insert(&vo->lm, f[i].id, 0, &pt, NULL) != RP_OK) {
            break;
        }
        added++;
    }
    return added;
}

/* ---- measurements ------------------------------------------------------------------------ */

/* Weight of an observation of pt at pose pl: s^2 / (s^2 + mean projected point variance). */
static rp_real obs_weight(const rp_vo_mono_t *vo, const rp_pose_lin_t *pl, const rp_point3_t *pt)
{
    if (!vo->cfg.weight_by_structure) {
        return RP_C(1.0);
    }
    rp_real uv[2], J[6];
    if (rp_rig_project(&vo->own, 0, pl, pt->M, uv, NULL, J) != RP_OK) {
        return RP_C(1.0);
    }
    const rp_real *c = pt->C;
    const rp_real C[9] = {c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5]};
    rp_real tr = RP_C(0.0);
    for (int r = 0; r < 2; ++r) {
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                tr += J[r * 3 + i] * C[i * 3 + j] * J[r * 3 + j];
            }
        }
    }
    const rp_real s2 = vo->cfg.ekf.sigma_px * vo->cfg.ekf.sigma_px;
    const rp_real w = s2 / (s2 + RP_C(0.5) * tr);
    return rp_finite(w) && w > RP_VO_MONO_MIN_WEIGHT ? w : RP_VO_MONO_MIN_WEIGHT;
}

/* Gather the observations of held landmarks of camera cfg.cam in fs into vo->obs (as camera 0
 * of the own rig), weighted at the predicted pose p_pred. */
static uint32_t gather_obs(rp_vo_mono_t *vo, const rp_frameset_t *fs, const rp_real p_pred[6])
{
    rp_pose_lin_t pl;
    const int have_pl = rp_pose_lin_set(&pl, p_pred) == RP_OK;
    uint32_t n = 0;
    /* ignored: cannot fill: the cap holds a whole frame set */
    (void)rp_lmtab_gather(&vo->lm, fs, &vo->cfg.cam, 1, 0, vo->obs, vo->obs_id,
                          RP_MAX_FEATS_PER_CAM, &n);
    for (uint32_t i = 0; i < n; ++i) {
        uint16_t slot;
        rp_obs_t *o = &vo->obs[i];
        o->cam = 0;
        if (have_pl && rp_lmtab_find(&vo->lm, vo->obs_id[i], &slot) == RP_OK) {
            o->w = obs_weight(vo, &pl, &vo->lm.pt[slot]);
        }
    }
    return n;
}

static void fill_estimates(const rp_vo_mono_t *vo, int64_t utime, uint32_t flags,
                           rp_estimate_t *est, rp_estimate_t *own)
{
    rp_estimate_t e;
    memset(&e, 0, sizeof(e));
    /* a single camera's scale is the assumed depth's */
    /* ignored: only NULL arguments fail */
    (void)rp_vo_fill_estimate(&vo->ekf, RP_C(1.0), utime, vo->frame, flags | RP_EST_SCALE_WEAK,
                              vo->lm.map.n, &e);
    if (own) {
        *own = e;
    }
    /* Rig pose through the extrinsics (eqs. 3-4). In rp_rig.h's chart the own rotation
     * r = Exp(w) r^ gives R_j = R_k r R_k^T = Exp(R_k w) R^_j, and l maps to R_k l: both halves
     * of the velocity and of the covariance turn by R_k, C_rig = T C T^T with
     * T = diag(R_k, R_k) (first order: the term -R_j D_k's dependence on w is left out). */
    rp_real pr[6];
    if (rp_vo_mono_to_rig(vo->rig, vo->cfg.cam, e.p, pr) == RP_OK) {
        memcpy(e.p, pr, sizeof(pr));
        const rp_real *Rk = vo->rig->cam[vo->cfg.cam].R;
        rp_rot_apply(Rk, e.v, e.v);
        rp_rot_apply(Rk, e.v + 3, e.v + 3);
        for (int bi = 0; bi < 2; ++bi) {
            for (int bj = 0; bj < 2; ++bj) {
                rp_real Ct[9], T[9];
                for (int i = 0; i < 3; ++i) {
                    for (int j = 0; j < 3; ++j) {
                        Ct[i * 3 + j] = e.cov[(3 * bi + i) * 6 + 3 * bj + j];
                    }
                }
                rp_rot_mul(Rk, Ct, T);
                rp_rot_mul_a_bt(T, Rk, Ct);
                for (int i = 0; i < 3; ++i) {
                    for (int j = 0; j < 3; ++j) {
                        e.cov[(3 * bi + i) * 6 + 3 * bj + j] = Ct[i * 3 + j];
                    }
                }
            }
        }
    }
    *est = e;
}

static void remember(rp_vo_mono_t *vo, const rp_frameset_t *fs)
{
    const uint8_t cam = vo->cfg.cam;
    vo->n_prev = fs->n[cam];
    memcpy(vo->prev, fs->f[cam], (size_t)fs->n[cam] * sizeof(rp_feat_t));
    for (int i = 0; i < 6; ++i) {
        vo->prev_p[i] = vo->ekf.x[i];
    }
    vo->prev_utime = fs->utime;
}

static rp_status_t first_frame(rp_vo_mono_t *vo, const rp_frameset_t *fs, rp_estimate_t *est,
                               rp_estimate_t *own)
{
    static const rp_real zero[6] = {0};
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_clear(&vo->lm);
    const uint16_t added = add_features(vo, fs->f[vo->cfg.cam], fs->n[vo->cfg.cam], zero, NULL);
    /* ignored: cannot fail: the parameters were checked at init */
    (void)rp_vo_ekf_at_origin(&vo->ekf, &vo->cfg.ekf);
    remember(vo, fs);
    uint32_t flags = RP_EST_INITIALISING;
    if (added < vo->cfg.min_tracked) {
        flags |= RP_EST_DEGRADED;
    }
    if (added >= RP_VO_MIN_START) {
        vo->frame = 1;
    } /* else: stay at frame 0, the next frame set starts again */
    fill_estimates(vo, fs->utime, flags, est, own);
    est->frame = 0;
    if (own) {
        own->frame = 0;
    }
    return added >= RP_VO_MIN_START ? RP_OK : RP_E_TOO_FEW;
}

/* Step (2): Lowe's method on the orthographic structure starts the filter. */
static rp_status_t start_with_lowe(rp_vo_mono_t *vo, uint32_t n, rp_real dt)
{
    rp_lowe_params_t lp = rp_lowe_default_params();
    rp_real p[6] = {0}, cov[36];
    rp_status_t st = rp_lowe_solve(&vo->own, vo->obs, n, &lp, p, NULL, cov);
    if (st != RP_OK && st != RP_E_NO_CONVERGE) {
        return st;
    }
    st = rp_vo_ekf_from_pose(&vo->ekf, &vo->cfg.ekf, p, cov, vo->prev_p, dt);
    if (st != RP_OK) {
        return st;
    }
    for (uint32_t i = 0; i < n; ++i) {
        vo->used[i] = 1;
    }
    return RP_OK;
}

/* Step (3)'s re-find: RANSAC (P3P on the one camera) over the n observations, gate on
 * 2 sigma_px^2 / w (the landmark carries earlier pixels' noise), then the update redone on its
 * inliers from the prediction with the pose covariance widened by d d^T, d the gap from the
 * predicted pose to RANSAC's. RP_OK (vo->ekf, vo->used, *info replaced) when RANSAC found more
 * inliers than first_used and the redone update uses at least half of them; otherwise
 * RP_E_TOO_FEW, vo->ekf as given (RANSAC's outliers may be left at w = 0 in vo->obs). */
static rp_status_t refind(rp_vo_mono_t *vo, uint32_t n, uint32_t first_used, rp_ekf_info_t *info)
{
    const rp_status_t st = rp_vo_refind(&vo->rs, &vo->own, &vo->ekf_pred, vo->obs, n,
                                        first_used, vo->inl, &vo->ekf, vo->used, info);
    vo->n_refound += st == RP_OK;
    return st;
}

/* Step (3)'s update: 1-point RANSAC or the plain gated update, then (cfg.ransac) the re-find
 * when most observations were left out or the update failed with enough of them. */
static rp_status_t pose_update(rp_vo_mono_t *vo, uint32_t n, rp_ekf_info_t *info)
{
    vo->ekf_pred = vo->ekf;
    rp_status_t st;
    if (vo->cfg.one_point) {
        rp_ekf1pt_info_t oi;
        rp_ekf1pt_params_t op = rp_ekf1pt_default_params();
        op.plain_without_majority = 1; /* rp_vo_mono.h, step 3 */
        op.regroup = 0; /* young landmarks at an assumed depth: rp_ekf1pt.h, step 2b */
        st = rp_ekf1pt_update(&vo->op, &vo->ekf, &vo->own, vo->obs, n, &op, vo->used, &oi);
        *info = oi.ekf;
    } else {
        st = rp_ekf_update(&vo->ekf, &vo->own, vo->obs, n, vo->used, info);
    }
    const int most_out = st == RP_OK ? 2u * info->n_outside > n : n >= vo->cfg.ekf.min_features;
    if (!vo->cfg.ransac || !most_out) {
        return st;
    }
    const rp_ekf_info_t first_info = *info;
    memcpy(vo->first_used, vo->used, n);
    if (refind(vo, n, st == RP_OK ? first_info.n_used : 0u, info) == RP_OK) {
        return RP_OK;
    }
    memcpy(vo->used, vo->first_used, n);
    *info = first_info;
    return st;
}

rp_status_t rp_vo_mono_step(rp_vo_mono_t *vo, const rp_frameset_t *fs, rp_estimate_t *est,
                            rp_estimate_t *own)
{
    if (!vo || !est) {
        return RP_E_ARG;
    }
    memset(est, 0, sizeof(*est));
    if (!vo->rig) {
        return RP_E_ARG;
    }
    if (!fs || fs->n[vo->cfg.cam] > RP_MAX_FEATS_PER_CAM) {
        fill_estimates(vo, vo->prev_utime, RP_EST_LOST, est, own);
        return RP_E_ARG;
    }
    if (vo->frame == 0) {
        return first_frame(vo, fs, est, own);
    }
    rp_real dt;
    /* ignored: cannot fail: fs and dt given */
    (void)rp_vo_frame_dt(fs, vo->prev_utime, vo->cfg.default_dt_s, &dt);
    uint32_t flags = 0;

    /* Predict first (from frame 2 on) so that observation weights use the predicted pose. */
    rp_status_t st = RP_OK;
    if (vo->frame >= 2) {
        st = rp_ekf_predict(&vo->ekf, dt);
    }
    uint32_t n = gather_obs(vo, fs, vo->ekf.x);
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_mark_ids(&vo->lm, vo->obs_id, NULL, n);
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_drop_unmarked(&vo->lm, RP_IDMAP_ALL_GROUPS, NULL);

    /* Step (5): under the threshold, backtrack one frame and add the previous frame's features
     * (still tracked now) at the previous pose. */
    if (vo->lm.map.n < vo->cfg.min_tracked) {
        /* ignored: the count is not needed here */
        (void)add_features(vo, vo->prev, vo->n_prev, vo->prev_p, fs);
        flags |= RP_EST_REINIT;
        n = gather_obs(vo, fs, vo->ekf.x);
    }
    if (vo->lm.map.n < vo->cfg.min_tracked) {
        flags |= RP_EST_DEGRADED;
    }

    uint16_t n_gated = 0;
    if (st == RP_OK) {
        if (vo->frame == 1) {
            st = start_with_lowe(vo, n, dt);
        } else {
            rp_ekf_info_t info;
            st = pose_update(vo, n, &info);
            n_gated = info.n_gated;
            if (info.cov_reset) {
                flags |= RP_EST_COV_RESET;
            }
        }
    }

    uint16_t n_used = 0;
    if (st == RP_OK) {
        flags |= RP_EST_TRACKING;
        /* step 4: each used observation updates its landmark at the new pose */
        /* ignored: a point its gate refuses stays as it was (the gate, not a fault) */
        (void)rp_lmtab_refine(&vo->lm, &vo->own, vo->ekf.x, vo->ekf.x + 6, vo->ekf.toff, vo->obs,
                              vo->obs_id, vo->used, n, vo->cfg.ekf.sigma_px,
                              vo->cfg.ekf.gate_chi2);
        for (uint32_t i = 0; i < n; ++i) {
            if (vo->used[i]) {
                n_used++;
            }
        }
        /* ignored: only NULL arguments fail */
        (void)rp_lmtab_mark_ids(&vo->lm, vo->obs_id, vo->used, n);
        if (n_gated > 0) {
            flags |= RP_EST_GATED;
        }
        /* a landmark whose observation was gated is an outlier */
        /* ignored: only NULL arguments fail */
        (void)rp_lmtab_drop_unmarked(&vo->lm, n_gated > 0 ? RP_IDMAP_ALL_GROUPS : 0u, NULL);
    } else {
        flags |= RP_EST_LOST;
    }

    remember(vo, fs);
    fill_estimates(vo, fs->utime, flags, est, own);
    est->n_used[vo->cfg.cam] = n_used;
    est->n_gated = n_gated;
    if (own) {
        own->n_used[0] = n_used;
        own->n_gated = n_gated;
    }
    vo->frame++;
    return rp_vo_step_status(st);
}
