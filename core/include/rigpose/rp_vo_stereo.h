/*
 * rp_vo_stereo.h - the overlapping layout (paper section 2.2.1): stereo pairs, one pose EKF.
 *
 * Per frame set:
 *  1. At the first frame, and whenever a pair's tracked landmarks fall under min_tracked, the
 *     pair's matches (a feature id present in both of its cameras) are checked against the
 *     fixed fundamental matrix, triangulated, checked (depth range, reprojection error in both
 *     cameras) and stored as world landmarks. A re-initialisation backtracks one frame, as the
 *     paper does: it triangulates the previous frame set's matches at the previous pose
 *     estimate, then processes the current frame with them.
 *  2. At the second frame the pose EKF is started from Lowe's method on all correspondences
 *     (with `ransac`: on the inliers of a rig RANSAC over every camera, rp_ransac.h; the
 *     others are left out and their landmarks dropped). A pose RANSAC finds (here and when
 *     it is re-found, step 3) is refined by Lowe's method with Cauchy weights on the inliers'
 *     own residual scale (their median, at most RANSAC's sigma): RANSAC's gate is set for the
 *     worst pixel noise assumed, and points of a moving object a pixel or two off inside it
 *     would otherwise draw the start, which the map keeps.
 *  3. Every later frame: EKF prediction, then the iterated update with the pixels of every
 *     tracked landmark in every camera of the layout (eqs. 1-2). (beyond the paper) If the
 *     update's Mahalanobis gate rejects most of one pair's observations, the prediction was
 *     off along a direction the other pair hardly sees: the update is redone from the same
 *     prediction with its pose covariance widened by the gap to Lowe's pose from all
 *     observations, and kept if it uses more of them (n_retried counts these). With `ransac`
 *     the same happens when the gate rejects most of all observations, or the update fails
 *     with enough of them, and the pose is re-found from the images: rig RANSAC over every
 *     camera, Lowe's method on its inliers, and the filter restarted there (pose and its
 *     covariance from Lowe's method, velocity from the previous pose over dt); the outliers'
 *     landmarks are dropped (n_refound counts these). When the gate rejected most of one
 *     pair, RANSAC's pose is taken if it holds more observations than the update kept, or fits
 *     all of them better than the update's posterior by more than a pose error at the pixel
 *     noise explains: MSAC cost (rp_ekf1pt_cost) lower by over chi2(6 dof, 99.9 %) sigma_px^2.
 *     (A moving object holding most of one pair's features can draw the update along the
 *     other pair's weak direction, where that pair's features stay inside the gate, a pixel
 *     off: more of them held, a worse fit.)
 *     With `one_point` the update is 1-point RANSAC (rp_ekf1pt.h) instead of the plain gated
 *     one: hypotheses from single observations through the prior, the low-innovation
 *     consensus updates, the high-innovation inliers are rescued after it; observations left
 *     out count as gated (their landmarks are dropped), and "most outside the gate" means most
 *     left out of that consensus.
 *  4. (beyond the paper) Each landmark's structure EKF takes the frame's observations at the
 *     updated pose, so the structure improves instead of staying at its first triangulation.
 *  5. (beyond the paper, `add_landmarks`) Each pair's matches that are not landmarks yet (new
 *     features matched at their birth since, failed checks before, not retired) are
 *     triangulated at the updated pose with the same checks and added: the map follows the
 *     view instead of running down to min_tracked and being rebuilt at once, which on a real
 *     clip happened every 30-40 frames and moved the trajectory each time.
 *  A landmark missing from a frame (its track lost in both cameras) is dropped for good.
 */
#ifndef RP_VO_STEREO_H
#define RP_VO_STEREO_H

#include "rp_droptest.h"
#include "rp_ekf.h"
#include "rp_ekf1pt.h"
#include "rp_frame.h"
#include "rp_lmtab.h"
#include "rp_lowe.h"
#include "rp_obs.h"
#include "rp_ransac.h"
#include "rp_rig.h"
#include "rp_stereo.h"
#include "rp_struct.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint8_t n_pairs;                /* 1..RP_MAX_PAIRS */
    uint8_t pair_a[RP_MAX_PAIRS];   /* first camera of each pair */
    uint8_t pair_b[RP_MAX_PAIRS];   /* second camera of each pair */
    rp_ekf_params_t ekf;
    uint16_t min_tracked;           /* per pair: re-initialise under this many landmarks (50) */
    rp_real max_epipolar_px;        /* reject a match farther from its epipolar line, pixels */
    rp_real min_depth_m;            /* accepted triangulated depth range (camera a's z), m */
    rp_real max_depth_m;
    rp_real max_reproj_px;          /* reject a triangulation with a larger reprojection error */
    rp_real default_dt_s;           /* frame interval used when timestamps are missing, s */
    rp_real max_pair_skew_s;        /* a pair whose two images were captured farther apart in
                                     * time (stamps and clock offsets) makes no new landmarks
                                     * that set (RP_EST_UNSYNCED), s: the matcher and the
                                     * triangulation take the two as simultaneous */
    uint8_t refine_structure;       /* 1: a structure EKF per landmark refines its position with
                                     * every later observation (beyond the paper, which keeps the
                                     * first triangulation); 0: the paper's fixed structure */
    uint8_t ransac;                 /* 1: the pose is found by rig RANSAC (rp_ransac.h) at the
                                     * start and re-found by it when the prediction is wrong
                                     * (beyond the paper); 0: Lowe's method on everything */
    uint8_t one_point;              /* 1: every update through 1-point RANSAC (rp_ekf1pt.h);
                                     * 0: the plain gated update */
    rp_real drop_odds;              /* a landmark is dropped when the odds that its track
                                     * went wrong, from the record of its observations left out
                                     * of and taken into the updates against this frame set's
                                     * share left out, exceed this (a sequential test, below);
                                     * > 1 */
    uint8_t retry_triangulation;    /* 1: a match of a (re-)initialisation that failed the
                                     * epipolar or triangulation checks is tried again in the
                                     * next frame sets while both cameras track it (below); 0:
                                     * only at the next (re-)initialisation */
    uint8_t retire_outliers;        /* 1: the track of a landmark dropped as an outlier is not
                                     * triangulated again while it is tracked (below); 0: a
                                     * re-initialisation takes every matched track */
    uint8_t add_landmarks;          /* 1: every frame set (step 5), each pair's matches that are
                                     * not landmarks yet are triangulated at the updated pose and
                                     * added (beyond the paper); 0: only at (re-)initialisations
                                     * and as retried failed matches, as the paper's map */
} rp_vo_stereo_cfg_t;

/* Defaults: rp_ekf_default_params with plant noise q_trans = 3 m^2/s^3, q_rot = 3 rad^2/s^3
 * (config/README.md says why); the paper's threshold of 50, 1.5 px epipolar band,
 * 0.05..100 m, 1.5 px, 1/30 s, structure refinement on, rig RANSAC on, 1-point RANSAC on (its
 * cost: config/README.md), landmarks dropped at odds of 100 to 1, failed matches retried,
 * outlier tracks retired, new matches added as landmarks every frame set.
 * No pairs (n_pairs = 0): the caller
 * (or rp_pipe_default_cfg) names them. */
rp_vo_stereo_cfg_t rp_vo_stereo_default_cfg(void);

#define RP_VO_EMPTY_ID RP_IDMAP_EMPTY /* not a feature id */

/* Retired tracks (cfg.retire_outliers). A KLT track follows one surface point, so a track whose
 * landmark an update dropped as an outlier (a moving object, foliage, an occlusion edge) would
 * bring the same wrong point back at the pair's next re-initialisation: a moving object that
 * stays in view (one that moves with the rig) then refills the map every few frames. Such a
 * track is retired: never triangulated again while either camera of its pair tracks it (its id
 * leaves the list when both have lost it; a camera without features in a set, no image or a
 * blank one, loses nothing). Only an update that can judge tracks retires them: one whose
 * inliers are most of the observations, that left no pair mostly out (that judges the
 * prediction, not the tracks: rp_vo_stereo.c, pair_rejected) unless the rig RANSAC re-find it
 * then runs found no larger consensus (a moving object that fills most of one pair's view) and,
 * on a rig of several pairs,
 * whose inliers come from more than one pair (a consensus held by one pair alone may itself be
 * the moving object). The list holds RP_VO_RETIRED_MAX ids (when full, the first listed makes
 * room), found through a hash of twice that many cells. The front end keeps tracking a retired
 * track: its place in the image stays taken, so the detector does not put a new feature on the
 * same spot of the object (dropping them instead was measured worse: the object's freed area
 * filled with new tracks that the next re-initialisation took in). */
/* Dropping a landmark (cfg.drop_odds; rp_droptest.h, shared with gc). An update leaves out an observation either because its
 * landmark's track went wrong (a moving object, a track slipped onto another surface: its
 * observations then stay out, but for the chance RP_DROP_PASS that one falls inside the
 * consensus) or because a sound track's pixel read wrong once, at the rate eps at which this
 * frame set's update left out the observations of landmarks that the previous update took in
 * (Krichevsky-Trofimov estimate, at most 1/2: the consensus is a majority; from all
 * observations while fewer than ekf.min_features have such a past). Page's CUSUM test of
 * "wrong" against "sound" on each landmark's log-likelihood ratio,
 *   S = max(0, S + sum over its observations in this frame set of
 *                  log((1 - RP_DROP_PASS) / eps) if left out,
 *                  log(RP_DROP_PASS / (1 - eps)) if taken in),
 * drops it when S > log(cfg.drop_odds). On a clean frame set (eps a few %) a landmark left out
 * in both cameras of its pair goes at once, as a moving object's do (its landmarks are left
 * out from their first update on, so they do not raise eps); a landmark left out in one camera
 * only goes after several frame sets of it; under pixel outliers drawn anew every frame (eps
 * 30 %) it takes three frame sets in a row of both cameras left out, which a sound track meets
 * rarely (eps^6). */

/* Failed matches tried again (cfg.retry_triangulation). A (re-)initialisation triangulates
 * every match of its pair; one whose two pixels fail its checks at that frame set (a pixel
 * read wrong once, the other camera's track momentarily off) is not a landmark until the
 * pair's next re-initialisation, which comes only when the pair runs short. Such a match is
 * kept on a list (RP_MAX_FEATS_PER_CAM per pair, sorted by id, with the two pixels that failed
 * it and the pose they were seen at) and tried again, with the same checks, at every later
 * frame set's updated pose while both cameras track it; the list is replaced at the next
 * (re-)initialisation, and with add_landmarks (step 5) at every frame set, by that frame set's
 * failures with their pixels then. A match that is wrong stays wrong and keeps failing. One that succeeds
 * is placed at the later pose, whose error it carries, and then takes its first two pixels
 * through its structure EKF at their pose (the gate refuses the wrong one): the right one's ray
 * ties it to the pose the map was anchored at. */
#define RP_VO_RETIRED_MAX (RP_MAX_PAIRS * RP_MAX_FEATS_PER_CAM)
#define RP_VO_RETIRED_CELLS (2u * RP_VO_RETIRED_MAX)
RP_STATIC_ASSERT(RP_VO_RETIRED_CELLS <= 65535, "retired tracks are counted in uint16_t");

/* A failed match (cfg.retry_triangulation): its id and its two pixels (camera a, b) in the
 * frame set that failed it. */
typedef struct {
    uint32_t id;
    rp_real uv[2][2];
} rp_vo_retry_t;

typedef struct {
    const rp_rig_t *rig;
    rp_vo_stereo_cfg_t cfg;
    rp_stereo_pair_t pair[RP_MAX_PAIRS];
    rp_ekf_t ekf;
    rp_ekf_t ekf_pred;                  /* scratch: the prediction, for a retried update */
    uint32_t n_retried;                 /* updates redone because the gate rejected most of a
                                         * pair or of all (rp_vo_stereo.c, predict_update) */
    uint32_t n_refound;                 /* of those, poses re-found by rig RANSAC */
    uint32_t refind_inl;                /* this step: rig RANSAC's inliers when the re-find
                                         * ran and found a pose, else 0 */
    uint8_t skewed;                     /* this step: a pair refused (max_pair_skew_s) */
    uint8_t start_near;                 /* first frame set: a pair was at the state's time
                                         * (RP_VO_START_SKEW_S) */
    rp_ransac_t rs;                     /* rig RANSAC's generator and scratch */
    rp_ekf1pt_t op;                     /* 1-point RANSAC's generator and scratch */
    uint8_t inl[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM]; /* scratch: RANSAC's inliers */
    rp_real res2[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM]; /* scratch: squared residuals, px^2 */
    rp_real sel2[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM]; /* scratch: the inliers' (selection) */
    uint8_t keep[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM];/* scratch: obs[i]'s landmark is kept */
    uint16_t obs_slot[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM]; /* scratch: obs[i]'s landmark slot
                                                            * (RP_IDMAP_MAX_SLOTS: none) */
    rp_droptest_t drop;                 /* the drop test's state per landmark slot (above) */
    rp_vo_retry_t retry[RP_MAX_PAIRS][RP_MAX_FEATS_PER_CAM]; /* failed matches (above), by id */
    uint16_t n_retry[RP_MAX_PAIRS];
    rp_pose_lin_t retry_pl[RP_MAX_PAIRS]; /* the pose of their pixels (camera a's time) */
    rp_vo_retry_t retry_scratch[RP_MAX_FEATS_PER_CAM]; /* scratch of the triangulation */
    uint32_t retired_id[RP_VO_RETIRED_MAX]; /* retired tracks (above) */
    uint8_t retired_pair[RP_VO_RETIRED_MAX]; /*   and the pair each belongs to */
    uint16_t n_retired;
    uint32_t retired_cell[RP_VO_RETIRED_CELLS]; /* their ids hashed (open addressing) */
    uint8_t retired_keep[RP_VO_RETIRED_MAX]; /* scratch of the pruning */
    rp_lmtab_t lm;                      /* landmarks: world points (m); group = the pair that
                                         * triangulated it; mark = observed (and not gated)
                                         * in the current frame */
    rp_frameset_t prev;                 /* previous frame set, for backtracking */
    rp_real prev_p[6];                  /* pose estimate at the previous frame */
    uint32_t frame;                     /* frames processed */
    int64_t prev_utime;
    rp_obs_t obs[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM]; /* scratch: this frame's observations */
    uint8_t used[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM];
    uint32_t obs_id[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM]; /* scratch: landmark id of obs[i] */
    uint32_t match_key[2 * RP_MAX_FEATS_PER_CAM];        /* scratch: id -> feature index map */
    uint16_t match_idx[2 * RP_MAX_FEATS_PER_CAM];        /*   of one camera, for matching */
} rp_vo_stereo_t;

/* Set up the estimator for rig (which must outlive it) with cfg. The world is cam1's frame at
 * the first frame set. RP_E_ARG (bad config: no pair, camera index out of range, a camera in
 * two pairs, a switch other than 0 or 1), rp_rig_check's errors, rp_stereo_pair_init's errors. */
rp_status_t rp_vo_stereo_init(rp_vo_stereo_t *vo, const rp_rig_t *rig,
                              const rp_vo_stereo_cfg_t *cfg);

/* Process one frame set; fills est (never NULL) whatever happens.
 * RP_OK: pose updated, or first frame initialised (est->flags say which).
 * RP_E_TOO_FEW: no usable structure or too few features: est carries the prediction with
 *   RP_EST_LOST; the next frame set tries to re-initialise. Other failures of the start or the
 *   update keep their own code with the same outcome (rp_vo_step_status: RP_E_DIVERGED,
 *   RP_E_NO_CONVERGE, RP_E_SINGULAR, RP_E_NAN, ...).
 * RP_E_NAN / RP_E_ARG: the frame set was malformed (non-finite pixel, count over the limit);
 *   the offending features are skipped when possible, otherwise the frame set is ignored. */
rp_status_t rp_vo_stereo_step(rp_vo_stereo_t *vo, const rp_frameset_t *fs, rp_estimate_t *est);

/* *is_retired = 1 if track id is one of the retired tracks (above), else 0.
 * RP_E_ARG (NULL vo or is_retired). */
rp_status_t rp_vo_stereo_is_retired(const rp_vo_stereo_t *vo, uint32_t id, uint8_t *is_retired);

#ifdef __cplusplus
}
#endif

#endif /* RP_VO_STEREO_H */
