/*
 * rp_lowe.h - Lowe's method: the rig pose from 2-D/3-D correspondences in any number of
 * cameras, by damped Gauss-Newton (Levenberg-Marquardt) on the reprojection error of eq. (2).
 * The paper uses it to start the pose EKF as accurately as possible.
 */
#ifndef RP_LOWE_H
#define RP_LOWE_H

#include "rp_obs.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint16_t max_iter; /* iteration limit (e.g. 30) */
    rp_real tol_step;  /* stop when the step's norm falls under this (e.g. 1e-10 in double) */
} rp_lowe_params_t;

rp_lowe_params_t rp_lowe_default_params(void);

/* Refine pose p (in: start, out: estimate) minimising the weighted reprojection error of the
 * n observations. prm may be NULL (defaults). rms_px (may be NULL): final weighted RMS residual
 * per pixel coordinate, pixels (about sigma_px when the residuals are the noise). cov (may be
 * NULL): 6x6 covariance of p for unit pixel noise (scale by sigma^2), in the pose chart of rp_rig.h
 * (translation, then the world-frame rotation vector). Observations with w = 0,
 * or behind their camera at the current pose, are left out.
 * RP_E_TOO_FEW (n < 3, or fewer than 3 usable observations), RP_E_SINGULAR (geometry does not
 * fix the pose), RP_E_NO_CONVERGE (iteration limit; p holds the best pose found, rms_px and cov
 * are filled), RP_E_NAN, RP_E_ARG (also a bad camera index or a negative weight). */
rp_status_t rp_lowe_solve(const rp_rig_t *rig, const rp_obs_t *obs, uint32_t n,
                          const rp_lowe_params_t *prm, rp_real p[6], rp_real *rms_px,
                          rp_real cov[36]);

#ifdef __cplusplus
}
#endif

#endif /* RP_LOWE_H */
