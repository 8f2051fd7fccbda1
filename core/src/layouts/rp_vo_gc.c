/*
 * rp_vo_gc.c - the generalised camera (see rp_vo_gc.h for the algorithm).
 */
#include <string.h>

#include "priv/rp_math.h"
#include "priv/rp_sym3.h"
#include "priv/rp_vo_gc_scale.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_vo.h"

#define RANSAC_SEED 0x5EED5u /* any fixed value: the run is a function of its input */

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
    c.one_point = 1; /* config/README.md, `one_point`: its cost and gain */
    c.ransac = 1;
    c.drop_odds = RP_DROP_ODDS_ONE; /* step 3b (rp_vo_gc.h) */
    return c;
}

/* ---- landmarks: vo->lm (group = the camera that sees it) and vo->mature, by slot ---------- */

static rp_status_t lm_insert(rp_vo_gc_t *vo, uint32_t id, uint8_t cam, const rp_point3_t *pt)
{
    uint16_t slot;
    rp_status_t st = rp_lmtab_insert(&vo->lm, id, cam, pt, &slot);
    if (st == RP_OK) {
        /* ignored: slot is the table's own */
        (void)rp_droptest_reset_slot(&vo->drop, slot);
        vo->mature[slot] = 0;
        vo->taken[slot] = vo->frame + 1u; /* the pixel that placed it */
    }
    return st;
}

/* Bit cam set for each camera that delivered an image. */
static uint32_t image_mask(const uint8_t had_image[RP_MAX_CAMS])
{
    uint32_t mask = 0;
    for (uint32_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        mask |= had_image[cam] ? (1u << cam) : 0u;
    }
    return mask;
}

/* Drop every landmark not seen this frame whose camera delivered an image (its track was
 * lost); landmarks of cameras without an image are kept. Clears the marks. */
static void lm_drop_lost(rp_vo_gc_t *vo, const uint8_t had_image[RP_MAX_CAMS])
{
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_drop_unmarked(&vo->lm, image_mask(had_image), NULL);
}

/* ---- set-up ------------------------------------------------------------------------------ */

rp_status_t rp_vo_gc_init(rp_vo_gc_t *vo, const rp_rig_t *rig, const rp_vo_gc_cfg_t *cfg)
{
    rp_ekf_t idle; /* rp_vo_init_filter checks the EKF parameters */
    rp_status_t st = vo && cfg ? rp_vo_init_filter(rig, &cfg->ekf, &idle) : RP_E_ARG;
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
        !(cfg->default_dt_s > RP_C(0.0)) || !rp_finite(cfg->default_dt_s) ||
        cfg->one_point > 1 || cfg->ransac > 1 || !rp_finite(cfg->drop_odds) ||
        !(cfg->drop_odds == RP_C(0.0) || cfg->drop_odds > RP_C(1.0))) {
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
    memset(vo, 0, sizeof(*vo));
    vo->rig = rig;
    vo->cfg = *cfg;
    rp_vo_gc_set_mu(vo, RP_C(1.0));
    vo->ekf = idle;
    uint8_t cams = 0;
    for (uint8_t k = 0; k < cfg->n_cams; ++k) {
        cams = (uint8_t)(cams | (1u << cfg->cams[k]));
    }
    st = rp_vo_ekf_offsets(&vo->ekf, cams);
    if (st != RP_OK) {
        return st;
    }
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_clear(&vo->lm);
    /* ignored: only NULL arguments fail */
    (void)rp_idmap_clear(&vo->retired);
    vo->n_dropped = 0;
    (void)rp_ekf1pt_seed(&vo->op, RANSAC_SEED);
    /* ignored: only NULL arguments fail */
    (void)rp_ransac_seed(&vo->rs, RANSAC_SEED);
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
        uint16_t slot;
        uint8_t retired = 0;
        /* ignored: vo and the flag are ours */
        (void)rp_vo_gc_is_retired(vo, ft->id, &retired);
        if (ft->id == RP_VO_GC_EMPTY_ID || !rp_all_finite(ft->uv, 2) ||
            rp_lmtab_find(&vo->lm, ft->id, &slot) == RP_OK || retired) {
            continue; /* a landmark already, or a retired track (step 3b) */
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

/* Standard deviation of the landmark in slot along its ray from its camera at pose pl, and the
 * range. */
static void ray_sigma(const rp_vo_gc_t *vo, uint16_t slot, const rp_pose_lin_t *pl,
                      rp_real *sigma, rp_real *range)
{
    const rp_point3_t *pt = &vo->lm.pt[slot];
    const rp_rig_cam_t *rc = &vo->rig_m.cam[vo->lm.map.slot_group[slot]];
    rp_real c[3], u[3];
    for (int a = 0; a < 3; ++a) {
        c[a] = pl->p[a] + pl->R[a * 3 + 0] * rc->D[0] + pl->R[a * 3 + 1] * rc->D[1] +
               pl->R[a * 3 + 2] * rc->D[2];
        u[a] = pt->M[a] - c[a];
    }
    const rp_real r = rp_sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    *range = r;
    if (!(r > RP_C(0.0))) {
        *sigma = RP_C(1e30); /* at the camera's centre: no direction, never mature */
        return;
    }
    for (int a = 0; a < 3; ++a) {
        u[a] /= r;
    }
    const rp_real *k = pt->C;
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

/* Gather the observations of held landmarks in fs, each from the camera that holds it, into
 * vo->obs; marks them seen. */
static uint32_t gather_obs(rp_vo_gc_t *vo, const rp_frameset_t *fs)
{
    uint32_t n = 0;
    /* ignored: cannot fill: the cap holds a whole frame set */
    (void)rp_lmtab_gather(&vo->lm, fs, vo->cfg.cams, vo->cfg.n_cams, 1, vo->obs, vo->obs_id,
                          RP_VO_GC_MAX_OBS, &n);
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_mark_ids(&vo->lm, vo->obs_id, NULL, n);
    return n;
}

static void fill_estimate(const rp_vo_gc_t *vo, const rp_frameset_t *fs, uint32_t flags,
                          rp_estimate_t *est)
{
    /* map units -> metres: translations and their velocities divided by mu */
    const rp_real im = RP_C(1.0) / vo->mu;
    /* ignored: only NULL arguments fail */
    (void)rp_vo_fill_estimate(&vo->ekf, im, fs ? fs->utime : vo->prev_utime, vo->frame, flags,
                              vo->lm.map.n, est);
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

static rp_status_t first_frame(rp_vo_gc_t *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    static const rp_real zero[6] = {0};
    rp_pose_lin_t pl;
    /* ignored: a zero pose is finite, the only failure */
    (void)rp_pose_lin_set(&pl, zero);
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_clear(&vo->lm);
    /* ignored: only NULL arguments fail */
    (void)rp_idmap_clear(&vo->retired);
    /* ignored: cannot fail: the parameters were checked at init */
    (void)rp_vo_ekf_at_origin(&vo->ekf, &vo->cfg.ekf);
    rp_vo_gc_scale_reset(vo);
    uint32_t flags = RP_EST_INITIALISING;
    /* a camera not at the state's time waits for the filter's rate (RP_VO_START_SKEW_S), unless
     * none is: then all start here, each as if at the state's time */
    uint8_t any_near = 0;
    for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
        const uint8_t cam = vo->cfg.cams[k];
        const rp_real d = (rp_real)fs->cam_dt_us[cam] * RP_C(1e-6) + vo->ekf.toff[cam];
        any_near = (uint8_t)(any_near | (fs->n[cam] > 0 && rp_fabs(d) <= RP_VO_START_SKEW_S));
    }
    for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
        const uint8_t cam = vo->cfg.cams[k];
        const rp_real d = (rp_real)fs->cam_dt_us[cam] * RP_C(1e-6) + vo->ekf.toff[cam];
        if (!any_near || rp_fabs(d) <= RP_VO_START_SKEW_S) {
            /* ignored: the count is not needed here */
            (void)top_up_camera(vo, fs, cam, &pl, NULL);
        }
        if (vo->lm.map.n_group[cam] < vo->cfg.min_tracked) {
            flags |= RP_EST_DEGRADED;
        }
    }
    rp_vo_gc_scale_step(vo, fs, 0);
    vo->frame = 1;
    vo->prev_utime = fs->utime;
    fill_estimate(vo, fs, flags | RP_EST_SCALE_WEAK, est);
    est->frame = 0;
    return vo->lm.map.n >= RP_VO_MIN_START ? RP_OK : RP_E_TOO_FEW;
}

/* Weights and maturity of the gathered observations at the predicted pose; fills vo->pobs
 * with the ones offered to the pose update. Returns their number; *n_mature the mature ones. */
static uint32_t select_for_pose(rp_vo_gc_t *vo, uint32_t n, uint32_t *n_mature)
{
    rp_pose_lin_t pl;
    *n_mature = 0;
    for (uint32_t i = 0; i < n; ++i) {
        uint16_t s;
        vo->in_pose[i] = 0;
        vo->obs_slot[i] = rp_lmtab_find(&vo->lm, vo->obs_id[i], &s) == RP_OK
                              ? s
                              : (uint16_t)RP_IDMAP_MAX_SLOTS;
    }
    if (rp_pose_lin_set(&pl, vo->ekf.x) != RP_OK) {
        return 0;
    }
    const rp_real s2 = vo->cfg.ekf.sigma_px * vo->cfg.ekf.sigma_px;
    for (uint32_t i = 0; i < n; ++i) {
        const uint16_t s = vo->obs_slot[i];
        rp_obs_t *o = &vo->obs[i];
        rp_real uv[2], JM[6];
        if (s >= RP_IDMAP_MAX_SLOTS ||
            rp_rig_project(&vo->rig_m, o->cam, &pl, o->M, uv, NULL, JM) != RP_OK) {
            o->w = RP_C(0.0);
            continue;
        }
        const rp_real lam = proj_var_max(JM, 3, vo->lm.pt[s].C, 1);
        o->w = s2 / (s2 + (lam > RP_C(0.0) ? lam : RP_C(0.0)));
        if (!vo->mature[s]) {
            rp_real sig, range;
            ray_sigma(vo, s, &pl, &sig, &range);
            if (sig < vo->cfg.mature_frac * range) {
                vo->mature[s] = 1;
            }
        }
        if (vo->mature[s]) {
            (*n_mature)++;
        }
    }
    const int all = *n_mature < vo->cfg.min_mature;
    uint32_t m = 0;
    rp_real wsum = RP_C(0.0);
    for (uint32_t i = 0; i < n; ++i) {
        const uint16_t s = vo->obs_slot[i];
        if (s >= RP_IDMAP_MAX_SLOTS || !(vo->obs[i].w > RP_C(0.0)) ||
            (!all && !vo->mature[s])) {
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

/* Each observed landmark's structure EKF takes its pixel at the updated pose (moved to its
 * camera's capture time, rp_pose_lin_at), with the pose's projected uncertainty added to the
 * pixel noise. */
static void refine_structure(rp_vo_gc_t *vo, uint32_t n)
{
    rp_pose_lin_t pl;
    rp_real delta = RP_C(0.0); /* of pl */
    if (rp_pose_lin_set(&pl, vo->ekf.x) != RP_OK) {
        return;
    }
    rp_real Ppp[36];
    pose_cov(vo, Ppp);
    const rp_real s2 = vo->cfg.ekf.sigma_px * vo->cfg.ekf.sigma_px;
    for (uint32_t i = 0; i < n; ++i) {
        uint16_t s;
        if (rp_lmtab_find(&vo->lm, vo->obs_id[i], &s) != RP_OK) {
            continue;
        }
        rp_point3_t *pt = &vo->lm.pt[s];
        const uint8_t cam = vo->lm.map.slot_group[s];
        const rp_real d = vo->obs[i].dt + vo->ekf.toff[cam];
        if (d != delta) {
            if (rp_pose_lin_at(&pl, vo->ekf.x, vo->ekf.x + 6, d) != RP_OK) {
                continue; /* a non-finite stamp: this observation only */
            }
            delta = d;
        }
        rp_real uv[2], Jp[12];
        if (rp_rig_project(&vo->rig_m, cam, &pl, pt->M, uv, Jp, NULL) != RP_OK) {
            continue;
        }
        const rp_real lam = proj_var_max(Jp, 6, Ppp, 0);
        const rp_real sig = rp_sqrt(s2 + (lam > RP_C(0.0) ? lam : RP_C(0.0)));
        /* a point its gate refuses stays as it was (the gate, not a fault) */
        if (rp_struct_update(pt, &vo->rig_m, cam, &pl, vo->obs[i].uv, sig,
                             vo->cfg.ekf.gate_chi2) == RP_OK) {
            vo->taken[s] = vo->frame + 1u;
        }
    }
}

/* Step 2's re-find: rig RANSAC over the m offered observations (vo->pobs), its gate the
 * filter's on a residual of variance 2 sigma_px^2 (a landmark placed from earlier pixels
 * carries their noise too), then the update redone on its inliers from the prediction with the
 * pose covariance widened by d d^T, d the gap from the predicted pose to RANSAC's. Kept (RP_OK,
 * vo->ekf, vo->pused, *info) when RANSAC found more inliers than the first update used and the
 * redone update uses at least half of them; otherwise RP_E_TOO_FEW and vo->ekf as it was given
 * (vo->pobs's weights are scratch: RANSAC's outliers may be left at 0). */
static rp_status_t refind(rp_vo_gc_t *vo, uint32_t m, uint32_t first_used, rp_ekf_info_t *info)
{
    const rp_status_t st = rp_vo_refind(&vo->rs, &vo->rig_m, &vo->ekf_pred, vo->pobs, m,
                                        first_used, vo->inl, &vo->ekf, vo->pused, info);
    vo->n_refound += st == RP_OK;
    return st;
}

/* Step 2's pose update of the m offered observations vo->pobs: 1-point RANSAC or the plain
 * gated update, then (cfg.ransac, metric structure) the re-find when most were left out or the
 * update failed with enough of them. */
static rp_status_t pose_update(rp_vo_gc_t *vo, uint32_t m, uint32_t n_mature,
                               rp_ekf_info_t *info, int *refind_ran)
{
    *refind_ran = 0;
    vo->ekf_pred = vo->ekf;
    rp_status_t st;
    if (vo->cfg.one_point) {
        rp_ekf1pt_info_t oi;
        rp_ekf1pt_params_t op = rp_ekf1pt_default_params();
        op.regroup = 0; /* young landmarks at an assumed depth: rp_ekf1pt.h, step 2b */
        st = rp_ekf1pt_update(&vo->op, &vo->ekf, &vo->rig_m, vo->pobs, m, &op, vo->pused, &oi);
        *info = oi.ekf;
    } else {
        st = rp_ekf_update(&vo->ekf, &vo->rig_m, vo->pobs, m, vo->pused, info);
    }
    const int most_out = st == RP_OK ? 2u * info->n_outside > m : m >= vo->cfg.ekf.min_features;
    if (!vo->cfg.ransac || !most_out || n_mature < vo->cfg.min_mature) {
        return st;
    }
    const rp_ekf_info_t first_info = *info;
    memcpy(vo->used, vo->pused, m); /* vo->used is rebuilt from vo->pused after the update */
    *refind_ran = 1;
    if (refind(vo, m, st == RP_OK ? first_info.n_used : 0u, info) == RP_OK) {
        return RP_OK;
    }
    memcpy(vo->pused, vo->used, m);
    *info = first_info;
    return st;
}

rp_status_t rp_vo_gc_is_retired(const rp_vo_gc_t *vo, uint32_t id, uint8_t *is_retired)
{
    if (vo == NULL || is_retired == NULL) {
        return RP_E_ARG;
    }
    uint16_t slot;
    *is_retired = (uint8_t)(id != RP_VO_GC_EMPTY_ID && vo->retired.n > 0 &&
                            rp_idmap_find(&vo->retired, id, &slot) == RP_OK);
    return RP_OK;
}

/* Step 3b (rp_vo_gc.h): the drop test on this frame set's n observations, each judged in by
 * the pose update (offered ones) or by its structure gate (young ones); the landmarks it drops
 * leave the map and their tracks are retired. had_image: the cameras whose landmarks were
 * all observed (every one of theirs is among the n). */
static void drop_tracks(rp_vo_gc_t *vo, uint32_t n, const uint8_t had_image[RP_MAX_CAMS])
{
    uint32_t n_judged_in = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const uint16_t slot = vo->obs_slot[i]; /* select_for_pose's */
        vo->judged_in[i] = (uint8_t)(vo->in_pose[i] ? vo->used[i]
                                                    : slot < RP_IDMAP_MAX_SLOTS &&
                                                          vo->taken[slot] == vo->frame + 1u);
        n_judged_in += vo->judged_in[i];
    }
    if (2u * n_judged_in <= n) {
        return; /* the test's premise: the consensus is a majority (else the map is in doubt) */
    }
    /* ignored: the arrays are the estimator's own and drop_odds was checked at init */
    (void)rp_droptest_run(&vo->drop, vo->obs_slot, vo->judged_in, n, vo->cfg.ekf.min_features,
                          vo->cfg.drop_odds, vo->keep);
    uint32_t n_drop = 0;
    for (uint32_t i = 0; i < n; ++i) {
        vo->keep[i] = (uint8_t)(vo->keep[i] || vo->obs_slot[i] >= RP_IDMAP_MAX_SLOTS);
        if (!vo->keep[i]) {
            uint16_t rs;
            /* a full list forgets nothing it holds: the track may become a landmark again */
            (void)rp_idmap_insert(&vo->retired, vo->obs_id[i], vo->obs[i].cam, &rs);
            n_drop++;
        }
    }
    if (n_drop == 0) {
        return;
    }
    /* ignored: only NULL arguments fail */
    (void)rp_lmtab_mark_ids(&vo->lm, vo->obs_id, vo->keep, n);
    (void)rp_lmtab_drop_unmarked(&vo->lm, image_mask(had_image), NULL);
    vo->n_dropped += n_drop;
}

/* Step 3b's retired tracks that their camera no longer tracks leave the list (a camera without
 * an image this frame set keeps its). */
static void prune_retired(rp_vo_gc_t *vo, const rp_frameset_t *fs,
                          const uint8_t had_image[RP_MAX_CAMS])
{
    if (vo->retired.n == 0) {
        return;
    }
    for (uint8_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        for (uint16_t f = 0; had_image[cam] && f < fs->n[cam]; ++f) {
            uint16_t slot;
            if (rp_idmap_find(&vo->retired, fs->f[cam][f].id, &slot) == RP_OK) {
                /* ignored: slot is the map's own */
                (void)rp_idmap_mark(&vo->retired, slot);
            }
        }
    }
    /* ignored: only NULL arguments fail */
    (void)rp_idmap_drop_unmarked(&vo->retired, image_mask(had_image), NULL);
}

rp_status_t rp_vo_gc_step(rp_vo_gc_t *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    if (!vo || !est) {
        return RP_E_ARG;
    }
    memset(est, 0, sizeof(*est));
    rp_real dt;
    if (rp_vo_begin_step(vo->rig, fs, vo->prev_utime, vo->cfg.default_dt_s, &dt) != RP_OK) {
        fill_estimate(vo, NULL, RP_EST_LOST, est);
        return RP_E_ARG;
    }
    if (vo->frame == 0) {
        return first_frame(vo, fs, est);
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
    int refind_ran = 0;
    for (uint8_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        est->n_used[cam] = 0;
    }
    uint32_t m_offered = 0, n_in = 0;
    if (st == RP_OK) {
        const uint32_t m = select_for_pose(vo, n, &n_mature);
        m_offered = m;
        rp_ekf_info_t info;
        st = pose_update(vo, m, n_mature, &info, &refind_ran);
        n_gated = info.n_gated;
        if (info.cov_reset) {
            flags |= RP_EST_COV_RESET;
        }
        if (info.toff_reset) {
            flags |= RP_EST_CLOCK_JUMP;
        }
        if (st == RP_OK) {
            for (uint32_t i = 0, k = 0; i < n; ++i) {
                vo->used[i] = 0;
                if (vo->in_pose[i]) {
                    vo->used[i] = vo->pused[k++];
                    if (vo->used[i]) {
                        est->n_used[vo->obs[i].cam]++;
                        n_in++;
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
        refine_structure(vo, n);
        /* judged only by an update that can judge tracks: the map's depths converged (at the
         * start the updates judge the assumed depth, not the tracks), the prediction kept (not
         * re-found), most of the offered observations taken in, and most of all of them
         * (drop_tracks) */
        if (vo->cfg.drop_odds > RP_C(0.0) && n_mature >= vo->cfg.min_mature && !refind_ran &&
            2u * n_in > m_offered) {
            drop_tracks(vo, n, had_image);
        }
        rp_vo_gc_scale_step(vo, fs, refind_ran);
        /* the scale is weak while the landmarks have not converged; without step 6 always
         * (the assumed depth's); with it while the map's unit is known less well than the
         * reported covariance claims: its relative standard deviation over scale_sigma (no
         * window fused yet, or too few: a straight drive does not tell the unit, the prior's
         * stays) */
        if (n_mature < vo->cfg.min_mature || !(vo->cfg.mscale_sigma > RP_C(0.0)) ||
            vo->mu_var > vo->cfg.scale_sigma * vo->cfg.scale_sigma * vo->mu * vo->mu) {
            flags |= RP_EST_SCALE_WEAK;
        }
    } else {
        flags |= RP_EST_LOST;
    }

    prune_retired(vo, fs, had_image);
    /* Top up cameras under their threshold from this frame, at the (updated) pose at each
     * camera's capture time. */
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, vo->ekf.x) == RP_OK) {
        rp_real Ppp[36];
        pose_cov(vo, Ppp);
        for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
            const uint8_t cam = vo->cfg.cams[k];
            const rp_real d = (rp_real)fs->cam_dt_us[cam] * RP_C(1e-6) + vo->ekf.toff[cam];
            if (vo->lm.map.n_group[cam] < vo->cfg.min_tracked && had_image[cam] &&
                rp_pose_lin_at(&pl, vo->ekf.x, vo->ekf.x + 6, d) == RP_OK) {
                if (top_up_camera(vo, fs, cam, &pl, Ppp) > 0) {
                    flags |= RP_EST_REINIT;
                }
            }
        }
    }
    for (uint8_t k = 0; k < vo->cfg.n_cams; ++k) {
        const uint8_t cam = vo->cfg.cams[k];
        if (vo->lm.map.n_group[cam] < vo->cfg.min_tracked || !had_image[cam]) {
            flags |= RP_EST_DEGRADED;
        }
    }

    fill_estimate(vo, fs, flags, est);
    return rp_vo_end_step(fs, n_gated, st, &vo->prev_utime, &vo->frame, est);
}
