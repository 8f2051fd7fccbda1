/*
 * rp_vo_gc.c - the generalised camera (see rp_vo_gc.h for the algorithm).
 */
#include <string.h>

#include "priv/rp_math.h"
#include "priv/rp_sym3.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_vo_gc.h"

/* Prior standard deviations of the velocity when the filter starts (m/s, rad/s). */
#define START_SIGMA_V RP_C(1.0)
#define START_SIGMA_W RP_C(1.0)

rp_vo_gc_cfg_t rp_vo_gc_default_cfg(void)
{
    rp_vo_gc_cfg_t c;
    memset(&c, 0, sizeof(c));
    c.ekf = rp_ekf_default_params();
    c.min_tracked = 50;
    c.init_depth_m = RP_C(1.0);
    c.init_depth_sigma_m = RP_C(0.3);
    c.mature_frac = RP_C(0.02);
    c.min_mature = 50;
    c.default_dt_s = RP_C(1.0) / RP_C(30.0);
    c.max_eff_obs = RP_C(0.0);
    c.scale_sigma = RP_C(0.02);
    c.trans_drift_sigma = RP_C(6e-5);
    c.rot_drift_sigma = RP_C(1e-4);
    c.mscale_sigma = RP_C(0.3);
    c.mscale_q = RP_C(0.0);
    c.ba_stride = 4;
    c.ba_kf = 6;
    c.ba_every = 2;
    c.ba_per_cam = 80;
    c.ba_var_scale = RP_C(3.0);
    c.ba = rp_gcba_default_cfg();
    c.ba.iterations = 2;
    return c;
}

/* ---- landmark records, found by id through vo->map ------------------------------------- */

static rp_gc_landmark_t *lm_find(rp_vo_gc_t *vo, uint32_t id)
{
    uint16_t slot;
    return rp_idmap_find(&vo->map, id, &slot) == RP_OK ? &vo->lm[slot] : NULL;
}

static rp_status_t lm_insert(rp_vo_gc_t *vo, uint32_t id, uint8_t cam, const rp_point3_t *pt)
{
    uint16_t slot;
    rp_status_t st = rp_idmap_insert(&vo->map, id, cam, &slot);
    if (st == RP_OK) {
        rp_gc_landmark_t *l = &vo->lm[slot];
        memset(l, 0, sizeof(*l));
        l->cam = cam;
        l->pt = *pt;
    }
    return st;
}

/* Drop every landmark not seen this frame whose camera delivered an image (its track was
 * lost); landmarks of cameras without an image are kept. Clears the marks. */
static void lm_drop_lost(rp_vo_gc_t *vo, const uint8_t had_image[RP_MAX_CAMS])
{
    uint32_t mask = 0;
    for (uint32_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        mask |= had_image[cam] ? (1u << cam) : 0u;
    }
    (void)rp_idmap_drop_unmarked(&vo->map, mask, NULL);
}

/* ---- set-up ------------------------------------------------------------------------------ */

/* The map's unit: mu map units per metre; the rig in map units has offsets D_k * mu. */
static void set_mu(rp_vo_gc_t *vo, rp_real mu)
{
    vo->rig_m = *vo->rig;
    vo->mu = mu;
    for (uint8_t k = 0; k < vo->rig_m.n_cams; ++k) {
        for (int a = 0; a < 3; ++a) {
            vo->rig_m.cam[k].D[a] = mu * vo->rig->cam[k].D[a];
        }
    }
}

static void start_ekf(rp_vo_gc_t *vo)
{
    rp_real x0[RP_EKF_N] = {0}, P0[RP_EKF_N];
    for (int i = 0; i < 6; ++i) {
        P0[i] = RP_C(1e-12); /* the pose at frame 0 is the origin by definition */
        P0[6 + i] = i < 3 ? START_SIGMA_V * START_SIGMA_V : START_SIGMA_W * START_SIGMA_W;
    }
    (void)rp_ekf_init(&vo->ekf, &vo->cfg.ekf, x0, P0);
}

rp_status_t rp_vo_gc_init(rp_vo_gc_t *vo, const rp_rig_t *rig, const rp_vo_gc_cfg_t *cfg)
{
    if (!vo || !rig || !cfg) {
        return RP_E_ARG;
    }
    rp_status_t st = rp_rig_check(rig);
    if (st != RP_OK) {
        return st;
    }
    if (!rp_finite(cfg->max_eff_obs) || !rp_finite(cfg->scale_sigma) ||
        cfg->scale_sigma < RP_C(0.0) || !rp_finite(cfg->trans_drift_sigma) ||
        cfg->trans_drift_sigma < RP_C(0.0) || !rp_finite(cfg->rot_drift_sigma) ||
        cfg->rot_drift_sigma < RP_C(0.0) || !rp_finite(cfg->mscale_sigma) ||
        cfg->mscale_sigma < RP_C(0.0) || !rp_finite(cfg->mscale_q) ||
        cfg->mscale_q < RP_C(0.0)) {
        return RP_E_ARG;
    }
    if (cfg->mscale_sigma > RP_C(0.0) &&
        (cfg->ba_stride < 1 || cfg->ba_kf < 3 || cfg->ba_kf > RP_GCBA_MAX_KF ||
         cfg->ba_every < 1 || cfg->ba_per_cam < 8 ||
         !(cfg->ba_var_scale >= RP_C(1.0)) || !rp_finite(cfg->ba_var_scale) ||
         cfg->ba.iterations < 1 || cfg->ba.min_obs < 2 || !(cfg->ba.sigma_px > RP_C(0.0)) ||
         !(cfg->ba.huber_px > RP_C(0.0)) || !(cfg->ba.min_angle >= RP_C(0.0)))) {
        return RP_E_ARG;
    }
    if (cfg->n_cams < 1 || cfg->n_cams > RP_MAX_CAMS || cfg->min_tracked < 6 ||
        !(cfg->init_depth_m > RP_C(0.0)) || !rp_finite(cfg->init_depth_m) ||
        !(cfg->init_depth_sigma_m > RP_C(0.0)) || !rp_finite(cfg->init_depth_sigma_m) ||
        !(cfg->mature_frac >= RP_C(0.0)) || !rp_finite(cfg->mature_frac) ||
        !(cfg->default_dt_s > RP_C(0.0)) || !rp_finite(cfg->default_dt_s)) {
        return RP_E_ARG;
    }
    uint8_t in_use[RP_MAX_CAMS] = {0};
    for (uint8_t k = 0; k < cfg->n_cams; ++k) {
        uint8_t c = cfg->cams[k];
        if (c >= rig->n_cams || in_use[c]) {
            return RP_E_ARG;
        }
        in_use[c] = 1;
    }
    rp_real x0[RP_EKF_N] = {0}, P0[RP_EKF_N];
    for (int i = 0; i < RP_EKF_N; ++i) {
        P0[i] = RP_C(1.0);
    }
    rp_ekf_t probe;
    st = rp_ekf_init(&probe, &cfg->ekf, x0, P0); /* checks the EKF parameters */
    if (st != RP_OK) {
        return st;
    }
    memset(vo, 0, sizeof(*vo));
    vo->rig = rig;
    vo->cfg = *cfg;
    set_mu(vo, RP_C(1.0));
    vo->ekf = probe;
    (void)rp_idmap_clear(&vo->map);
    return RP_OK;
}

/* ---- orthographic initialisation of a feature -------------------------------------------- */

/* Landmark for pixel uv of camera cam at pose pl: on the plane z = init_depth_m of the camera,
 * covariance sigma_z^2 d d^T along the ray d = (xn, 1) plus an isotropic across-ray part from
 * the pixel noise and the pose uncertainty (Ppp, 6x6 row-major, may be NULL). */
static rp_status_t init_feature(const rp_vo_gc_t *vo, uint8_t cam, const rp_real uv[2],
                                const rp_pose_lin_t *pl, const rp_real *Ppp, rp_point3_t *pt)
{
    const rp_rig_cam_t *rc = &vo->rig_m.cam[cam];
    rp_real xn[2];
    rp_status_t st = rp_cam_unproject(&rc->cam, uv, xn);
    if (st != RP_OK) {
        return st;
    }
    const rp_real d[3] = {xn[0], xn[1], RP_C(1.0)};
    const rp_real dn = rp_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    /* on the plane z = depth, or on the sphere of radius depth around the camera */
    const rp_real depth = vo->cfg.init_depth_m * vo->mu; /* in map units */
    const rp_real z = vo->cfg.init_on_sphere ? depth / dn : depth;
    const rp_real P[3] = {z * d[0], z * d[1], z};
    const rp_real range = z * dn;
    const rp_real u[3] = {d[0] / dn, d[1] / dn, d[2] / dn};
    const rp_real f = rc->cam.fx > rc->cam.fy ? rc->cam.fx : rc->cam.fy;
    const rp_real ang = vo->cfg.ekf.sigma_px / f; /* rad per pixel-noise sigma */
    rp_real perp2 = range * range * ang * ang;
    if (Ppp) {
        perp2 += (Ppp[0] + Ppp[7] + Ppp[14]) / RP_C(3.0) +
                 range * range * (Ppp[21] + Ppp[28] + Ppp[35]) / RP_C(3.0);
    }
    /* variance of z: the configured sigma is on z (plane) or on the range (sphere) */
    const rp_real sd = vo->cfg.init_depth_sigma_m * vo->mu;
    const rp_real sz = vo->cfg.init_on_sphere ? sd / dn : sd;
    const rp_real sz2 = sz * sz;
    rp_real Cc[9];
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            Cc[a * 3 + b] = sz2 * d[a] * d[b] + perp2 * ((a == b ? RP_C(1.0) : RP_C(0.0)) -
                                                         u[a] * u[b]);
        }
    }
    /* camera -> world: Rw = R_j R_k; C_w = Rw Cc Rw^T */
    rp_real Rw[9], T[9], Cw[9];
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            rp_real acc = RP_C(0.0);
            for (int k = 0; k < 3; ++k) {
                acc += pl->R[a * 3 + k] * rc->R[k * 3 + b];
            }
            Rw[a * 3 + b] = acc;
        }
    }
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            rp_real acc = RP_C(0.0);
            for (int k = 0; k < 3; ++k) {
                acc += Rw[a * 3 + k] * Cc[k * 3 + b];
            }
            T[a * 3 + b] = acc;
        }
    }
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            rp_real acc = RP_C(0.0);
            for (int k = 0; k < 3; ++k) {
                acc += T[a * 3 + k] * Rw[b * 3 + k];
            }
            Cw[a * 3 + b] = acc;
        }
    }
    st = rp_rig_world_point(&vo->rig_m, cam, pl, P, pt->M);
    if (st != RP_OK) {
        return st;
    }
    rp_sym3_pack(Cw, pt->C);
    if (!rp_all_finite(pt->M, 3) || !rp_all_finite(pt->C, 6)) {
        return RP_E_NAN;
    }
    return RP_OK;
}

/* Add every finite feature of camera cam in fs that is not yet a landmark, at pose pl.
 * Returns how many were added. */
static uint16_t top_up_camera(rp_vo_gc_t *vo, const rp_frameset_t *fs, uint8_t cam,
                              const rp_pose_lin_t *pl, const rp_real *Ppp)
{
    uint16_t added = 0;
    for (uint16_t f = 0; f < fs->n[cam]; ++f) {
        const rp_feat_t *ft = &fs->f[cam][f];
        if (ft->id == RP_VO_GC_EMPTY_ID || !rp_all_finite(ft->uv, 2) || lm_find(vo, ft->id)) {
            continue;
        }
        rp_point3_t pt;
        if (init_feature(vo, cam, ft->uv, pl, Ppp, &pt) != RP_OK) {
            continue;
        }
        if (lm_insert(vo, ft->id, cam, &pt) != RP_OK) {
            break; /* table full (or id in two cameras): keep what we have */
        }
        added++;
    }
    return added;
}

/* ---- small helpers ----------------------------------------------------------------------- */

/* Largest eigenvalue of the symmetric 2x2 [a b; b d]. */
static rp_real eig2_max(rp_real a, rp_real b, rp_real d)
{
    const rp_real h = RP_C(0.5) * (a - d);
    return RP_C(0.5) * (a + d) + rp_sqrt(h * h + b * b);
}

/* Largest eigenvalue of J C J^T with J 2 x n, C n x n symmetric (row-major; packed3 = 1: C is
 * the packed 3x3 of rp_point3_t). */
static rp_real proj_var_max(const rp_real *J, int n, const rp_real *C, int packed3)
{
    rp_real Cf[36];
    if (packed3) {
        rp_sym3_unpack(C, Cf);
        C = Cf;
    }
    rp_real S[4];
    for (int r = 0; r < 2; ++r) {
        for (int q = r; q < 2; ++q) {
            rp_real acc = RP_C(0.0);
            for (int a = 0; a < n; ++a) {
                rp_real t = RP_C(0.0);
                for (int b = 0; b < n; ++b) {
                    t += C[a * n + b] * J[q * n + b];
                }
                acc += J[r * n + a] * t;
            }
            S[r * 2 + q] = acc;
        }
    }
    return eig2_max(S[0], S[1], S[3]);
}

/* Standard deviation of landmark l along its ray from camera cam at pose pl, and the range. */
static void ray_sigma(const rp_vo_gc_t *vo, const rp_gc_landmark_t *l, const rp_pose_lin_t *pl,
                      rp_real *sigma, rp_real *range)
{
    const rp_rig_cam_t *rc = &vo->rig_m.cam[l->cam];
    rp_real c[3], u[3];
    for (int a = 0; a < 3; ++a) {
        c[a] = pl->p[a] + pl->R[a * 3 + 0] * rc->D[0] + pl->R[a * 3 + 1] * rc->D[1] +
               pl->R[a * 3 + 2] * rc->D[2];
        u[a] = l->pt.M[a] - c[a];
    }
    const rp_real r = rp_sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    *range = r;
    if (!(r > RP_C(0.0))) {
        *sigma = RP_C(1e30);
        return;
    }
    for (int a = 0; a < 3; ++a) {
        u[a] /= r;
    }
    const rp_real *k = l->pt.C;
    const rp_real v = u[0] * (k[0] * u[0] + k[1] * u[1] + k[2] * u[2]) +
                      u[1] * (k[1] * u[0] + k[3] * u[1] + k[4] * u[2]) +
                      u[2] * (k[2] * u[0] + k[4] * u[1] + k[5] * u[2]);
    *sigma = v > RP_C(0.0) ? rp_sqrt(v) : RP_C(0.0);
}

static int cam_in_layout(const rp_vo_gc_t *vo, uint8_t cam)
{
    for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
        if (vo->cfg.cams[k] == cam) {
            return 1;
        }
    }
    return 0;
}

/* Gather the observations of held landmarks in fs into vo->obs; marks them seen. */
static uint32_t gather_obs(rp_vo_gc_t *vo, const rp_frameset_t *fs)
{
    uint32_t n = 0;
    for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
        const uint8_t cam = vo->cfg.cams[k];
        for (uint16_t f = 0; f < fs->n[cam]; ++f) {
            const rp_feat_t *ft = &fs->f[cam][f];
            if (!rp_all_finite(ft->uv, 2)) {
                continue;
            }
            rp_gc_landmark_t *l = lm_find(vo, ft->id);
            if (!l || l->cam != cam) {
                continue;
            }
            (void)rp_idmap_mark(&vo->map, (uint16_t)(l - vo->lm));
            rp_obs_t *o = &vo->obs[n];
            o->uv[0] = ft->uv[0];
            o->uv[1] = ft->uv[1];
            memcpy(o->M, l->pt.M, sizeof(o->M));
            o->w = RP_C(1.0);
            o->cam = cam;
            vo->obs_id[n] = ft->id;
            n++;
        }
    }
    return n;
}

static void fill_estimate(const rp_vo_gc_t *vo, const rp_frameset_t *fs, uint32_t flags,
                          rp_estimate_t *est)
{
    est->utime = fs ? fs->utime : vo->prev_utime;
    est->frame = vo->frame;
    /* map units -> metres: translations and their velocities divided by mu */
    const rp_real im = RP_C(1.0) / vo->mu;
    for (int i = 0; i < 6; ++i) {
        const rp_real si = i < 3 ? im : RP_C(1.0);
        est->p[i] = si * vo->ekf.x[i];
        est->v[i] = si * vo->ekf.x[6 + i];
        for (int j = 0; j < 6; ++j) {
            const rp_real sj = j < 3 ? im : RP_C(1.0);
            est->cov[i * 6 + j] = si * sj * vo->ekf.P[i * RP_EKF_N + j];
        }
    }
    /* the map's scale uncertainty, common to every landmark (and the estimated unit's) */
    const rp_real s2 = vo->cfg.scale_sigma * vo->cfg.scale_sigma + vo->mu_var * im * im;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            est->cov[i * 6 + j] += s2 * est->p[i] * est->p[j];
        }
    }
    const rp_real r2 = vo->cfg.rot_drift_sigma * vo->cfg.rot_drift_sigma * (rp_real)vo->frame;
    const rp_real t2 =
        vo->cfg.trans_drift_sigma * vo->cfg.trans_drift_sigma * (rp_real)vo->frame;
    for (int i = 0; i < 3; ++i) {
        est->cov[i * 6 + i] += t2;
        est->cov[(3 + i) * 6 + 3 + i] += r2;
    }
    est->flags = flags;
    est->n_landmarks = vo->map.n;
}

static rp_status_t validate_frameset(const rp_vo_gc_t *vo, const rp_frameset_t *fs)
{
    for (uint8_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        if (fs->n[cam] > RP_MAX_FEATS_PER_CAM) {
            return RP_E_ARG;
        }
        if (cam >= vo->rig->n_cams && fs->n[cam] != 0) {
            return RP_E_ARG;
        }
    }
    return RP_OK;
}

static void pose_cov(const rp_vo_gc_t *vo, rp_real Ppp[36])
{
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            Ppp[i * 6 + j] = vo->ekf.P[i * RP_EKF_N + j];
        }
    }
}

/* ---- the step ---------------------------------------------------------------------------- */

static void metric_scale(rp_vo_gc_t *vo, const rp_frameset_t *fs);

static rp_status_t first_frame(rp_vo_gc_t *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    static const rp_real zero[6] = {0};
    rp_pose_lin_t pl;
    (void)rp_pose_lin_set(&pl, zero);
    (void)rp_idmap_clear(&vo->map);
    start_ekf(vo);
    set_mu(vo, RP_C(1.0));
    vo->mu_var = vo->cfg.mscale_sigma * vo->cfg.mscale_sigma;
    (void)rp_gcba_reset(&vo->ba, vo->cfg.mscale_sigma > RP_C(0.0) ? vo->cfg.ba_kf : 3);
    vo->kf_since = 0;
    vo->n_ba = 0;
    vo->n_ba_rejected = 0;
    vo->ba_refused_run = 0;
    memset(&vo->ba_last, 0, sizeof(vo->ba_last));
    uint32_t flags = RP_EST_INITIALISING;
    for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
        const uint8_t cam = vo->cfg.cams[k];
        (void)top_up_camera(vo, fs, cam, &pl, NULL);
        if (vo->map.n_group[cam] < vo->cfg.min_tracked) {
            flags |= RP_EST_DEGRADED;
        }
    }
    metric_scale(vo, fs);
    vo->frame = 1;
    vo->prev_utime = fs->utime;
    fill_estimate(vo, fs, flags | RP_EST_SCALE_WEAK, est);
    est->frame = 0;
    return vo->map.n >= 6 ? RP_OK : RP_E_TOO_FEW;
}

/* Weights and maturity of the gathered observations at the predicted pose; fills vo->pobs
 * with the ones offered to the pose update. Returns their number; *n_mature the mature ones. */
static uint32_t select_for_pose(rp_vo_gc_t *vo, uint32_t n, uint32_t *n_mature)
{
    rp_pose_lin_t pl;
    *n_mature = 0;
    if (rp_pose_lin_set(&pl, vo->ekf.x) != RP_OK) {
        return 0;
    }
    const rp_real s2 = vo->cfg.ekf.sigma_px * vo->cfg.ekf.sigma_px;
    for (uint32_t i = 0; i < n; ++i) {
        rp_gc_landmark_t *l = lm_find(vo, vo->obs_id[i]);
        rp_obs_t *o = &vo->obs[i];
        rp_real uv[2], JM[6];
        vo->in_pose[i] = 0;
        if (!l || rp_rig_project(&vo->rig_m, o->cam, &pl, o->M, uv, NULL, JM) != RP_OK) {
            o->w = RP_C(0.0);
            continue;
        }
        const rp_real lam = proj_var_max(JM, 3, l->pt.C, 1);
        o->w = s2 / (s2 + (lam > RP_C(0.0) ? lam : RP_C(0.0)));
        if (!l->mature) {
            rp_real sig, range;
            ray_sigma(vo, l, &pl, &sig, &range);
            if (sig < vo->cfg.mature_frac * range) {
                l->mature = 1;
            }
        }
        if (l->mature) {
            (*n_mature)++;
        }
    }
    const int all = *n_mature < vo->cfg.min_mature;
    uint32_t m = 0;
    rp_real wsum = RP_C(0.0);
    for (uint32_t i = 0; i < n; ++i) {
        const rp_gc_landmark_t *l = lm_find(vo, vo->obs_id[i]);
        if (!l || !(vo->obs[i].w > RP_C(0.0)) || (!all && !l->mature)) {
            continue;
        }
        vo->in_pose[i] = 1;
        vo->pobs[m++] = vo->obs[i];
        wsum += vo->obs[i].w;
    }
    if (vo->cfg.max_eff_obs > RP_C(0.0) && wsum > vo->cfg.max_eff_obs) {
        const rp_real k = vo->cfg.max_eff_obs / wsum;
        for (uint32_t i = 0; i < m; ++i) {
            vo->pobs[i].w *= k;
        }
    }
    return m;
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
            if (vo->map.slot_id[slot] == RP_IDMAP_EMPTY) {
                continue;
            }
            rp_gc_landmark_t *l = &vo->lm[slot];
            const rp_real *D = vo->rig->cam[l->cam].D;
            for (int a = 0; a < 3; ++a) {
                l->pt.M[a] += dmu * (pl.R[a * 3 + 0] * D[0] + pl.R[a * 3 + 1] * D[1] +
                                     pl.R[a * 3 + 2] * D[2]);
            }
        }
    }
    set_mu(vo, mu);
}

/* After an adjustment: the window's poses in map units (the oldest keyframe stays where it was,
 * the others follow the solution's motion from it, converted at the map unit the window itself
 * implies: the map keeps its own unit, the window only gives its shape) go back into the ring;
 * the correction T_c that takes the newest keyframe from the filter's pose to the solved one is
 * applied to every landmark and to the filter's pose now (the adjustment was spread over the
 * frames since that keyframe), so that the map keeps its place relative to the rig; then the
 * adjusted landmarks take the solution's positions. */
static void correct_pose(rp_vo_gc_t *vo)
{
    const uint8_t nk = vo->ba.n_kf;
    rp_real p0[6], s0[6], pk[6], sk[6], po[6];
    if (rp_gcba_kf_pose(&vo->ba, 0, p0) != RP_OK || rp_gcba_solved_pose(&vo->ba, 0, s0) != RP_OK ||
        rp_gcba_kf_pose(&vo->ba, (uint8_t)(nk - 1), po) != RP_OK) {
        return;
    }
    for (uint8_t k = 1; k < nk; ++k) {
        if (rp_gcba_solved_pose(&vo->ba, k, sk) != RP_OK) {
            return;
        }
        for (int a = 0; a < 3; ++a) {
            pk[a] = p0[a] + vo->ba_last.mu * (sk[a] - s0[a]);
            pk[3 + a] = sk[3 + a];
        }
        (void)rp_gcba_set_pose(&vo->ba, k, pk);
    }
    /* the newest keyframe, as the filter had it (po) and as solved (pk): T_c = T_pk T_po^-1 */
    rp_real Ro[9], Rn[9], Rc[9], tc[3], t[3];
    rp_rot_from_angles(&po[3], Ro);
    rp_rot_from_angles(&pk[3], Rn);
    rp_rot_mul_a_bt(Rn, Ro, Rc);
    rp_rot_apply(Rc, po, t);
    for (int a = 0; a < 3; ++a) {
        tc[a] = pk[a] - t[a];
    }
    for (uint16_t slot = 0; slot < RP_IDMAP_MAX_SLOTS; ++slot) {
        if (vo->map.slot_id[slot] == RP_IDMAP_EMPTY) {
            continue;
        }
        rp_point3_t *pt = &vo->lm[slot].pt;
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
    for (uint16_t i = 0; i < vo->ba.n_lm_tab; ++i) {
        uint32_t id;
        uint8_t cam;
        rp_real X[3], C[6];
        rp_gc_landmark_t *l;
        if (rp_gcba_landmark(&vo->ba, i, &id, &cam, X, C) != RP_OK || !(l = lm_find(vo, id)) ||
            l->cam != cam) {
            continue;
        }
        const rp_real m2 = vo->ba_last.mu * vo->ba_last.mu;
        for (int a = 0; a < 3; ++a) {
            l->pt.M[a] = p0[a] + vo->ba_last.mu * (X[a] - s0[a]);
        }
        for (int a = 0; a < 6; ++a) {
            l->pt.C[a] = m2 * C[a];
        }
    }
    /* the filter's pose now (a frame or more after the keyframe) follows the same T_c */
    rp_real v[3], Rj[9], Rnew[9], ang[3];
    rp_rot_from_angles(&vo->ekf.x[3], Rj);
    rp_rot_mul(Rc, Rj, Rnew);
    if (rp_rot_to_angles(Rnew, ang) != RP_OK) {
        return;
    }
    rp_rot_apply(Rc, vo->ekf.x, t);
    rp_rot_apply(Rc, &vo->ekf.x[6], v);
    for (int a = 0; a < 3; ++a) {
        vo->ekf.x[a] = t[a] + tc[a];
        vo->ekf.x[3 + a] = ang[a];
        vo->ekf.x[6 + a] = v[a];
    }
}

/* Reorder h[0..n) (and idx with it) so that its want lowest values come first (quickselect). */
static void select_lowest(uint32_t *h, uint16_t *idx, uint16_t n, uint16_t want)
{
    int lo = 0, hi = (int)n - 1;
    const int k = (int)want - 1;
    while (lo < hi) {
        const uint32_t pivot = h[(lo + hi) / 2];
        int i = lo, j = hi;
        while (i <= j) {
            while (h[i] < pivot) {
                i++;
            }
            while (h[j] > pivot) {
                j--;
            }
            if (i <= j) {
                const uint32_t th = h[i];
                const uint16_t ti = idx[i];
                h[i] = h[j];
                idx[i] = idx[j];
                h[j] = th;
                idx[j] = ti;
                i++;
                j--;
            }
        }
        if (k <= j) {
            hi = j;
        } else if (k >= i) {
            lo = i;
        } else {
            break;
        }
    }
}

static void take_adjustment(rp_vo_gc_t *vo);

/* Step 6 (rp_vo_gc.h): keep this frame as a keyframe every ba_stride frames and, every ba_every
 * keyframes, fuse the map's unit that the window's adjustment implies. */
static void metric_scale(rp_vo_gc_t *vo, const rp_frameset_t *fs)
{
    if (!(vo->cfg.mscale_sigma > RP_C(0.0))) {
        return;
    }
    vo->mu_var += vo->cfg.mscale_q * vo->mu * vo->mu;
    /* an adjustment under way advances by one piece per frame (start, steps, result), so no
     * frame pays for all of it; a keyframe due before it is done finishes it first */
    if (vo->ba.state == RP_GCBA_STARTED || vo->ba.state == RP_GCBA_ITERATING) {
        if (rp_gcba_step(&vo->ba) != RP_OK) {
            vo->n_ba_rejected++;
        }
    }
    if (vo->ba.state == RP_GCBA_SOLVED) {
        take_adjustment(vo);
    }
    if (vo->frame % vo->cfg.ba_stride != 0) {
        return;
    }
    if (vo->ba.state != RP_GCBA_IDLE) {
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
            const rp_gc_landmark_t *l;
            if (!rp_all_finite(ft->uv, 2) || !(l = lm_find(vo, ft->id)) || l->cam != cam) {
                continue;
            }
            vo->kf_hash[nc] = rp_idmap_hash(ft->id);
            vo->kf_feat[nc] = f;
            nc++;
        }
        const uint16_t want = vo->cfg.ba_per_cam;
        if (nc > want) {
            select_lowest(vo->kf_hash, vo->kf_feat, nc, want);
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
    if (rp_gcba_add_keyframe(&vo->ba, vo->ekf.x, o, m) != RP_OK) {
        return;
    }
    if (++vo->kf_since < vo->cfg.ba_every || vo->ba.n_kf < 3) {
        return;
    }
    vo->kf_since = 0;
    if (rp_gcba_start(&vo->ba, vo->rig, vo->mu, &vo->cfg.ba) != RP_OK) {
        vo->n_ba_rejected++;
    }
}

/* The adjustment under way is solved: its result into mu, the map and the pose. */
static void take_adjustment(rp_vo_gc_t *vo)
{
    rp_gcba_result_t *r = &vo->ba_last;
    const rp_status_t st = rp_gcba_finish(&vo->ba, r);
    const rp_real var_obs = r->mu_var * vo->cfg.ba_var_scale;
    const rp_real dm = r->mu - vo->mu;
    /* refused: a failed or unconverged adjustment (residuals well above the pixel noise), or
     * one more than 4 sigma from the current unit; after two such refusals in a row of
     * converged adjustments the current unit is the suspect: it restarts from the next one */
    if (st != RP_OK || r->rms_px > RP_C(1.5) * vo->cfg.ba.sigma_px) {
        vo->n_ba_rejected++;
        return;
    }
    if (dm * dm > RP_C(16.0) * (vo->mu_var + var_obs)) {
        vo->n_ba_rejected++;
        if (++vo->ba_refused_run < 2) {
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
    correct_pose(vo);
}

/* Each observed landmark's structure EKF takes its pixel at the updated pose, with the pose's
 * projected uncertainty added to the pixel noise. */
static void refine_structure(rp_vo_gc_t *vo, uint32_t n)
{
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, vo->ekf.x) != RP_OK) {
        return;
    }
    rp_real Ppp[36];
    pose_cov(vo, Ppp);
    const rp_real s2 = vo->cfg.ekf.sigma_px * vo->cfg.ekf.sigma_px;
    for (uint32_t i = 0; i < n; ++i) {
        rp_gc_landmark_t *l = lm_find(vo, vo->obs_id[i]);
        if (!l) {
            continue;
        }
        rp_real uv[2], Jp[12];
        if (rp_rig_project(&vo->rig_m, l->cam, &pl, l->pt.M, uv, Jp, NULL) != RP_OK) {
            continue;
        }
        const rp_real lam = proj_var_max(Jp, 6, Ppp, 0);
        const rp_real sig = rp_sqrt(s2 + (lam > RP_C(0.0) ? lam : RP_C(0.0)));
        /* a rejected update leaves the point as it was */
        (void)rp_struct_update(&l->pt, &vo->rig_m, l->cam, &pl, vo->obs[i].uv, sig,
                               vo->cfg.ekf.gate_chi2);
    }
}

rp_status_t rp_vo_gc_step(rp_vo_gc_t *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    if (!vo || !est) {
        return RP_E_ARG;
    }
    memset(est, 0, sizeof(*est));
    if (!fs || !vo->rig) {
        fill_estimate(vo, NULL, RP_EST_LOST, est);
        return RP_E_ARG;
    }
    if (validate_frameset(vo, fs) != RP_OK) {
        fill_estimate(vo, NULL, RP_EST_LOST, est);
        return RP_E_ARG;
    }
    if (vo->frame == 0) {
        return first_frame(vo, fs, est);
    }

    rp_real dt = vo->cfg.default_dt_s;
    if (fs->utime > vo->prev_utime) {
        dt = (rp_real)(fs->utime - vo->prev_utime) * RP_C(1e-6);
    }
    uint32_t flags = 0;

    uint8_t had_image[RP_MAX_CAMS] = {0};
    for (uint8_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        had_image[cam] = (uint8_t)(fs->n[cam] > 0 && cam_in_layout(vo, cam));
    }
    /* Which landmarks are still tracked; lost tracks are dropped. */
    const uint32_t n = gather_obs(vo, fs);
    lm_drop_lost(vo, had_image);

    rp_status_t st = rp_ekf_predict(&vo->ekf, dt);
    uint16_t n_gated = 0;
    uint32_t n_mature = 0;
    for (uint8_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        est->n_used[cam] = 0;
    }
    if (st == RP_OK) {
        const uint32_t m = select_for_pose(vo, n, &n_mature);
        rp_ekf_info_t info;
        st = rp_ekf_update(&vo->ekf, &vo->rig_m, vo->pobs, m, vo->pused, &info);
        n_gated = info.n_gated;
        if (info.cov_reset) {
            flags |= RP_EST_COV_RESET;
        }
        if (st == RP_OK) {
            for (uint32_t i = 0, k = 0; i < n; ++i) {
                vo->used[i] = 0;
                if (vo->in_pose[i]) {
                    vo->used[i] = vo->pused[k++];
                    if (vo->used[i]) {
                        est->n_used[vo->obs[i].cam]++;
                    }
                }
            }
        }
    }

    if (st == RP_OK) {
        flags |= RP_EST_TRACKING;
        if (n_gated > 0) {
            flags |= RP_EST_GATED;
        }
        if (n_mature < vo->cfg.min_mature) {
            flags |= RP_EST_SCALE_WEAK;
        }
        refine_structure(vo, n);
        metric_scale(vo, fs);
    } else {
        flags |= RP_EST_LOST;
    }

    /* Top up cameras under their threshold from this frame, at the (updated) pose. */
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, vo->ekf.x) == RP_OK) {
        rp_real Ppp[36];
        pose_cov(vo, Ppp);
        for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
            const uint8_t cam = vo->cfg.cams[k];
            if (vo->map.n_group[cam] < vo->cfg.min_tracked && had_image[cam]) {
                if (top_up_camera(vo, fs, cam, &pl, Ppp) > 0) {
                    flags |= RP_EST_REINIT;
                }
            }
        }
    }
    for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
        if (vo->map.n_group[vo->cfg.cams[k]] < vo->cfg.min_tracked || !had_image[vo->cfg.cams[k]]) {
            flags |= RP_EST_DEGRADED;
        }
    }

    vo->prev_utime = fs->utime;
    fill_estimate(vo, fs, flags, est);
    est->n_gated = n_gated;
    vo->frame++;
    return st == RP_OK ? RP_OK : (st == RP_E_DIVERGED ? RP_E_DIVERGED : RP_E_TOO_FEW);
}
