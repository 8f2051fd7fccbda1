/*
 * rp_vo_mono.c - one camera on its own (see rp_vo_mono.h; the step numbers are the paper's).
 */
#include <string.h>

#include "priv/rp_math.h"
#include "rigpose/rp_lowe.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_vo_mono.h"

#define START_SIGMA_V RP_C(1.0)
#define START_SIGMA_W RP_C(1.0)

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
    return c;
}

/* ---- landmark records, found by id through vo->map ------------------------------------- */

static rp_mono_landmark_t *lm_find(rp_vo_mono_t *vo, uint32_t id)
{
    uint16_t slot;
    return rp_idmap_find(&vo->map, id, &slot) == RP_OK ? &vo->lm[slot] : NULL;
}

static rp_status_t lm_insert(rp_vo_mono_t *vo, uint32_t id, const rp_point3_t *pt)
{
    uint16_t slot;
    rp_status_t st = rp_idmap_insert(&vo->map, id, 0, &slot);
    if (st == RP_OK) {
        vo->lm[slot].pt = *pt;
    }
    return st;
}

static void lm_mark_seen(rp_vo_mono_t *vo, const rp_mono_landmark_t *l)
{
    (void)rp_idmap_mark(&vo->map, (uint16_t)(l - vo->lm));
}

rp_status_t rp_vo_mono_init(rp_vo_mono_t *vo, const rp_rig_t *rig, const rp_vo_mono_cfg_t *cfg)
{
    if (!vo || !rig || !cfg) {
        return RP_E_ARG;
    }
    rp_status_t st = rp_rig_check(rig);
    if (st != RP_OK) {
        return st;
    }
    if (cfg->cam >= rig->n_cams || cfg->min_tracked < 6 || !(cfg->init_depth_m > RP_C(0.0)) ||
        !(cfg->init_depth_sigma_m > RP_C(0.0)) || !(cfg->default_dt_s > RP_C(0.0)) ||
        !rp_finite(cfg->init_depth_m) || !rp_finite(cfg->init_depth_sigma_m)) {
        return RP_E_ARG;
    }
    memset(vo, 0, sizeof(*vo));
    vo->rig = rig;
    vo->cfg = *cfg;
    vo->own.n_cams = 1;
    memset(vo->own.cam[0].R, 0, sizeof(vo->own.cam[0].R));
    vo->own.cam[0].R[0] = vo->own.cam[0].R[4] = vo->own.cam[0].R[8] = RP_C(1.0);
    vo->own.cam[0].cam = rig->cam[cfg->cam].cam;
    rp_real x0[RP_EKF_N] = {0}, P0[RP_EKF_N];
    for (int i = 0; i < RP_EKF_N; ++i) {
        P0[i] = RP_C(1.0);
    }
    st = rp_ekf_init(&vo->ekf, &cfg->ekf, x0, P0);
    if (st != RP_OK) {
        return st;
    }
    (void)rp_idmap_clear(&vo->map);
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
        if (f[i].id == RP_VO_MONO_EMPTY_ID || !rp_all_finite(f[i].uv, 2) ||
            lm_find(vo, f[i].id) != NULL ||
            (only_in && !has_id(only_in, vo->cfg.cam, f[i].id))) {
            continue;
        }
        rp_point3_t pt;
        if (ortho_point(vo, &pl, f[i].uv, &pt) != RP_OK) {
            continue;
        }
        if (lm_insert(vo, f[i].id, &pt) != RP_OK) {
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
    return rp_finite(w) && w > RP_C(1e-6) ? w : RP_C(1e-6);
}

static uint32_t gather_obs(rp_vo_mono_t *vo, const rp_frameset_t *fs, const rp_real p_pred[6])
{
    rp_pose_lin_t pl;
    const int have_pl = rp_pose_lin_set(&pl, p_pred) == RP_OK;
    const uint8_t cam = vo->cfg.cam;
    uint32_t n = 0;
    for (uint16_t f = 0; f < fs->n[cam]; ++f) {
        const rp_feat_t *ft = &fs->f[cam][f];
        if (!rp_all_finite(ft->uv, 2)) {
            continue;
        }
        rp_mono_landmark_t *l = lm_find(vo, ft->id);
        if (!l) {
            continue;
        }
        rp_obs_t *o = &vo->obs[n];
        o->uv[0] = ft->uv[0];
        o->uv[1] = ft->uv[1];
        memcpy(o->M, l->pt.M, sizeof(o->M));
        o->w = have_pl ? obs_weight(vo, &pl, &l->pt) : RP_C(1.0);
        o->cam = 0;
        vo->obs_id[n] = ft->id;
        n++;
    }
    return n;
}

static void fill_estimates(const rp_vo_mono_t *vo, int64_t utime, uint32_t flags,
                           rp_estimate_t *est, rp_estimate_t *own)
{
    rp_estimate_t e;
    memset(&e, 0, sizeof(e));
    e.utime = utime;
    e.frame = vo->frame;
    for (int i = 0; i < 6; ++i) {
        e.p[i] = vo->ekf.x[i];
        e.v[i] = vo->ekf.x[6 + i];
        for (int j = 0; j < 6; ++j) {
            e.cov[i * 6 + j] = vo->ekf.P[i * RP_EKF_N + j];
        }
    }
    e.flags = flags | RP_EST_SCALE_WEAK; /* a single camera's scale is the assumed depth's */
    e.n_landmarks = vo->map.n;
    if (own) {
        *own = e;
    }
    /* Rig pose through the extrinsics; the translation covariance block is rotated by R_k
     * (first order, the angle block kept as is). */
    rp_real pr[6];
    if (rp_vo_mono_to_rig(vo->rig, vo->cfg.cam, e.p, pr) == RP_OK) {
        memcpy(e.p, pr, sizeof(pr));
        const rp_real *Rk = vo->rig->cam[vo->cfg.cam].R;
        rp_real v[3];
        rp_rot_apply(Rk, e.v, v);
        memcpy(e.v, v, sizeof(v));
        rp_real Ct[9], T[9];
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                Ct[i * 3 + j] = e.cov[i * 6 + j];
            }
        }
        rp_rot_mul(Rk, Ct, T);
        rp_rot_mul_a_bt(T, Rk, Ct);
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                e.cov[i * 6 + j] = Ct[i * 3 + j];
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
    (void)rp_idmap_clear(&vo->map);
    const uint16_t added = add_features(vo, fs->f[vo->cfg.cam], fs->n[vo->cfg.cam], zero, NULL);
    rp_real x0[RP_EKF_N] = {0}, P0[RP_EKF_N];
    for (int i = 0; i < 6; ++i) {
        P0[i] = RP_C(1e-12);
        P0[6 + i] = i < 3 ? START_SIGMA_V * START_SIGMA_V : START_SIGMA_W * START_SIGMA_W;
    }
    (void)rp_ekf_init(&vo->ekf, &vo->cfg.ekf, x0, P0);
    remember(vo, fs);
    uint32_t flags = RP_EST_INITIALISING;
    if (added < vo->cfg.min_tracked) {
        flags |= RP_EST_DEGRADED;
    }
    if (added >= 6) {
        vo->frame = 1;
    } /* else: stay at frame 0, the next frame set starts again */
    fill_estimates(vo, fs->utime, flags, est, own);
    est->frame = 0;
    if (own) {
        own->frame = 0;
    }
    return added >= 6 ? RP_OK : RP_E_TOO_FEW;
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
    const rp_real s2 = vo->cfg.ekf.sigma_px * vo->cfg.ekf.sigma_px;
    rp_real x[RP_EKF_N], P0diag[RP_EKF_N];
    for (int i = 0; i < 6; ++i) {
        x[i] = p[i];
        x[6 + i] = (p[i] - vo->prev_p[i]) / dt;
        P0diag[i] = cov[i * 6 + i] * s2;
        P0diag[6 + i] = P0diag[i] / (dt * dt) +
                        (i < 3 ? START_SIGMA_V * START_SIGMA_V : START_SIGMA_W * START_SIGMA_W);
    }
    st = rp_ekf_init(&vo->ekf, &vo->cfg.ekf, x, P0diag);
    if (st != RP_OK) {
        return st;
    }
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            vo->ekf.P[i * RP_EKF_N + j] = cov[i * 6 + j] * s2;
        }
    }
    for (uint32_t i = 0; i < n; ++i) {
        vo->used[i] = 1;
    }
    return RP_OK;
}

static void refine_structure(rp_vo_mono_t *vo, uint32_t n)
{
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, vo->ekf.x) != RP_OK) {
        return;
    }
    for (uint32_t i = 0; i < n; ++i) {
        if (!vo->used[i]) {
            continue;
        }
        rp_mono_landmark_t *l = lm_find(vo, vo->obs_id[i]);
        if (l) {
            (void)rp_struct_update(&l->pt, &vo->own, 0, &pl, vo->obs[i].uv, vo->cfg.ekf.sigma_px,
                                   vo->cfg.ekf.gate_chi2);
        }
    }
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
    rp_real dt = vo->cfg.default_dt_s;
    if (fs->utime > vo->prev_utime) {
        dt = (rp_real)(fs->utime - vo->prev_utime) * RP_C(1e-6);
    }
    uint32_t flags = 0;

    /* Predict first (from frame 2 on) so that observation weights use the predicted pose. */
    rp_status_t st = RP_OK;
    if (vo->frame >= 2) {
        st = rp_ekf_predict(&vo->ekf, dt);
    }
    uint32_t n = gather_obs(vo, fs, vo->ekf.x);
    for (uint32_t i = 0; i < n; ++i) {
        lm_mark_seen(vo, lm_find(vo, vo->obs_id[i]));
    }
    (void)rp_idmap_drop_unmarked(&vo->map, RP_IDMAP_ALL_GROUPS, NULL);

    /* Step (5): under the threshold, backtrack one frame and add the previous frame's features
     * (still tracked now) at the previous pose. */
    if (vo->map.n < vo->cfg.min_tracked) {
        (void)add_features(vo, vo->prev, vo->n_prev, vo->prev_p, fs);
        flags |= RP_EST_REINIT;
        n = gather_obs(vo, fs, vo->ekf.x);
    }
    if (vo->map.n < vo->cfg.min_tracked) {
        flags |= RP_EST_DEGRADED;
    }

    uint16_t n_gated = 0;
    if (st == RP_OK) {
        if (vo->frame == 1) {
            st = start_with_lowe(vo, n, dt);
        } else {
            rp_ekf_info_t info;
            st = rp_ekf_update(&vo->ekf, &vo->own, vo->obs, n, vo->used, &info);
            n_gated = info.n_gated;
            if (info.cov_reset) {
                flags |= RP_EST_COV_RESET;
            }
        }
    }

    uint16_t n_used = 0;
    if (st == RP_OK) {
        flags |= RP_EST_TRACKING;
        refine_structure(vo, n);
        for (uint32_t i = 0; i < n; ++i) {
            if (vo->used[i]) {
                n_used++;
                rp_mono_landmark_t *l = lm_find(vo, vo->obs_id[i]);
                if (l) {
                    lm_mark_seen(vo, l);
                }
            }
        }
        if (n_gated > 0) {
            flags |= RP_EST_GATED;
            /* a landmark whose observation was gated is an outlier */
            (void)rp_idmap_drop_unmarked(&vo->map, RP_IDMAP_ALL_GROUPS, NULL);
        } else {
            (void)rp_idmap_clear_marks(&vo->map);
        }
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
    return st == RP_OK ? RP_OK : (st == RP_E_DIVERGED ? RP_E_DIVERGED : RP_E_TOO_FEW);
}
