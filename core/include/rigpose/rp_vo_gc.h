/*
 * rp_vo_gc.h - the generalised camera (`gc`): rigpose's own method for the non-overlapping
 * layout (beyond the paper, which fuses per-camera filters by rigidity constraints).
 *
 * One 12-state pose EKF (rp_ekf) takes the pixels of every tracked feature of every single
 * camera of the layout through eq. (2): the known offsets D_k and rotations R_k of the cameras
 * make the metric scale observable without any stereo matching. Each feature has its own
 * 3-state structure EKF (rp_struct, world position).
 *
 * Per frame set:
 *  1. Frame 0 (the world is cam1's frame now, pose exactly zero): every feature of every camera
 *     of the layout becomes a landmark, initialised "orthographically": on the plane z = depth
 *     (init_depth_m, in its camera) along its pixel's ray, with a covariance that is large along
 *     the ray (init_depth_sigma_m on z: depth unknown) and small across it (pixel noise).
 *  2. Later frames: EKF prediction, then the iterated update with every landmark's pixel. The
 *     point's own uncertainty is carried into the pose update as a weight:
 *     w = sigma^2 / (sigma^2 + l_max(J_M C J_M^T)), l_max the largest eigenvalue of the point
 *     covariance projected into the image at the predicted pose (worst direction). A landmark
 *     enters the pose update only once its depth is converged (its standard deviation along
 *     the ray under mature_frac of its range); until then it only feeds its structure EKF.
 *     While fewer than min_mature landmarks are converged (start-up), every landmark enters,
 *     weighted as above.
 *     With `one_point` the update is 1-point RANSAC (rp_ekf1pt.h): hypotheses from one
 *     observation of each of three cameras through the prior, the consensus and its rescued
 *     inliers update the filter, the others are left out (counted as gated). This is also gc's
 *     robust start: at frame 1 the landmarks' depths are still the assumed one (no metric
 *     structure for a minimal solver), but the filter's prior at the origin and three cameras'
 *     observations fix a hypothesis (one camera's alone leaves rotation across it and
 *     translation along it interchangeable, and a group that fits that ambiguity, such as an
 *     object static in another camera's image, could win).
 *     With `ransac`, once min_mature landmarks have converged (metric structure), an update
 *     that leaves most of the offered observations out (or fails with enough of them) says
 *     the prediction is wrong: the pose is re-found from the images by rig RANSAC over every
 *     camera (rp_ransac.h, gate on 2 sigma_px^2 as stereo's), and the update redone on its
 *     inliers from the prediction with the pose covariance widened by d d^T, d the gap to the
 *     re-found pose; kept if it uses at least half of the inliers (n_refound counts these).
 *  3. After the pose update each observed landmark's structure EKF takes its pixel at the
 *     updated pose, with the pose's projected uncertainty added to the pixel noise (the pose is
 *     taken as known, but not as exact).
 *  3b. (drop_odds > 0) Each observed landmark is judged in or out by this frame set's
 *     updates: one offered to the pose update by whether the update took it, a young one by
 *     whether its structure EKF's gate took its pixel. The drop test (rp_droptest.h, as
 *     stereo's) drops a landmark whose observations keep being left out (a moving object, a
 *     track slipped onto another surface), and its track is retired: not made a landmark
 *     again while its camera tracks it, so that the camera, short of landmarks, is topped up
 *     from the rest of its view. Judged only by an update that can judge tracks: min_mature
 *     landmarks converged (at the start and after a blackout the updates judge the assumed
 *     depth), the pose not re-found, most of what it was offered taken in and most of all
 *     the judged observations in (the test's premise; else the prediction or the map, not
 *     the tracks, is in doubt: after a blackout a frame set judged without it dropped 213 of
 *     389 landmarks at once).
 *  4. Features come and go: a landmark whose camera delivered an image without it is dropped
 *     (its track was lost); a camera that delivered no image at all keeps its landmarks. When a
 *     camera holds fewer than min_tracked landmarks, it is topped up from the *current* frame
 *     once the pose is updated: its untracked features are initialised as in 1 at the updated
 *     pose (no backtracking is needed: the new landmarks' depths are unknown anyway, and they
 *     enter the pose update only once converged). The across-ray covariance of a topped-up
 *     landmark includes the pose uncertainty.
 *  5. Reported covariance. The pose EKF treats the landmarks' errors as independent, but they
 *     are not (every landmark was placed from estimated poses and one assumed depth), so its
 *     own covariance is far too small. The estimate's covariance
 *     is the filter's plus the map's correlated errors as "consider" terms: scale_sigma^2 t t^T
 *     for the metric scale, and position / orientation drift growing with the frame count.
 *     These are calibrated on the paper's simulation (tests/test_vo_gc.c checks them).
 *  6. Metric scale (mscale_sigma > 0; beyond the paper; rp_vo_gc_scale.c). Steps 1-3 alone
 *     take the metric scale from the assumed depth, for good: landmarks are refined by
 *     parallax against the filter's own translations, so map and trajectory can be wrong by
 *     one common factor that no single frame shows. The map is therefore kept in map units: the offsets the filter projects
 *     with are D_k * mu (mu: map units per metre), output translations are divided by mu, new
 *     features start at init_depth_m * mu. Every ba_stride frames the updated pose and the
 *     pixels of ba_per_cam landmarks per camera become a keyframe (only pixels that their
 *     landmark's structure gate took in step 3: the frame's outliers stay out of the window;
 *     with them, 30 % gross outliers had every window refused); every ba_every keyframes
 *     (once RP_VO_GC_BA_MIN_KF are held) a window bundle adjustment in metres over the last
 *     ba_kf keyframes (rp_gcba.h; run in pieces, one per frame set, the piece of a frame set
 *     that re-found its pose in step 2 waiting for the next one, so that the two largest
 *     costs of the estimator do not add up) says which mu the window implies, and a scalar filter on
 *     mu (prior 1 +- mscale_sigma) takes it with its variance times ba_var_scale. Refused (counted in
 *     n_ba_rejected): a failed adjustment, one whose RMS residual stays over
 *     RP_VO_GC_BA_MAX_RMS ba.sigma_px, one that took no step (its first Gauss-Newton step
 *     raised the cost at every length rp_gcba_step tries, so it ends at the mu it started from
 *     and would confirm that mu with its
 *     own variance: on real tracks such windows locked mu at its prior), one more than
 *     RP_VO_GC_BA_GATE_SIGMA sigma from the
 *     current mu (after RP_VO_GC_BA_MAX_REFUSED such refusals in a row the current mu is the
 *     suspect: its variance goes back to the prior and the next one is taken).
 *     A taken adjustment also (a) moves each landmark with its camera's centre at the new
 *     offsets, (b) writes the window's solved poses back into the keyframes, (c) sets the
 *     filter's pose to the newest keyframe's solution, the map following rigidly, and
 *     (d) replaces the adjusted landmarks' positions and covariances by the solution's.
 *  7. RP_EST_SCALE_WEAK says the metric scale is poorly determined: while fewer than
 *     min_mature landmarks have converged; always without step 6 (the scale is the assumed
 *     depth's); with step 6 while mu's relative standard deviation is over scale_sigma, the
 *     scale error the reported covariance claims (before enough windows are fused, and for as
 *     long as the motion does not tell the unit: a straight drive without rotation moves every
 *     camera alike, so the offsets say nothing, no window is taken and mu keeps its prior).
 * Output: an rp_estimate_t, the pose of cam1 in the world (rp_frame.h).
 */
#ifndef RP_VO_GC_H
#define RP_VO_GC_H

#include "rp_droptest.h"
#include "rp_ekf.h"
#include "rp_ekf1pt.h"
#include "rp_frame.h"
#include "rp_gcba.h"
#include "rp_lmtab.h"
#include "rp_obs.h"
#include "rp_ransac.h"
#include "rp_rig.h"
#include "rp_struct.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint8_t n_cams;               /* cameras of the layout, 1..RP_MAX_CAMS */
    uint8_t cams[RP_MAX_CAMS];    /* their rig indices (distinct) */
    rp_ekf_params_t ekf;
    uint16_t min_tracked;         /* per camera: top up under this many landmarks (50) */
    rp_real init_depth_m;         /* assumed scene depth (camera z) of a new feature, m */
    rp_real init_depth_sigma_m;   /* its prior standard deviation, m */
    uint8_t init_on_sphere;       /* 0: new features on the plane z = init_depth_m of their
                                   * camera (the paper's "orthographic" plane); 1: on the sphere
                                   * of radius init_depth_m around the camera (depth measured
                                   * along the ray: a scene that surrounds the robot) */
    rp_real mature_frac;          /* a landmark enters the pose update once its standard
                                   * deviation along its ray is under this fraction of its range;
                                   * >= 1: every landmark enters at once */
    uint16_t min_mature;          /* fewer converged landmarks than this: all of them enter */
    rp_real default_dt_s;         /* frame interval used when timestamps are missing, s */
    rp_real max_eff_obs;          /* the map's errors are correlated (every landmark was placed
                                   * from estimated poses, at one assumed depth): the pose update
                                   * gets at most the information of this many nominal
                                   * observations (weights scaled down); <= 0: no cap */
    rp_real scale_sigma;          /* relative standard deviation of the map's metric scale: adds
                                   * scale_sigma^2 t t^T (t: translation since frame 0) to the
                                   * reported translation covariance (not to the filter's) */
    rp_real trans_drift_sigma;    /* position drift of the map, m per sqrt(frame): adds
                                   * trans_drift_sigma^2 * frame to the reported variance of each
                                   * translation (not to the filter's) */
    rp_real rot_drift_sigma;      /* orientation drift of the map, rad per sqrt(frame): adds
                                   * rot_drift_sigma^2 * frame to the reported variance of each
                                   * angle (not to the filter's) */
    rp_real mscale_sigma;         /* step 6, the metric scale from the offsets: prior relative
                                   * standard deviation of the map's unit in metres; 0: off (the
                                   * map's unit is the metre: the scale is the assumed depth's) */
    rp_real mscale_q;             /* its random walk: relative variance added per frame */
    uint8_t ba_stride;            /* frames between keyframes (>= 1 when step 6 is on) */
    uint8_t ba_kf;                /* keyframes per window, 3..RP_GCBA_MAX_KF */
    uint8_t ba_every;             /* adjust the window every this many keyframes, >= 1 */
    uint16_t ba_per_cam;          /* landmarks per camera kept in a keyframe, >= 8 (those whose
                                   * ids hash lowest: mostly the same ones in every keyframe) */
    rp_real ba_var_scale;         /* a window's scale variance is multiplied by this before it
                                   * is fused (windows overlap: they share observations), >= 1 */
    rp_gcba_cfg_t ba;             /* the adjustment (rp_gcba.h) */
    uint8_t one_point;            /* 1: every pose update through 1-point RANSAC (rp_ekf1pt.h);
                                   * 0: the plain gated update */
    uint8_t ransac;               /* 1: the pose re-found by rig RANSAC when most observations
                                   * are left out (step 2); 0: never */
    rp_real drop_odds;            /* step 3b: a landmark whose observations the updates keep
                                   * leaving out is dropped at these odds (rp_droptest.h) and
                                   * its track retired; 0: off (every landmark kept). Default
                                   * RP_DROP_ODDS_ONE: one observation per frame set, so the
                                   * square of stereo's odds, which sees two */
} rp_vo_gc_cfg_t;

/* Step 6's fixed rules (rp_vo_gc_scale.c). */
#define RP_VO_GC_BA_MIN_KF 3            /* keyframes a window needs before it is adjusted */
#define RP_VO_GC_BA_MAX_RMS RP_C(1.5)   /* refuse an adjustment whose RMS residual is over this
                                         * times ba.sigma_px (unconverged or wrong) */
#define RP_VO_GC_BA_GATE_SIGMA RP_C(4.0) /* refuse a window's mu further than this many sigma
                                          * (both variances) from the current mu */
#define RP_VO_GC_BA_MAX_REFUSED 2       /* after this many such refusals in a row the current
                                         * mu's variance goes back to its prior */

/* Defaults: the paper's threshold of 50, plane at 1 m +- 0.3 m, mature at 2 % of the range
 * (at least 50 mature landmarks, else all enter), no information cap, reported scale sigma 2 %,
 * position drift 6e-5 m and orientation drift 1e-4 rad per sqrt(frame), 1/30 s; step 6 on:
 * map unit prior 1 +- 0.3, no random walk, a keyframe every 4 frames with 80 landmarks per
 * camera, windows of 6 keyframes adjusted every 2 keyframes (2 Gauss-Newton iterations), the
 * window's variance times 3; 1-point RANSAC and the rig RANSAC re-find on. */
rp_vo_gc_cfg_t rp_vo_gc_default_cfg(void);

#define RP_VO_GC_EMPTY_ID RP_IDMAP_EMPTY /* not a feature id */
#define RP_VO_GC_MAX_OBS (RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM)

typedef struct {
    const rp_rig_t *rig;
    rp_rig_t rig_m;                        /* the rig in map units: offsets D_k * mu */
    rp_real mu;                            /* map units per metre (1 unless mscale_sigma > 0) */
    rp_real mu_var;                        /* its variance */
    rp_gcba_t ba;                          /* step 6's keyframe window */
    uint8_t kf_since;                      /* keyframes since the last adjustment */
    uint16_t n_ba;                         /* adjustments fused since the first frame */
    uint16_t n_ba_rejected;                /* adjustments that failed or were refused */
    uint8_t ba_refused_run;                /* converged ones refused in a row */
    rp_gcba_result_t ba_last;              /* the last adjustment's result */
    rp_gcba_obs_t kf_obs[RP_GCBA_MAX_OBS_KF]; /* scratch: a keyframe's observations */
    uint32_t kf_hash[RP_MAX_FEATS_PER_CAM];   /* scratch: one camera's id hashes */
    uint16_t kf_feat[RP_MAX_FEATS_PER_CAM];   /* and their feature indices */
    rp_vo_gc_cfg_t cfg;
    rp_ekf_t ekf;
    rp_lmtab_t lm;                         /* landmarks: world points in map units; group =
                                            * the camera that sees it; mark = observed this
                                            * frame */
    uint8_t mature[RP_IDMAP_MAX_SLOTS];    /* by slot of lm: 1 once the landmark's depth has
                                            * converged (it enters the pose update) */
    uint32_t taken[RP_IDMAP_MAX_SLOTS];    /* by slot of lm: frame + 1 of the last pixel its
                                            * structure EKF's gate took (step 3), or of the
                                            * one that placed it (a keyframe holds this
                                            * frame's taken ones, step 6) */
    uint32_t frame;                        /* frames processed */
    int64_t prev_utime;
    rp_obs_t obs[RP_VO_GC_MAX_OBS];        /* scratch: this frame's observations */
    uint8_t used[RP_VO_GC_MAX_OBS];
    uint8_t in_pose[RP_VO_GC_MAX_OBS];     /* scratch: obs[i] offered to the pose update */
    uint32_t obs_id[RP_VO_GC_MAX_OBS];     /* scratch: landmark id of obs[i] */
    rp_obs_t pobs[RP_VO_GC_MAX_OBS];       /* scratch: the pose update's subset */
    uint8_t pused[RP_VO_GC_MAX_OBS];
    uint8_t inl[RP_VO_GC_MAX_OBS];         /* scratch: rig RANSAC's inliers among pobs */
    rp_ekf_t ekf_pred;                     /* scratch: the prediction, for a re-found update */
    rp_ekf1pt_t op;                        /* 1-point RANSAC's generator and scratch */
    rp_ransac_t rs;                        /* rig RANSAC's generator and scratch */
    uint32_t n_refound;                    /* updates redone at a pose re-found by rig RANSAC */
    rp_droptest_t drop;                    /* step 3b's test, by slot of lm */
    uint16_t obs_slot[RP_VO_GC_MAX_OBS];   /* scratch: obs[i]'s landmark slot (select_for_pose;
                                            * RP_IDMAP_MAX_SLOTS: none) */
    uint8_t judged_in[RP_VO_GC_MAX_OBS];   /* scratch: obs[i] taken in (pose or structure) */
    uint8_t keep[RP_VO_GC_MAX_OBS];        /* scratch: obs[i]'s landmark is kept */
    rp_idmap_t retired;                    /* step 3b's retired tracks (group: camera) */
    uint32_t n_dropped;                    /* landmarks step 3b dropped since the start */
} rp_vo_gc_t;

/* *is_retired = 1 if track id is one of step 3b's retired tracks (rp_vo_gc.h), else 0.
 * RP_E_ARG (NULL). */
rp_status_t rp_vo_gc_is_retired(const rp_vo_gc_t *vo, uint32_t id, uint8_t *is_retired);

/* Set up the estimator for rig (which must outlive it) with cfg. The world is cam1's frame at
 * the first frame set. RP_E_ARG (bad config: no camera, index out of range or repeated,
 * min_tracked < 6, non-positive depth, sigma or dt, negative mature_frac, a switch other than
 * 0 or 1), rp_rig_check's
 * errors, rp_ekf_init's errors. */
rp_status_t rp_vo_gc_init(rp_vo_gc_t *vo, const rp_rig_t *rig, const rp_vo_gc_cfg_t *cfg);

/* Process one frame set; fills est (never NULL) whatever happens.
 * RP_OK: pose updated, or first frame initialised (est->flags say which).
 * RP_E_TOO_FEW: too few features: est carries the prediction with RP_EST_LOST. Other failures
 *   of the update keep their own code with the same outcome (rp_vo_step_status).
 * RP_E_DIVERGED: the EKF rejected its update (covariance reset), est as predicted.
 * RP_E_ARG: malformed frame set (count over the limit, features in a camera not in the rig);
 *   it is ignored. Non-finite pixels are skipped. */
rp_status_t rp_vo_gc_step(rp_vo_gc_t *vo, const rp_frameset_t *fs, rp_estimate_t *est);

#ifdef __cplusplus
}
#endif

#endif /* RP_VO_GC_H */
