/*
 * rp_ransac.h - the rig pose from 2-D/3-D correspondences containing gross outliers: minimal-
 * solver RANSAC over all cameras of the rig, then Lowe's method on the consensus. Needs no prior
 * pose. Deterministic: the generator's state lives in the caller's rp_ransac_t.
 *
 * The algorithm (equation numbers: (1), (2) of the Ragab paper, rp_rig.h; Lambda Twist's in
 * rp_p3p.h):
 *  1. Every observation with w > 0 is unprojected once through its camera's distortion model
 *     (rp_cam_unproject) to a unit bearing in camera k. Cameras with at least 3 such
 *     observations are "sampleable".
 *  2. Sample: one usable observation of a sampleable camera uniformly, i.e. camera k with
 *     probability n_k / n_s (its share of the sampleable observations), then two more distinct
 *     observations of the same camera. Why one camera, weighted by its count: P3P needs its three
 *     rays through one centre; weighting by count treats every observation alike (the same
 *     inlier prior for each) and draws more from cameras whose wider spread of points gives
 *     better-conditioned triangles; a camera that sees nothing but outliers costs only its
 *     share of the draws.
 *  3. Hypotheses: P3P (Lambda Twist) gives up to four world -> camera-k poses Xc = Rc M + tc.
 *     Eq. (2), P = R_k^T R_j^T (M - d_j - R_j D_k), identifies Rc = R_k^T R_j^T and
 *     tc = -R_k^T (R_j^T d_j + D_k), so the rig pose is
 *         R_j = (R_k Rc)^T,      d_j = -R_j (R_k tc + D_k),
 *     and the angles (alpha, beta, gamma) of R_j (rp_rot_to_angles).
 *  4. Score: every usable observation of every camera is projected through eq. (2) at the
 *     hypothesis (rp_rig_project); it is an inlier when w |uv - h_k(p, M)|^2 <= thresh^2 with
 *     thresh = sigma_px sqrt(chi2) (chi2: the quantile of the chi-square law with 2 degrees of
 *     freedom; 9.21 keeps 99 % of the inliers). A point behind its camera is an outlier. The
 *     hypothesis with the most inliers wins; ties go to the lower truncated cost
 *     sum min(w e^2, thresh^2) (MSAC's).
 *  5. Local optimisation (LO-RANSAC: O. Chum, J. Matas, J. Kittler, "Locally Optimized
 *     RANSAC", DAGM 2003), when local_opt: each new best with at least min_inliers inliers is
 *     refined at once by Lowe's method on its inliers and re-scored, kept if better. A P3P pose
 *     from three noisy points gathers only part of the inliers; counting from that part
 *     underestimates the inlier ratio and overestimates N. Measured on rp_sim (6 cameras,
 *     1714 observations, 60 % outliers): 317 -> 193 draws per solve, 18-23 -> 10-13 ms (host,
 *     -O2), the same pose error.
 *     Adaptive count: after each better hypothesis, with k_c of the best's inliers among camera
 *     c's n_c usable observations, the probability that one draw is all-inlier is
 *         s = sum_c (n_c / n_s) C(k_c, 3) / C(n_c, 3)
 *     (for one camera, or equal ratios, s ~ w^3 with w the inlier ratio), and
 *         N = log(1 - confidence) / log(1 - s),
 *     capped at max_iter (and at least min_iter). By Jensen's inequality s >= w^3 for the global
 *     ratio w, so N is never more than the textbook log(1-p)/log(1-w^3): fewer draws when the
 *     inliers sit in a few cameras (e.g. one camera sees the scene, the others only outliers).
 *  6. Refine: Lowe's method (rp_lowe_solve) on the best hypothesis's inliers from that
 *     hypothesis, re-score at the refined pose, and again (refine_rounds times at most, or until
 *     the inlier set stops changing). The refined pose is kept only if it has at least as many
 *     inliers as the hypothesis.
 */
#ifndef RP_RANSAC_H
#define RP_RANSAC_H

#include "rp_lowe.h"
#include "rp_obs.h"
#include "rp_opts.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Observations one call accepts: every camera full. */
#define RP_RANSAC_MAX_OBS (RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM)

typedef struct {
    rp_real sigma_px;    /* pixel noise of a w = 1 observation, px (default 1.0) */
    rp_real chi2;        /* inlier gate: chi-square quantile, 2 dof (default 9.21: 99 %) */
    rp_real confidence;  /* probability that an all-inlier sample is drawn (default 0.999) */
    uint32_t min_iter;   /* draws at least (default 16) */
    uint32_t max_iter;   /* draws at most (default 2000) */
    uint32_t min_inliers;/* consensus needed to succeed (default 8; at least 4) */
    uint8_t refine_rounds; /* Lowe + re-score rounds (default 3; 0: the hypothesis as it is) */
    uint8_t local_opt;   /* 1: Lowe on every new best's inliers during the draws (default 1) */
    rp_lowe_params_t lowe; /* Lowe's method on the inliers (default rp_lowe_default_params) */
} rp_ransac_params_t;

/* Every default, the only place they are written. */
rp_ransac_params_t rp_ransac_default_params(void);

/* Caller-owned state: the generator and the scratch of one call (with the default limits about
 * 270 KB in double, 145 KB in float; make it static). Seed it once with rp_ransac_seed; the
 * generator then advances call after call, so a fixed sequence of inputs gives a fixed sequence
 * of outputs. */
typedef struct {
    uint64_t rng;                            /* xorshift64* state, never 0 */
    rp_real ray[RP_RANSAC_MAX_OBS][3];       /* unit bearings in their camera */
    uint32_t order[RP_RANSAC_MAX_OBS];       /* usable observations grouped by camera */
    uint32_t cam_start[RP_MAX_CAMS + 1];     /* camera c's are order[cam_start[c] .. c+1) */
    uint8_t usable[RP_RANSAC_MAX_OBS];       /* 1: w > 0 and unprojectable */
    uint8_t mask[RP_RANSAC_MAX_OBS];         /* the inlier mask when the caller passes none */
    uint8_t cand[RP_RANSAC_MAX_OBS];         /* a refined pose's inlier mask, before it is kept */
    rp_obs_t sel[RP_RANSAC_MAX_OBS];         /* the inliers handed to Lowe's method */
} rp_ransac_t;

typedef struct {
    rp_real p[6];         /* rig pose [tx ty tz alpha beta gamma] of cam1 in the world, m, rad */
    uint32_t n_inliers;   /* observations within the gate at p */
    uint32_t n_usable;    /* observations with w > 0 that could be unprojected */
    uint32_t iters;       /* draws made */
    uint32_t n_hyp;       /* P3P poses scored */
    rp_real rms_px;       /* weighted RMS residual per pixel coordinate of the inliers at p, px */
    rp_real thresh_px;    /* the gate used, px */
} rp_ransac_result_t;

/* Seed the generator (any seed, 0 included). RP_E_ARG for NULL. */
rp_status_t rp_ransac_seed(rp_ransac_t *rs, uint64_t seed);

/* The rig pose from the n observations obs (any cameras of rig; pixels distorted, as
 * measured). prm may be NULL (defaults). inlier (may be NULL): n bytes, 1 for an inlier of the
 * final pose, else 0. res: the result (filled also on RP_E_TOO_FEW with the best found).
 * Observations with w = 0, or whose pixel cannot be unprojected, are not used (inlier 0).
 * RP_E_ARG (NULL rig/obs/rs/res, n > RP_RANSAC_MAX_OBS, a camera index outside the rig, a
 * negative weight, bad parameters), RP_E_NAN (a non-finite pixel,
 * point or weight), RP_E_TOO_FEW (fewer than 4 usable observations, no camera with 3, or no
 * hypothesis reaching min_inliers); a bad rig gives rp_rig_check's status. */
rp_status_t rp_ransac_solve(rp_ransac_t *rs, const rp_rig_t *rig, const rp_obs_t *obs,
                            uint32_t n, const rp_ransac_params_t *prm, uint8_t *inlier,
                            rp_ransac_result_t *res);

#ifdef __cplusplus
}
#endif

#endif /* RP_RANSAC_H */
