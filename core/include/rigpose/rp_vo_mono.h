/*
 * rp_vo_mono.h - one camera of the non-overlapping layout on its own (paper section 2.2.2):
 * methods cam1..cam4.
 *
 * Camera k of the rig runs its own 12-state pose EKF (rp_ekf over a one-camera rig: camera k's
 * intrinsics at R = I, D = 0) in its own world frame, world_k = camera k's frame at its first
 * frame, and one structure EKF (rp_struct) per tracked feature. Per frame set:
 *  1. New features (at the first frame, and whenever the tracked landmarks fall under
 *     min_tracked) are initialised "orthographically": on the plane z = init_depth_m of the
 *     camera's current frame, back-projected through the pixel, with a covariance long along the
 *     ray (init_depth_sigma_m in z) and thin across it (the pixel noise at that depth). A
 *     re-initialisation backtracks one frame, as the paper does: it places the previous frame's
 *     features (still tracked now) at the previous pose, then processes the current frame.
 *  2. At the second frame the pose EKF is started from Lowe's method (rp_lowe_solve).
 *  3. Every later frame: prediction, then the iterated update with every tracked landmark; each
 *     observation is weighted by its structure uncertainty (w = s^2 / (s^2 + projected point
 *     variance)), so fresh, depth-uncertain points count little. With `one_point` the update
 *     is 1-point RANSAC (rp_ekf1pt.h, with plain_without_majority: one camera's map carries
 *     the assumed depth's correlated errors, which with a small sigma_px exceed the gate in
 *     most observations; measured on the noise-free test without it, cam2 ty 0.037 m against
 *     0.013 m); observations it leaves out count as gated (their landmarks are dropped). With `ransac`, an update that leaves most observations out (or
 *     fails with enough of them) says the prediction is wrong: the camera's pose is re-found by
 *     RANSAC (P3P on the one camera, rp_ransac.h, gate on 2 sigma_px^2 / w: the weights carry
 *     the assumed depths' uncertainty), and the update redone on its inliers from the
 *     prediction with the pose covariance widened by d d^T, d the gap to the re-found pose;
 *     kept if it uses at least half of them (n_refound). The start (2) stays Lowe's method:
 *     at the second frame every landmark is at the assumed depth, so a minimal solver has no
 *     metric structure to work on; outliers there are left to the updates after it.
 *  4. After the pose update each used feature's structure EKF takes the observation at the new
 *     pose. A landmark missing from a frame is dropped for good.
 * The translation scale of a single camera comes only from the assumed depth.
 * Output: the camera's own pose (r_kj, l_kj) in world_k, and the pose mapped to the rig (cam1)
 * frame through the known extrinsics: R_j = R_k r_kj R_k^T (eq. 3), d_j = R_k l_kj + D_k - R_j D_k
 * (eq. 4 with unit scales).
 */
#ifndef RP_VO_MONO_H
#define RP_VO_MONO_H

#include "rp_ekf.h"
#include "rp_ekf1pt.h"
#include "rp_frame.h"
#include "rp_lmtab.h"
#include "rp_obs.h"
#include "rp_ransac.h"
#include "rp_rig.h"
#include "rp_struct.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint8_t cam;                /* camera of the rig this estimator uses */
    rp_ekf_params_t ekf;
    uint16_t min_tracked;       /* re-initialise under this many landmarks (50) */
    rp_real init_depth_m;       /* assumed scene depth: new features lie on z = this, m (> 0) */
    rp_real init_depth_sigma_m; /* its 1-sigma uncertainty, m (> 0) */
    rp_real default_dt_s;       /* frame interval used when timestamps are missing, s */
    uint8_t weight_by_structure;/* 1: weight pose observations by structure uncertainty */
    uint8_t one_point;          /* 1: every update through 1-point RANSAC (rp_ekf1pt.h) */
    uint8_t ransac;             /* 1: the pose re-found by RANSAC when most observations are
                                 * left out (step 3) */
} rp_vo_mono_cfg_t;

#define RP_VO_MONO_MIN_WEIGHT RP_C(1e-6) /* least structure weight w of an observation (and the
                                         * weight of one whose w is not finite); keeps every
                                         * gathered observation in the pose update's sums */

/* Defaults: camera 0, threshold 50, depth 1 m +- 0.3 m, 1/30 s, weighting on, 1-point RANSAC
 * and the RANSAC re-find on. */
rp_vo_mono_cfg_t rp_vo_mono_default_cfg(void);

#define RP_VO_MONO_EMPTY_ID RP_IDMAP_EMPTY /* not a feature id */

typedef struct {
    const rp_rig_t *rig;               /* the full rig (extrinsics of cam) */
    rp_rig_t own;                      /* one camera at R = I, D = 0 */
    rp_vo_mono_cfg_t cfg;
    rp_ekf_t ekf;                      /* camera's own pose in world_k */
    rp_lmtab_t lm;                     /* landmarks: points in world_k (m), all in group 0;
                                        * mark = observed now */
    uint16_t n_prev;                   /* previous frame's features of cam, for backtracking */
    rp_feat_t prev[RP_MAX_FEATS_PER_CAM];
    rp_real prev_p[6];                 /* own pose at the previous frame */
    uint32_t frame;
    int64_t prev_utime;
    rp_obs_t obs[RP_MAX_FEATS_PER_CAM];  /* scratch */
    uint8_t used[RP_MAX_FEATS_PER_CAM];
    uint32_t obs_id[RP_MAX_FEATS_PER_CAM];
    uint8_t inl[RP_MAX_FEATS_PER_CAM];   /* scratch: RANSAC's inliers */
    uint8_t first_used[RP_MAX_FEATS_PER_CAM]; /* scratch: the first update's used flags */
    rp_ekf_t ekf_pred;                 /* scratch: the prediction, for a re-found update */
    rp_ekf1pt_t op;                    /* 1-point RANSAC's generator and scratch */
    rp_ransac_t rs;                    /* RANSAC's generator and scratch */
    uint32_t n_refound;                /* updates redone at a pose re-found by RANSAC */
} rp_vo_mono_t;

/* Set up for rig (must outlive the estimator). RP_E_ARG (cam out of range, min_tracked < 6,
 * non-positive depth, depth sigma or dt, bad EKF params, a switch other than 0 or 1),
 * rp_rig_check's errors. */
rp_status_t rp_vo_mono_init(rp_vo_mono_t *vo, const rp_rig_t *rig, const rp_vo_mono_cfg_t *cfg);

/* Process one frame set (only camera cfg.cam's features are read). est (never NULL) receives
 * the pose mapped to the rig (cam1) frame; own (may be NULL) the camera's own pose
 * [l_kj, angles of r_kj] in world_k, with its velocity and covariance.
 * Returns as rp_vo_stereo_step: RP_OK (updated, or first frame), RP_E_TOO_FEW (no usable
 * features: prediction, RP_EST_LOST, the next frame re-initialises; a dark camera gives this),
 * RP_E_DIVERGED, the other failures of the start or update with their own code
 * (rp_vo_step_status), RP_E_ARG (malformed frame set: ignored). */
rp_status_t rp_vo_mono_step(rp_vo_mono_t *vo, const rp_frameset_t *fs, rp_estimate_t *est,
                            rp_estimate_t *own);

/* Map camera k's own pose (translation l_kj, rotation r_kj as angles) to the rig pose p_rig:
 * R_j = R_k r_kj R_k^T, d_j = R_k l_kj + D_k - R_j D_k. RP_E_ARG, RP_E_NAN. */
rp_status_t rp_vo_mono_to_rig(const rp_rig_t *rig, uint8_t k, const rp_real p_own[6],
                              rp_real p_rig[6]);

#ifdef __cplusplus
}
#endif

#endif /* RP_VO_MONO_H */
