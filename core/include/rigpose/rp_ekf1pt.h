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
 *     is the hypothesis. On a rig, one observation of each of up to hyp_cams cameras instead
 *     (i, then draws among the usable ones until a camera not yet in it comes up, at most
 *     RP_EKF1PT_HYP_TRIES draws), the prior updated by them (rp_ekf_update, two
 *     linearisations): the hypothesis. Why: the prior is what lets one observation fix a
 *     pose, and it is wide exactly when outliers do most harm (the start, a turn's onset,
 *     gc's young landmarks whose depths are still the assumed one): a single camera then
 *     leaves rotation about axes across it and translation along them interchangeable, and
 *     a hypothesis drawn in one camera is supported by that camera's features and by whatever
 *     else fits the same ambiguous pose (a moving object static in another camera's image:
 *     gc from rendered pixels took the object and cam2 over the static scene in its first
 *     frames). Observations of three cameras fix all six directions whatever the prior; on a
 *     camera alone (cam1..cam4) it is the single observation above. Its support: every usable
 *     observation k with
 *         w_k |z_k - h_k(p_i)|^2 <= gate_chi2 s2
 *     (the filter's own chi-square gate on the pixel noise alone: at p_i the pose error is
 *     small next to it for the inliers). A hypothesis that beats the best so far is refined
 *     (local optimisation, as LO-RANSAC's, Chum et al. 2003): the prior updated once, one
 *     linearisation, by its support, and that posterior's support kept if larger. (A single
 *     observation fixes two of the six pose directions; under a wide prior its support is a
 *     small part of the inliers, and the adaptive count below would draw for a far worse
 *     inlier ratio than the data's.) The largest support wins (ties: the first); after each
 *     better one the draw count is adapted,
 *         n_hyp = log(1 - confidence) / log(1 - eps^m),   eps = support / usable,
 *     m the observations of a hypothesis (hyp_cams, or the cameras the usable observations
 *     come from if fewer), clamped to [min_hyp, max_hyp] (paper, eq. 17).
 *  2. Rescue of the high-innovation inliers: every other usable observation whose innovation
 *     at the winner's refined posterior passes the filter's gate,
 *     r^T (J C+ J^T + s2 / w I)^-1 r <= gate_chi2, C+ that posterior's pose covariance, joins
 *     the winner's support (paper, section 3.3).
 *  2b. The rescued ones must fit together, not only each on its own: when the low-innovation
 *     consensus leaves a pose direction open (on a rig of two stereo pairs, the consensus of
 *     one pair alone and its blind direction, x against beta for a camera looking along z), a
 *     moving object and the static scene in the other pair's view can each be inside that
 *     posterior's gate while 20 px apart, and an update on both splits the difference. So after
 *     step 3, if a used observation that the consensus did not hold is outside the gate of
 *     the posterior on the consensus's own spread (w |z - h(x+)|^2 > gate_chi2 v, v the mean
 *     w |z - h|^2 / 2 of the consensus at its posterior, at least s2: an observation inside an
 *     update has a posterior residual of variance under the data's, and v holds what the model
 *     leaves of its inliers, the pixel noise and map errors such as gc's and mono's depths
 *     before they converge, which the pose update does not model), the rescue is redone as a
 *     consensus of its own: step 1 among the rescued observations, from the low-innovation
 *     posterior instead of the prior; the largest mutually consistent group joins the
 *     consensus, and step 3 runs again (its rounds rescue the rest against the posterior that
 *     group pins down). If a used observation outside the consensus is still past that gate
 *     (the largest group among the rescued was the one the consensus left out: a moving object
 *     while the consensus holds the scene), the consensus alone makes the update. A rescue that
 *     fits together does not reach 2b and is updated exactly as without it; a clean one can,
 *     when one of its rescued observations is past the gate by chance (about 1 in 1,000 each).
 *     2b runs after the clock-jump test of step 3 (a jumped camera's features are a consistent
 *     group that the redrawn rescue could take in). Switch: prm.regroup. The test holds where
 *     the landmarks are points known to about the pixel noise, as a stereo pair's
 *     triangulations are; gc's and mono's young landmarks lie along their rays at an assumed
 *     depth, sound ones stay off the posterior by more than the consensus's spread, and
 *     redrawing drops them (gc's noise-free run went from 0.3 mm to 3 cm with it).
 *  3. One update of the filter from its prior (rp_ekf_update: iterated, gated) on the
 *     low-innovation inliers and the rescued ones, the others weighted 0. The paper's two
 *     partial updates in a row are not used: the second would be linearised at, and gated
 *     against, the first's posterior, and on outlier-free data the pair then differs from the
 *     filter's plain update (measured: up to 1.14x the error on Table 1); one update on the
 *     inlier set is the plain update whenever that set is every observation the plain gate
 *     keeps. What is still left out is tested against the new posterior as in 2, and the update
 *     repeated from the prior if that adds any (3 updates at most). With
 *     plain_without_majority, consensus + rescued under half of the usable observations are
 *     taken as judging the model (a map whose errors exceed sigma_px), not the observations,
 *     and the plain update is made instead (rp_ekf_update's own rule for a gate that would
 *     reject more than it keeps). Off by default: under gross outliers a start-up map (depths
 *     still unknown) gives such consensuses too, and the plain update then takes the outliers
 *     (gc with 30 % outliers: 1.9x its clean error without the rule, 126x with it).
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
/* Draws at most to find a hypothesis's observation of another camera (step 1). */
#define RP_EKF1PT_HYP_TRIES 16

RP_STATIC_ASSERT(RP_EKF1PT_MAX_OBS <= 65535, "RP_EKF1PT_MAX_OBS: indices are uint16_t");

typedef struct {
    rp_real confidence; /* probability of drawing at least one inlier hypothesis (0.99) */
    uint16_t min_hyp;   /* hypotheses at least (2) */
    uint16_t max_hyp;   /* hypotheses at most (200; the paper's 1000 is for a mono prior) */
    uint8_t plain_without_majority; /* 1: the plain update when consensus + rescued are under
                                     * half of the usable observations (0) */
    uint8_t regroup;    /* 1: step 2b, the rescued ones redrawn as a consensus of their own
                         * when they do not fit together (1; off for layouts whose map errors
                         * the pose update does not model: rp_vo_gc.c, rp_vo_mono.c) */
    uint8_t hyp_cams;   /* cameras a hypothesis draws one observation from, 1..RP_MAX_CAMS
                         * (3: all six pose directions; 1: the paper's one observation) */
} rp_ekf1pt_params_t;

/* Every default, the only place they are written. */
rp_ekf1pt_params_t rp_ekf1pt_default_params(void);

/* Caller-owned state (with the default limits 222 KB in double, 122 KB in float; make it
 * static). */
typedef struct {
    uint64_t rng;                        /* xorshift64* state, never 0 */
    uint8_t best[RP_EKF1PT_MAX_OBS];     /* the winner's support */
    uint8_t cand[RP_EKF1PT_MAX_OBS];     /* the hypothesis being scored; then the first
                                          * update's used flags */
    uint8_t ok[RP_EKF1PT_MAX_OBS];       /* 1: usable (w > 0, projectable at the prior) */
    uint8_t low[RP_EKF1PT_MAX_OBS];      /* the winner's support before the rescue */
    uint8_t ok_all[RP_EKF1PT_MAX_OBS];   /* scratch of step 2b: the usable flags */
    rp_obs_t sel[RP_EKF1PT_MAX_OBS];     /* obs with the weights of one update */
    rp_ekf_t prior;                      /* the filter as it was given */
    rp_ekf_t post;                       /* the best support's refined posterior */
    rp_ekf_t base;                       /* the low-innovation posterior, for step 2b */
    rp_ekf_t hyp;                        /* a hypothesis of several cameras' observations */
    uint16_t pool[RP_EKF1PT_MAX_OBS];    /* the usable observations' indices (step 1) */
} rp_ekf1pt_t;

typedef struct {
    rp_ekf_info_t ekf;  /* n_used: every update; n_gated = n_outside: usable and not used;
                         * n_bad: not usable; rms_px (of the low-innovation update) and
                         * cov_reset as rp_ekf_update's */
    uint16_t n_hyp;     /* hypotheses drawn */
    uint16_t n_low;     /* low-innovation inliers (the winner's support) */
    uint16_t n_rescued; /* used, and not in the winner's support (rescued) */
    uint16_t n_usable;  /* observations that could be hypotheses */
    uint8_t n_no_majority; /* 1: consensus + rescued were under half of the usable ones, and
                            * the plain update was made instead */
    uint8_t n_reconsensus; /* 1: the rescued ones did not fit together, and their own
                            * consensus was drawn (step 2b); 2: that group did not fit the
                            * consensus either, and the consensus alone updated */
    uint16_t n_hyp_regroup; /* hypotheses drawn by step 2b (not in n_hyp) */
} rp_ekf1pt_info_t;

/* Seed the generator (any seed). RP_E_ARG for NULL. */
rp_status_t rp_ekf1pt_seed(rp_ekf1pt_t *s, uint64_t seed);

/* The measurement update of ekf with the n observations obs, outliers removed by 1-point
 * RANSAC (see above). prm may be NULL (defaults). used (n bytes, may be NULL): 1 for each
 * observation that entered an update. info may be NULL.
 * Returns the final update's rp_ekf_update status (RP_OK, RP_E_TOO_FEW: fewer than
 * min_features in the inlier set, the state left as predicted; RP_E_DIVERGED, its fault
 * handling). RP_E_ARG (NULL ekf/rig/s, obs NULL with n > 0,
 * n > RP_EKF1PT_MAX_OBS, bad prm). */
rp_status_t rp_ekf1pt_update(rp_ekf1pt_t *s, rp_ekf_t *ekf, const rp_rig_t *rig,
                             const rp_obs_t *obs, uint32_t n, const rp_ekf1pt_params_t *prm,
                             uint8_t *used, rp_ekf1pt_info_t *info);

/* The MSAC cost of pose p on the n observations (P. H. S. Torr, A. Zisserman, "MLESAC",
 * CVIU 78, 2000): the sum over observations with w > 0 and finite pixels of
 * min(w |z - h(p)|^2, gate_chi2 sigma_px^2) with ekf's filter parameters (13.8 for gate_chi2
 * 0), each observation at its camera's time at ekf's rate and offsets; one that does not
 * project at p adds the cap. px^2; lower fits better; comparable between poses on the same
 * observations and weights. Unlike the size of a support, it tells a pose that fits the
 * inliers to the pixel noise from one that holds them within the gate a pixel off (a moving
 * object's pose, which the other cameras' features do not rule out; rp_vo_stereo.h).
 * inliers (may be NULL): how many are under the cap. RP_E_ARG (NULL ekf/rig/p/cost, obs NULL
 * with n > 0, p not finite). */
rp_status_t rp_ekf1pt_cost(const rp_ekf_t *ekf, const rp_rig_t *rig, const rp_obs_t *obs,
                           uint32_t n, const rp_real p[6], rp_real *cost, uint32_t *inliers);

#ifdef __cplusplus
}
#endif

#endif /* RP_EKF1PT_H */
