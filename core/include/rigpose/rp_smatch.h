/*
 * rp_smatch.h - left-right matching of a stereo pair's features from the images, under the
 * pair's fixed geometry (issue 4 item 2).
 *
 * The matcher reads the images as pyramids (rp_pyr_t, rp_pyr_build: the trackers hold them).
 * For each feature of camera a (the "left" one) it walks the epipolar curve of its pixel in
 * camera b's image: the ray of the pixel (undistorted through camera a) is cut at inverse
 * depths from 1 / min_depth_m to 1 / max_depth_m, the points projected (with distortion) into
 * camera b, so the walk follows the true (curved) epipolar line of distorted images. A patch
 * score compares the windows (ZNCC: integer sums of Q5 grey levels, Q15 result):
 *   0. coarse: at pyramid level search_level, one step per level pixel, window half side
 *      half_win - 1 (at least 2), integer sums in one pass; fine: at level 0, one step per
 *      pixel around the coarse best, window half side half_win, the template sampled at the
 *      feature's sub-pixel position;
 *   1. best fine score >= min_zncc_q15, and the best other local maximum of the coarse scores
 *      (farther than 2 steps from the best) lower by at least uniq_margin_q15 (uniqueness);
 *   2. left-right consistency: the same search from the right pixel back along its epipolar
 *      curve in camera a must land within lr_max_px of the left feature;
 *   3. sub-pixel: parabola through the scores around the best step, then a 1-D Lucas-Kanade
 *      refinement along the curve's direction (mean-removed patches, bilinear weights Q14,
 *      intensities Q5, int64 sums), at most subpix_iter iterations, then a 2-D one from there
 *      (gain-normalised, at most 2 subpix_iter iterations; the 1-D match stays if it leaves
 *      1.5 px or the window is an edge): a match along the curve alone takes the calibration's
 *      error across the curve up as a shift along it, e cot theta on an edge slanted by theta,
 *      whose sign a mirror image flips;
 *   4. the refined match passes the symmetric epipolar check (rp_stereo_epipolar_px) within
 *      max_epipolar_px.
 * A matched feature of camera b carries the SAME id as the feature of camera a (the stereo
 * estimator's contract, rp_frame.h). All state is in a caller-owned rp_smatch_t (no heap).
 */
#ifndef RP_SMATCH_H
#define RP_SMATCH_H

#include "rp_frame.h"
#include "rp_opts.h"
#include "rp_rig.h"
#include "rp_status.h"
#include "rp_stereo.h"
#include "rp_track.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Most steps along one epipolar curve (longer curves are sampled more coarsely). */
#ifndef RP_SMATCH_MAX_STEPS
#define RP_SMATCH_MAX_STEPS 1024
#endif

typedef struct {
    uint8_t half_win;         /* patch half side, px: (2 h + 1)^2 window, 2..7 (4: 9x9) */
    int16_t min_zncc_q15;     /* accept a best score at least this, Q15 (0.8 = 26214) */
    int16_t uniq_margin_q15;  /* second peak must be lower by this, Q15 (0.05 = 1638) */
    uint16_t min_std;         /* reject a left patch whose grey-level standard deviation is
                               * under this (flat, no texture), grey levels (4) */
    rp_real min_depth_m;      /* search range along the ray of camera a's pixel (camera a's */
    rp_real max_depth_m;      /*   z), m (0.2 .. 100) */
    rp_real lr_max_px;        /* left-right consistency tolerance, px (1.0) */
    rp_real max_epipolar_px;  /* final epipolar check, px (1.0) */
    uint8_t subpix_iter;      /* 1-D LK iterations after the parabola fit, 0 = parabola only (5) */
    uint8_t search_level;     /* pyramid level of the coarse search (0 = full resolution, the
                               * default: a coarser level's pixel centres are not a mirror
                               * image's when the width is even, and its half-size windows pick
                               * other peaks; clipped to the pyramids' levels) */
} rp_smatch_cfg_t;

/* Counts of one rp_smatch_pair call: every input feature ends in exactly one bucket. */
typedef struct {
    uint16_t n_in;        /* features of camera a offered */
    uint16_t n_matched;   /* matched (written out, unless past the cap: RP_E_FULL) */
    uint16_t n_outside;   /* epipolar curve (within the depth range) misses camera b's image,
                           * or the feature's window leaves camera a's image */
    uint16_t n_flat;      /* left patch without texture (min_std) */
    uint16_t n_low_score; /* best ZNCC under min_zncc_q15 */
    uint16_t n_ambiguous; /* failed the uniqueness test */
    uint16_t n_lr_fail;   /* failed the left-right consistency check */
    uint16_t n_epi_fail;  /* refined match off the epipolar line (or no undistortion) */
} rp_smatch_stats_t;

/* One sample of an epipolar curve: pixel in Q16 (level 0 coordinates). */
typedef struct {
    int32_t u_q16, v_q16;
} rp_smatch_pt_t;

/* Caller-owned matcher (a few tens of KB: allocate it statically or inside rp_pipe_t). */
typedef struct {
    rp_smatch_cfg_t cfg;
    rp_smatch_pt_t curve[RP_SMATCH_MAX_STEPS]; /* scratch: the current epipolar curve */
    int16_t score[RP_SMATCH_MAX_STEPS];        /* scratch: ZNCC per step, Q15 */
} rp_smatch_t;

/* Defaults: 9x9 window, ZNCC >= 0.8, margin 0.05, std >= 4, depths 0.2 .. 100 m, left-right
 * 1 px, epipolar 1 px, 5 LK iterations, coarse search at level 1. RP_E_ARG if cfg is NULL. */
rp_status_t rp_smatch_default_cfg(rp_smatch_cfg_t *cfg);

/* Resets sm with cfg (copied). RP_E_ARG: NULL, or a value out of range (half_win outside
 * 2..7, scores outside 0..32767, depths not 0 < min < max, tolerances not > 0). */
rp_status_t rp_smatch_init(rp_smatch_t *sm, const rp_smatch_cfg_t *cfg);

/* Match the n_a features fa of camera sp->a (image pyramid pyr_a) into camera sp->b's image
 * (pyramid pyr_b).
 * Matches go to fb (at most cap, *n_b of them), in the order of fa, each with its fa id and its
 * pixel in camera b. stats (may be NULL) receives the counts.
 * Returns:
 *   RP_OK           done (*n_b may be 0: nothing matched)
 *   RP_E_ARG        NULL pointer; a pyramid without levels or whose level 0 is not the size
 *                   of the rig's calibration of its camera; sp not a pair of the rig's cameras
 *                   (nothing written)
 *   RP_E_NAN        a feature of fa is not finite (it is skipped, the others are matched)
 *   RP_E_FULL       more matches than cap: the first cap written */
rp_status_t rp_smatch_pair(rp_smatch_t *sm, const rp_rig_t *rig, const rp_stereo_pair_t *sp,
                           const rp_pyr_t *pyr_a, const rp_pyr_t *pyr_b,
                           const rp_feat_t *fa, uint16_t n_a, rp_feat_t *fb, uint16_t cap,
                           uint16_t *n_b, rp_smatch_stats_t *stats);

#ifdef __cplusplus
}
#endif

#endif /* RP_SMATCH_H */
