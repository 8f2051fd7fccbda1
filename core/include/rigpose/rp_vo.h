/*
 * rp_vo.h - what every layout (rp_vo_stereo, rp_vo_mono, rp_vo_gc) does around its pose EKF:
 * checking a frame set, the frame interval, the filter's start priors, filling the estimate and
 * mapping the filter's status to the step's. The landmarks live in rp_lmtab.h.
 *
 * A layout's filter goes through three priors:
 *  - idle (rp_vo_ekf_idle): x = 0, P = I, between init and the first frame set (only its
 *    parameters matter: rp_ekf_init checks them);
 *  - at the origin (rp_vo_ekf_at_origin): the first frame set defines the world (cam1's frame
 *    now), so the pose is exactly zero (variance RP_VO_ORIGIN_VAR) and the velocity unknown
 *    (RP_VO_START_SIGMA_V, RP_VO_START_SIGMA_W);
 *  - from a pose (rp_vo_ekf_from_pose): at the second frame set, the pose p that Lowe's method
 *    found with its covariance sigma_px^2 cov (cov per unit pixel variance, as rp_lowe_solve
 *    gives it, in rp_rig.h's pose chart), and the rates (p [-] p_prev) / dt (translation
 *    difference; world-frame rotation vector Log(R R_prev^T) over dt) with variance
 *    diag(cov) sigma_px^2 / dt^2 plus the start sigma^2. The pose block keeps Lowe's full
 *    covariance.
 */
#ifndef RP_VO_H
#define RP_VO_H

#include "rp_ekf.h"
#include "rp_frame.h"
#include "rp_opts.h"
#include "rp_ransac.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RP_VO_START_SIGMA_V RP_C(1.0)  /* velocity prior when a filter starts, 1-sigma, m/s */
#define RP_VO_START_SIGMA_W RP_C(1.0)  /* angular-rate prior when it starts, 1-sigma, rad/s */
/* A camera captured delta seconds from the state's time sees from the pose the filter's rate
 * puts there (rp_ekf.h); before the filter has a rate (its first frame set; stereo: its first
 * two, whose landmarks come before the update) that pose is known to |delta| times the start
 * sigmas only, so a camera farther than this from the state's time makes no landmarks then
 * (s): 1 ms at RP_VO_START_SIGMA_W is 0.8 px at 800 px focal length, the pixel noise's size.
 * When no camera of the layout is that near, all start, each as if at the state's time. */
#define RP_VO_START_SKEW_S RP_C(0.001)
#define RP_VO_ORIGIN_VAR RP_C(1e-12)   /* variance of the pose at the first frame set (zero by
                                        * definition; kept positive definite), m^2 and rad^2 */
#define RP_VO_MIN_START 6              /* landmarks a first frame set needs to count as a start
                                        * (the 6 pose parameters) */

/* Rig RANSAC's parameters for a layout whose filter has settings prm: the filter's gate
 * (gate_chi2, when gating) on a residual of variance 2 sigma_px^2 (a landmark placed from
 * earlier pixels carries their noise as well as the current pixel's), at least prm's
 * min_features inliers. */
rp_ransac_params_t rp_vo_ransac_params(const rp_ekf_params_t *prm);

/* *out = pred with its pose covariance widened by d d^T, d = p [-] pred's pose (rp_pose_minus:
 * the filter's chart): an update from it can reach p, a pose found from the images, while the
 * velocity keeps its correlation with the pose. RP_E_ARG on NULL. */
rp_status_t rp_vo_ekf_towards(const rp_ekf_t *pred, const rp_real p[6], rp_ekf_t *out);

/* The re-find of a layout whose update left most of its n observations out: rig RANSAC
 * (rp_vo_ransac_params) over obs through rig, then the plain update redone on its inliers
 * (outliers get w = 0) from pred widened towards RANSAC's pose (rp_vo_ekf_towards). RP_OK, with
 * *ekf, used[0..n) and *info replaced (RANSAC's outliers counted as gated and outside), when
 * RANSAC found more inliers than first_used and the redone update uses at least half of them;
 * otherwise RP_E_TOO_FEW with *ekf unchanged (obs's weights are scratch then). inl: n bytes of
 * scratch. */
rp_status_t rp_vo_refind(rp_ransac_t *rs, const rp_rig_t *rig, const rp_ekf_t *pred,
                         rp_obs_t *obs, uint32_t n, uint32_t first_used, uint8_t *inl,
                         rp_ekf_t *ekf, uint8_t *used, rp_ekf_info_t *info);

/* x = 0, P = I under prm (the filter before the first frame set). rp_ekf_init's errors. */
rp_status_t rp_vo_ekf_idle(rp_ekf_t *ekf, const rp_ekf_params_t *prm);

/* The clock offsets of the layout's cameras (cam_mask, bit k: rig camera k): with
 * ekf->prm.toff_estimate, the offsets of all of them but the lowest (the reference) become
 * states (rp_ekf_toff_set from prm's toff0_s, toff_sigma_s, toff_q); else none is. Called on the
 * idle filter at a layout's init: the two priors below carry the offsets on. RP_E_ARG. */
rp_status_t rp_vo_ekf_offsets(rp_ekf_t *ekf, uint8_t cam_mask);

/* The two priors below restart *ekf, which must be a started filter (the idle one at least):
 * its clock offsets, their states and covariance carry over (rp_ekf_toff_carry). */

/* The prior at the first frame set: pose zero with variance RP_VO_ORIGIN_VAR, velocity zero with
 * the start sigmas. rp_ekf_init's errors. */
rp_status_t rp_vo_ekf_at_origin(rp_ekf_t *ekf, const rp_ekf_params_t *prm);

/* The prior at the second frame set from pose p (m, rad) and its covariance prm->sigma_px^2 cov
 * (cov: 6x6 row-major per unit pixel variance), the previous pose p_prev and the interval dt
 * (s, > 0). RP_E_ARG (NULL, dt not > 0), rp_ekf_init's errors. */
rp_status_t rp_vo_ekf_from_pose(rp_ekf_t *ekf, const rp_ekf_params_t *prm, const rp_real p[6],
                                const rp_real cov[36], const rp_real p_prev[6], rp_real dt);

/* The checks a layout's init starts with: the rig (rp_rig_check's errors; RP_E_ARG if NULL) and
 * the filter's parameters prm (rp_ekf_init's errors; RP_E_ARG if NULL). On RP_OK *ekf is the
 * idle filter (rp_vo_ekf_idle). */
rp_status_t rp_vo_init_filter(const rp_rig_t *rig, const rp_ekf_params_t *prm, rp_ekf_t *ekf);

/* The checks a layout's step starts with, and the frame interval: RP_E_ARG if rig is NULL or
 * rp_vo_check_frameset(fs, rig->n_cams) refuses fs; else RP_OK with *dt from rp_vo_frame_dt. */
rp_status_t rp_vo_begin_step(const rp_rig_t *rig, const rp_frameset_t *fs, int64_t prev_utime,
                             rp_real default_dt_s, rp_real *dt);

/* RP_OK if fs can be processed by a layout over a rig of n_rig_cams cameras: no camera holds more
 * than RP_MAX_FEATS_PER_CAM features and no camera outside the rig holds any. RP_E_ARG
 * otherwise (or fs NULL). */
rp_status_t rp_vo_check_frameset(const rp_frameset_t *fs, uint8_t n_rig_cams);

/* The interval from the previous frame set (prev_utime, us) to fs: its timestamp difference if
 * it is later, else default_dt_s (missing or repeated timestamps). *dt in s. RP_E_ARG (NULL). */
rp_status_t rp_vo_frame_dt(const rp_frameset_t *fs, int64_t prev_utime, rp_real default_dt_s,
                           rp_real *dt);

/* est's pose, velocity and 6x6 pose covariance from the filter, translations (and their
 * velocities) times t_scale (1: the filter's unit is the metre; gc: 1 / its map unit), and
 * utime, frame, flags, n_landmarks as given, except that LOST clears TRACKING and a held filter
 * (rp_ekf_t.held) adds HELD | LOST. The other fields of est are left alone.
 * RP_E_ARG (NULL). */
rp_status_t rp_vo_fill_estimate(const rp_ekf_t *ekf, rp_real t_scale, int64_t utime,
                                uint32_t frame, uint32_t flags, uint16_t n_landmarks,
                                rp_estimate_t *est);

/* A layout step's status from its filter's (the start or the update): each failure keeps its
 * own code, so a caller can tell them apart (RP_E_TOO_FEW too few features or inliers,
 * RP_E_DIVERGED a filter fault with the covariance reset, RP_E_NO_CONVERGE Lowe's start did not
 * converge, RP_E_SINGULAR geometry that does not fix the pose, RP_E_NAN a non-finite state
 * or measurement...); but RP_E_ARG, which a step's caller reads as a malformed frame set, is
 * said RP_E_TOO_FEW (the filter refuses arguments only for missing observations), and
 * RP_E_DEGENERATE, the pipeline's "no usable image" (rp_pipe.h), RP_E_SINGULAR. */
rp_status_t rp_vo_step_status(rp_status_t filter_st);

/* The bookkeeping a layout's step ends with, once est is filled: *prev_utime = fs->utime,
 * est->n_gated = n_gated, ++*frame; returns rp_vo_step_status(filter_st) (RP_E_ARG if a pointer
 * is NULL, nothing changed). */
rp_status_t rp_vo_end_step(const rp_frameset_t *fs, uint16_t n_gated, rp_status_t filter_st,
                           int64_t *prev_utime, uint32_t *frame, rp_estimate_t *est);

#ifdef __cplusplus
}
#endif

#endif /* RP_VO_H */
