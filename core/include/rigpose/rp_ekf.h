/*
 * rp_ekf.h - the 12-state pose EKF of the paper (section 2.1), made numerically careful.
 *
 * State x = [tx ty tz alpha beta gamma | vx vy vz wx wy wz] (m, rad, m/s, rad/s): the pose as
 * the paper's angles (the representation of the mean), then the velocity and the world-frame
 * angular rate omega. The covariance P and every increment are in the pose chart of rp_rig.h:
 * rows/columns 0..2 the translation (m), 3..5 the world-frame rotation vector w of
 * R = Exp(w) R^ (rad), 6..8 m/s, 9..11 omega (rad/s). It has no singularity where the angles
 * have one (beta = +-pi/2).
 * Plant: constant velocity and angular rate, t+ = t + dt v, R+ = Exp(dt omega) R, driven by
 * white acceleration noise (continuous spectral densities q_trans (m^2/s^3) and q_rot
 * (rad^2/s^3)); in the chart F = [I dt I; 0 I] diag(I, Exp(dt omega), I, I).
 * Measurement: the pixel of each tracked feature through eqs. (1)-(2) (rp_rig_project), at
 * its camera's capture time. The state is at the frame set's time t; camera k captured at
 * t + delta_k with delta_k = obs.dt (its stamp minus t) + toff[k] (its clock offset, below),
 * and the feature is predicted from the pose the constant-velocity model gives there:
 * p(delta) = p [+] delta [v; omega] (the chart below: t + delta v, Exp(delta omega) R).
 * Clock offsets (free-running cameras, issue 15): camera k's true capture time is its stamp
 * plus toff[k] (s). Offsets are either fixed (known) or states of the filter (toff_mask):
 * a random walk of density q_toff (s^2/s), observed through the image motion of the features
 * (d uv / d toff_k = J_pose [v; omega]), as OpenVINS estimates a camera-IMU time offset.
 * Camera 0 is the reference (its offset is not a state). A clock that jumps (a camera
 * restarted) shows as most of that camera's features gated out while the others' are used: its
 * offset state then restarts at its start sigma and the update runs again
 * (rp_ekf_info_t.toff_reset).
 * Update: iterated EKF (Gauss-Newton on the posterior, `iterations` relinearisations), computed
 * in information form (the sum of H^T R^-1 H over features is DxD, whatever their number), so
 * the covariance stays symmetric positive definite by construction. D = 6 (the pose; the rate
 * follows by conditioning) when every feature is at the state's time and no offset is a
 * state; else D = 12 + the offset states (pose, rate and offsets updated jointly), each capture
 * time's shared error of the extrapolated pose marginalised per capture time (rp_ekf.c,
 * tgroup_t: a positive semidefinite net information per group, formed in double).
 * Gate: every iteration tests each feature's innovation r against the current iterate, with
 * S = J C J^T + sigma^2 / w I (+ in a timed update the time error's J Q J^T) (C: the prior pose
 * covariance in the first iteration, the last
 * iteration's posterior after), and leaves it out when r^T S^-1 r > gate_chi2. An iteration
 * whose gate would reject more features than it keeps uses them all (the iterate is still
 * poor: residuals are linearisation error, not noise), and a later iteration gates. The
 * features counted as used and gated are those of the final iteration.
 * Fault: an update whose covariance is not positive definite, or whose state is not finite, is
 * discarded: the state stays as predicted and the covariance becomes the predicted one, made
 * symmetric and multiplied by RP_EKF_RESET_INFLATION.
 */
#ifndef RP_EKF_H
#define RP_EKF_H

#include "rp_obs.h"
#include "rp_opts.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RP_EKF_N 12
#define RP_EKF_RESET_INFLATION RP_C(4.0) /* factor on the predicted covariance after a fault,
                                          * so that the next measurements can pull the state
                                          * back (dimensionless) */

typedef struct {
    rp_real sigma_px;  /* measurement noise per pixel coordinate (1-sigma), pixels */
    rp_real q_trans;   /* plant: translational acceleration noise density, m^2/s^3 */
    rp_real q_rot;     /* plant: angular acceleration noise density, rad^2/s^3 */
    rp_real gate_chi2; /* per-feature 2-dof gate on the Mahalanobis distance (e.g. 13.8: 99.9%);
                        * <= 0 disables gating */
    uint8_t iterations;/* Gauss-Newton iterations of the update, >= 1 (1 = plain EKF) */
    uint16_t min_features; /* fewer accepted features than this: no update (RP_E_TOO_FEW) */
    rp_real max_predict_s; /* the constant-velocity prediction runs at most this long without
                            * a successful update (s, > 0); after it the pose is held (see
                            * rp_ekf_predict) */
    /* Clock offsets (top of this file; config/README.md "Time offsets"): */
    rp_real toff0_s[RP_MAX_CAMS]; /* each camera's configured offset (capture = stamp + it), s:
                                   * the filter's offsets after rp_ekf_init */
    uint8_t toff_estimate; /* 1: layouts make the offsets of their cameras but the first states
                            * (rp_vo_ekf_offsets) */
    rp_real toff_sigma_s;  /* start sigma of an offset state, s (> 0) */
    rp_real toff_q;        /* random-walk density of an offset state, s^2/s (>= 0): the
                            * clocks' drift */
    rp_real time_jitter_s; /* standard deviation of a capture time about its stamp (plus
                            * offset), s (>= 0): its image motion over that time, shared by the
                            * features of one image (group_time_noise) or, per feature,
                            * jitter^2 (J xi)(J xi)^T in each pixel's noise */
    uint8_t group_time_noise; /* 1: in a timed update the features of one capture time share
                               * the error of the pose extrapolated there (rate, jitter and the
                               * plant's acceleration over it), marginalised once per group
                               * (rp_ekf.c, tgroup_t); 0: the rate's and the jitter's parts
                               * as independent pixel noise per feature */
} rp_ekf_params_t;

/* Defaults for 0.5 px noise and a hand-held / robot motion at ~30 Hz. */
rp_ekf_params_t rp_ekf_default_params(void);

typedef struct {
    rp_real x[RP_EKF_N];            /* state */
    rp_real P[RP_EKF_N * RP_EKF_N]; /* covariance, row-major */
    rp_ekf_params_t prm;
    rp_real t_unobs;                /* time predicted since the last successful update (or the
                                     * start), s */
    uint8_t held;                   /* 1 once t_unobs passed prm.max_predict_s: the pose is held
                                     * (velocity mean zero) until the next successful update */
    /* Clock offsets (top of this file): all zero after rp_ekf_init (synchronised cameras). */
    uint8_t toff_mask;              /* bit k: camera k's offset is a state (never bit 0) */
    rp_real toff[RP_MAX_CAMS];      /* camera k's clock offset: capture = stamp + toff[k], s */
    rp_real q_toff;                 /* random-walk density of the offset states, s^2/s */
    rp_real Pxo[RP_EKF_N * RP_MAX_CAMS]; /* cross-covariance of x and the offsets, row-major
                                     * 12 x RP_MAX_CAMS (columns of non-states are zero) */
    rp_real Poo[RP_MAX_CAMS * RP_MAX_CAMS]; /* covariance of the offsets, s^2 (rows and
                                     * columns of non-states are zero) */
} rp_ekf_t;

typedef struct {
    uint16_t n_used;   /* features that entered the final update */
    uint16_t n_gated;  /* features rejected by the gate */
    uint16_t n_bad;    /* features rejected as unprojectable (behind camera, non-finite) */
    uint16_t n_outside;/* features outside the gate in the final iteration's test, also when
                        * that iteration then used them all (it rejected more than it kept):
                        * more than half of them says the prior is wrong, not the features */
    rp_real rms_px;    /* RMS residual per pixel coordinate of the used features, at the last
                        * linearisation point (pixels) */
    uint8_t cov_reset; /* 1 if the covariance had to be reset (numerical fault) */
    uint8_t toff_reset;/* bit c: camera c's clock jumped (most of its features gated out, the
                        * others' used): its offset state restarted at the start sigma and the
                        * update ran again (rp_ekf_update) */
    uint16_t n_used_cam[RP_MAX_CAMS];  /* n_used per camera */
    uint16_t n_gated_cam[RP_MAX_CAMS]; /* n_gated per camera */
} rp_ekf_info_t;

/* Start the filter at x0 with diagonal covariance P0diag; the clock offsets at prm->toff0_s,
 * none a state. RP_E_ARG (bad params: sigma_px <= 0, iterations 0, negative noise, offset
 * sigma <= 0 or q < 0), RP_E_NAN. */
rp_status_t rp_ekf_init(rp_ekf_t *ekf, const rp_ekf_params_t *prm, const rp_real x0[RP_EKF_N],
                        const rp_real P0diag[RP_EKF_N]);

/* Set the clock offsets: toff0[k] for every camera (s; NULL: all 0), and which are states
 * (mask, bit k; bit 0 refused: camera 0 is the reference) with start sigma sigma0[k] (s, > 0
 * for each state; may be NULL when mask is 0) and random-walk density q (s^2/s, >= 0).
 * Any cross-covariance with the pose is dropped. RP_E_ARG, RP_E_NAN; nothing changed then. */
rp_status_t rp_ekf_toff_set(rp_ekf_t *ekf, uint8_t mask, const rp_real toff0[RP_MAX_CAMS],
                            const rp_real sigma0[RP_MAX_CAMS], rp_real q);

/* Copy src's clock offsets (values, states, their covariance, q) into dst, a filter just
 * (re)started at a new pose: the cross-covariance with the pose is dropped. RP_E_ARG. */
rp_status_t rp_ekf_toff_carry(rp_ekf_t *dst, const rp_ekf_t *src);

/* Cameras whose clock jumped: of filter e's offset states, a camera with most of its features
 * (at least min_features) left out of an update (n_left: gated, or outside a RANSAC consensus)
 * while the other cameras' were mostly used (n_used): its offset has left what its state
 * allows (a camera restarted, a clock stepped), not its features. Bit c: camera c. 0 for NULL.
 * rp_ekf_update applies it to its own gate; rp_ekf1pt_update to its consensus. */
uint8_t rp_ekf_clock_jumps(const rp_ekf_t *e, const uint16_t n_used[RP_MAX_CAMS],
                           const uint16_t n_left[RP_MAX_CAMS]);

/* Restart the offset states of cameras cams (bit c) at the start sigma (prm.toff_sigma_s), their
 * correlations dropped; cameras without an offset state are left alone. NULL: nothing. */
void rp_ekf_toff_restart(rp_ekf_t *ekf, uint8_t cams);

/* Time update over dt seconds (dt > 0, finite; else RP_E_ARG and no change; RP_E_NAN and no
 * change for a non-finite pose or rate).
 * Bounded prediction: the constant-velocity model extrapolates for at most prm.max_predict_s
 * after the last successful update. At that time the velocity is released: its mean becomes
 * zero and its covariance Pvv + v v^T (the second moment of the true rate about zero, so the
 * error the held pose makes if the rig kept moving is in the covariance), and the prediction
 * goes on from there: the pose stays where it was while its covariance keeps growing, by the
 * plant noise and by dt^2 times the released rate covariance. ekf->held says so; a successful
 * update clears it (and t_unobs). */
rp_status_t rp_ekf_predict(rp_ekf_t *ekf, rp_real dt);

/* r^T S^-1 r with S = J C J^T + s2 I: the 2-dof Mahalanobis distance of a residual r whose
 * pixel's Jacobian is J (2x6, the pose chart) under pose covariance C (6x6) and pixel variance
 * s2. 1e30 (farther than any gate) if S is not positive definite. */
rp_real rp_ekf_mahalanobis2(const rp_real J[12], const rp_real C[36], rp_real s2,
                            const rp_real r[2]);

/* Measurement update with n observations. `used` (n bytes, may be NULL) receives 1 for each
 * observation used, 0 for one gated or unprojectable. info may be NULL.
 * Returns RP_OK; RP_E_TOO_FEW (fewer than prm.min_features usable; the state is left as
 * predicted); RP_E_DIVERGED (the update produced a non-finite state or a covariance that is not
 * positive definite: the update is discarded, the covariance reset to its predicted value made
 * symmetric and times RP_EKF_RESET_INFLATION, info->cov_reset set); RP_E_ARG. In every case
 * the filter stays usable. */
rp_status_t rp_ekf_update(rp_ekf_t *ekf, const rp_rig_t *rig, const rp_obs_t *obs, uint32_t n,
                          uint8_t *used, rp_ekf_info_t *info);

#ifdef __cplusplus
}
#endif

#endif /* RP_EKF_H */
