/*
 * rp_vo.c - the plumbing every layout shares around its pose EKF (see rp_vo.h).
 */
#include <string.h>

#include "rigpose/rp_vo.h"
#include "priv/rp_math.h"
#include "rigpose/rp_rot.h"

rp_status_t rp_vo_ekf_idle(rp_ekf_t *ekf, const rp_ekf_params_t *prm)
{
    rp_real x0[RP_EKF_N] = {0}, P0[RP_EKF_N];
    for (int i = 0; i < RP_EKF_N; ++i) {
        P0[i] = RP_C(1.0);
    }
    return rp_ekf_init(ekf, prm, x0, P0);
}

rp_status_t rp_vo_init_filter(const rp_rig_t *rig, const rp_ekf_params_t *prm, rp_ekf_t *ekf)
{
    const rp_status_t st = rp_rig_check(rig);
    if (st != RP_OK) {
        return st;
    }
    return prm && ekf ? rp_vo_ekf_idle(ekf, prm) : RP_E_ARG;
}

rp_status_t rp_vo_begin_step(const rp_rig_t *rig, const rp_frameset_t *fs, int64_t prev_utime,
                             rp_real default_dt_s, rp_real *dt)
{
    if (!rig || rp_vo_check_frameset(fs, rig->n_cams) != RP_OK) {
        return RP_E_ARG;
    }
    return rp_vo_frame_dt(fs, prev_utime, default_dt_s, dt);
}

/* Start variance of velocity component i (0..2 translation, 3..5 rotation). */
static rp_real start_var(int i)
{
    return i < 3 ? RP_VO_START_SIGMA_V * RP_VO_START_SIGMA_V
                 : RP_VO_START_SIGMA_W * RP_VO_START_SIGMA_W;
}

rp_status_t rp_vo_ekf_offsets(rp_ekf_t *ekf, uint8_t cam_mask)
{
    if (!ekf) {
        return RP_E_ARG;
    }
    /* all of the layout's cameras but the lowest */
    const uint8_t states = ekf->prm.toff_estimate ? (uint8_t)(cam_mask & (cam_mask - 1u)) : 0;
    rp_real sig[RP_MAX_CAMS];
    for (int k = 0; k < RP_MAX_CAMS; ++k) {
        sig[k] = ekf->prm.toff_sigma_s;
    }
    return rp_ekf_toff_set(ekf, states, ekf->prm.toff0_s, sig, ekf->prm.toff_q);
}

/* rp_ekf_init on a started filter, its clock offsets carried over. */
static rp_status_t restart(rp_ekf_t *ekf, const rp_ekf_params_t *prm, const rp_real x0[RP_EKF_N],
                           const rp_real P0diag[RP_EKF_N])
{
    const rp_ekf_t old = *ekf;
    const rp_status_t st = rp_ekf_init(ekf, prm, x0, P0diag);
    return st == RP_OK ? rp_ekf_toff_carry(ekf, &old) : st;
}

rp_status_t rp_vo_ekf_at_origin(rp_ekf_t *ekf, const rp_ekf_params_t *prm)
{
    rp_real x0[RP_EKF_N] = {0}, P0[RP_EKF_N];
    for (int i = 0; i < 6; ++i) {
        P0[i] = RP_VO_ORIGIN_VAR;
        P0[6 + i] = start_var(i);
    }
    return ekf ? restart(ekf, prm, x0, P0) : RP_E_ARG;
}

rp_status_t rp_vo_ekf_from_pose(rp_ekf_t *ekf, const rp_ekf_params_t *prm, const rp_real p[6],
                                const rp_real cov[36], const rp_real p_prev[6], rp_real dt)
{
    if (!ekf || !prm || !p || !cov || !p_prev || !(dt > RP_C(0.0))) {
        return RP_E_ARG;
    }
    const rp_real s2 = prm->sigma_px * prm->sigma_px;
    rp_real x[RP_EKF_N], P0diag[RP_EKF_N], d[6];
    rp_pose_minus(p, p_prev, d); /* the chart of rp_rig.h: rates from Log(R R_prev^T) */
    for (int i = 0; i < 6; ++i) {
        x[i] = p[i];
        x[6 + i] = d[i] / dt;
        P0diag[i] = cov[i * 6 + i] * s2;
        P0diag[6 + i] = P0diag[i] / (dt * dt) + start_var(i);
    }
    const rp_status_t st = restart(ekf, prm, x, P0diag);
    if (st != RP_OK) {
        return st;
    }
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            ekf->P[i * RP_EKF_N + j] = cov[i * 6 + j] * s2;
        }
    }
    return RP_OK;
}

rp_status_t rp_vo_check_frameset(const rp_frameset_t *fs, uint8_t n_rig_cams)
{
    if (!fs) {
        return RP_E_ARG;
    }
    for (uint8_t cam = 0; cam < RP_MAX_CAMS; ++cam) {
        if (fs->n[cam] > RP_MAX_FEATS_PER_CAM || (cam >= n_rig_cams && fs->n[cam] != 0)) {
            return RP_E_ARG;
        }
    }
    return RP_OK;
}

rp_status_t rp_vo_frame_dt(const rp_frameset_t *fs, int64_t prev_utime, rp_real default_dt_s,
                           rp_real *dt)
{
    if (!fs || !dt) {
        return RP_E_ARG;
    }
    *dt = default_dt_s;
    if (fs->utime > prev_utime) {
        *dt = (rp_real)(fs->utime - prev_utime) * RP_C(1e-6);
    }
    return RP_OK;
}

rp_status_t rp_vo_fill_estimate(const rp_ekf_t *ekf, rp_real t_scale, int64_t utime,
                                uint32_t frame, uint32_t flags, uint16_t n_landmarks,
                                rp_estimate_t *est)
{
    if (!ekf || !est) {
        return RP_E_ARG;
    }
    est->utime = utime;
    est->frame = frame;
    for (int i = 0; i < 6; ++i) {
        const rp_real si = i < 3 ? t_scale : RP_C(1.0);
        est->p[i] = si * ekf->x[i];
        est->v[i] = si * ekf->x[6 + i];
        for (int j = 0; j < 6; ++j) {
            const rp_real sj = j < 3 ? t_scale : RP_C(1.0);
            est->cov[i * 6 + j] = si * sj * ekf->P[i * RP_EKF_N + j];
        }
    }
    /* published angles in their canonical ranges, alpha, gamma in [-pi, pi], beta in
     * [-pi/2, pi/2] (the same rotation; the chart's covariance does not change) */
    const rp_real *a = est->p + 3;
    if (rp_fabs(a[0]) > RP_PI || rp_fabs(a[1]) > RP_PI / RP_C(2.0) || rp_fabs(a[2]) > RP_PI) {
        rp_real R[9];
        rp_rot_from_angles(a, R);
        /* ignored: only non-finite angles fail, and stay as they are */
        (void)rp_rot_to_angles(R, est->p + 3);
    }
    if (flags & RP_EST_LOST) {
        flags &= ~(uint32_t)RP_EST_TRACKING; /* no update this frame: never both */
    }
    if (ekf->held) {
        flags |= RP_EST_HELD | RP_EST_LOST;
    }
    est->flags = flags;
    est->n_landmarks = n_landmarks;
    return RP_OK;
}

rp_status_t rp_vo_step_status(rp_status_t filter_st)
{
    /* The filter refuses arguments only for observations it was not given (rp_ekf_update: NULL
     * with n > 0): too few. RP_E_ARG from a step keeps its one meaning, a malformed frame set,
     * and RP_E_DEGENERATE the pipeline's (rp_pipe.h: no usable image): geometry that does not
     * fix the pose is said RP_E_SINGULAR. */
    if (filter_st == RP_E_ARG) {
        return RP_E_TOO_FEW;
    }
    return filter_st == RP_E_DEGENERATE ? RP_E_SINGULAR : filter_st;
}

rp_status_t rp_vo_end_step(const rp_frameset_t *fs, uint16_t n_gated, rp_status_t filter_st,
                           int64_t *prev_utime, uint32_t *frame, rp_estimate_t *est)
{
    if (!fs || !prev_utime || !frame || !est) {
        return RP_E_ARG;
    }
    *prev_utime = fs->utime;
    est->n_gated = n_gated;
    ++*frame;
    return rp_vo_step_status(filter_st);
}

rp_ransac_params_t rp_vo_ransac_params(const rp_ekf_params_t *prm)
{
    rp_ransac_params_t rp = rp_ransac_default_params();
    rp.sigma_px = prm->sigma_px * RP_C(1.4142135623730951); /* sqrt(2) sigma_px */
    if (prm->gate_chi2 > RP_C(0.0)) {
        rp.chi2 = prm->gate_chi2;
    }
    if (prm->min_features > rp.min_inliers) {
        rp.min_inliers = prm->min_features;
    }
    return rp;
}

rp_status_t rp_vo_ekf_towards(const rp_ekf_t *pred, const rp_real p[6], rp_ekf_t *out)
{
    if (!pred || !p || !out) {
        return RP_E_ARG;
    }
    rp_real d[6];
    *out = *pred;
    rp_pose_minus(p, pred->x, d);
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            out->P[i * RP_EKF_N + j] += d[i] * d[j];
        }
    }
    return RP_OK;
}

rp_status_t rp_vo_refind(rp_ransac_t *rs, const rp_rig_t *rig, const rp_ekf_t *pred,
                         rp_obs_t *obs, uint32_t n, uint32_t first_used, uint8_t *inl,
                         rp_ekf_t *ekf, uint8_t *used, rp_ekf_info_t *info)
{
    if (!rs || !rig || !pred || (n > 0 && (!obs || !inl || !used)) || !ekf || !info) {
        return RP_E_ARG;
    }
    const rp_ransac_params_t rp = rp_vo_ransac_params(&pred->prm);
    rp_ransac_result_t res;
    rp_ekf_t e;
    if (rp_ransac_solve(rs, rig, obs, n, &rp, inl, &res) != RP_OK ||
        res.n_inliers <= first_used || rp_vo_ekf_towards(pred, res.p, &e) != RP_OK) {
        return RP_E_TOO_FEW;
    }
    for (uint32_t i = 0; i < n; ++i) {
        if (!inl[i]) {
            obs[i].w = RP_C(0.0);
        }
    }
    rp_ekf_info_t retry;
    if (rp_ekf_update(&e, rig, obs, n, used, &retry) != RP_OK ||
        2u * retry.n_used < res.n_inliers) {
        return RP_E_TOO_FEW;
    }
    *ekf = e;
    *info = retry;
    info->n_gated = (uint16_t)(info->n_gated + n - res.n_inliers); /* RANSAC's outliers */
    info->n_outside = info->n_gated;
    return RP_OK;
}
