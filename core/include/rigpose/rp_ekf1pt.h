/*
 * rp_ekf1pt.h - 1-point RANSAC for the pose EKF's measurement update (J. Civera, O. G. Grasa,
 * A. J. Davison, J. M. M. Montiel, "1-Point RANSAC for Extended Kalman Filtering: Application
 * to Real-Time Structure from Motion and Visual Odometry", J. Field Robotics 27(5), 2010,
 * algorithm 1). The filter's prior is the extra information that makes one observation enough
 * for a hypothesis.
 *
 * With the prior pose p0, its covariance C (the pose block of P), s2 = sigma_px^2 and the
 * observations' weights w:
 *  1. Hypotheses: draw one usable observation i (w > 0, projectable at p0) uniformly; its
 *     partial EKF update (state only, one linearisation at p0)
 *         S_i = J_i C J_i^T + s2 / w_i I,   p_i = p0 + C J_i^T S_i^-1 (z_i - h_i(p0))
 *     is the hypothesis. Its support: every usable observation k with
 *         w_k |z_k - h_k(p_i)|^2 <= gate_chi2 s2
 *     (the filter's own chi-square gate on the pixel noise alone: at p_i the pose error is
 *     small next to it for the inliers). The hypothesis with the most support wins (ties: the
 *     first); after each better one the draw count is adapted,
 *         n_hyp = log(1 - confidence) / log(1 - eps),   eps = support / usable,
 *     clamped to [min_hyp, max_hyp] (paper, eq. 17 with m = 1).
 *  2. Low-innovation inliers: the winner's support updates the filter (rp_ekf_update, the
 *     iterated update with its gate), the others weighted 0.
 *  3. Rescue of the high-innovation inliers: every other usable observation whose innovation
 *     at the posterior passes the filter's gate, r^T (J C+ J^T + s2 / w I)^-1 r <= gate_chi2
 *     with C+ the posterior pose covariance, enters a second partial update from that posterior
 *     (paper, section 3.3); repeated against each new posterior while it adds any (3 rounds
 *     at most).
 * No heap; the generator's state lives in the caller's rp_ekf1pt_t, so a fixed sequence of
 * inputs gives a fixed sequence of outputs.
 */
#ifndef RP_EKF1PT_H
#define RP_EKF1PT_H

#include "rp_ekf.h"
#include "rp_obs.h"
#include "rp_opts.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RP_EKF1PT_MAX_OBS (RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM)

typedef struct {
    rp_real confidence; /* probability of drawing at least one inlier hypothesis (0.99) */
    uint16_t min_hyp;   /* hypotheses at least (2) */
    uint16_t max_hyp;   /* hypotheses at most (200; the paper's 1000 is for a mono prior) */
} rp_ekf1pt_params_t;

/* Every default, the only place they are written. */
rp_ekf1pt_params_t rp_ekf1pt_default_params(void);

/* Caller-owned state (with the default limits 184 KB in double; make it static). */
typedef struct {
    uint64_t rng;                        /* xorshift64* state, never 0 */
    uint8_t best[RP_EKF1PT_MAX_OBS];     /* the winner's support */
    uint8_t cand[RP_EKF1PT_MAX_OBS];     /* the hypothesis being scored; then the first
                                          * update's used flags */
    uint8_t ok[RP_EKF1PT_MAX_OBS];       /* 1: usable (w > 0, projectable at the prior) */
    uint8_t used2[RP_EKF1PT_MAX_OBS];    /* the second update's used flags */
    rp_obs_t sel[RP_EKF1PT_MAX_OBS];     /* obs with the weights of one partial update */
} rp_ekf1pt_t;

typedef struct {
    rp_ekf_info_t ekf;  /* n_used: every update; n_gated = n_outside: usable and not used;
                         * n_bad: not usable; rms_px (of the low-innovation update) and
                         * cov_reset as rp_ekf_update's */
    uint16_t n_hyp;     /* hypotheses drawn */
    uint16_t n_low;     /* low-innovation inliers (the winner's support) */
    uint16_t n_rescued; /* high-innovation inliers rescued and used */
    uint16_t n_usable;  /* observations that could be hypotheses */
} rp_ekf1pt_info_t;

/* Seed the generator (any seed). RP_E_ARG for NULL. */
rp_status_t rp_ekf1pt_seed(rp_ekf1pt_t *s, uint64_t seed);

/* The measurement update of ekf with the n observations obs, outliers removed by 1-point
 * RANSAC (see above). prm may be NULL (defaults). used (n bytes, may be NULL): 1 for each
 * observation that entered an update. info may be NULL.
 * Returns rp_ekf_update's status for the low-innovation update (RP_OK, RP_E_TOO_FEW: fewer
 * than min_features in the support, the state left as predicted; RP_E_DIVERGED); a failed
 * rescue update leaves the first posterior. RP_E_ARG (NULL ekf/rig/s, obs NULL with n > 0,
 * n > RP_EKF1PT_MAX_OBS, bad prm). */
rp_status_t rp_ekf1pt_update(rp_ekf1pt_t *s, rp_ekf_t *ekf, const rp_rig_t *rig,
                             const rp_obs_t *obs, uint32_t n, const rp_ekf1pt_params_t *prm,
                             uint8_t *used, rp_ekf1pt_info_t *info);

#ifdef __cplusplus
}
#endif

#endif /* RP_EKF1PT_H */
