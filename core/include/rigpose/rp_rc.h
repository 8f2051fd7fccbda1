/*
 * rp_rc.h - rigidity constraints (method rc, paper section 2.1 eqs. 3-7): fuse the own poses
 * (r_kj, l_kj) of single cameras of a rig into one rig pose.
 *
 *  - Rotation: each camera's rotation is brought back to the rig frame by the change of basis
 *    R_kj = R_k r_kj R_k^T (eq. 3); the rig's rotation is the per-axis median over the cameras
 *    in rp_rig.h's chart at the reference camera's R_1j (w_k = Log(R_kj R_1j^T), R_j =
 *    Exp(median w) R_1j; the median of an even count is the mean of the middle two). The
 *    paper's per-angle median is the same near the identity, but not defined near
 *    beta = +-pi/2, where nearby rotations have far-apart alpha and gamma.
 *  - Translation: with d_j = l_1j, the reference camera's own translation, and R_j the fused
 *    rotation, each other camera k gives three equations S_j d_j - S_kj R_k l_kj = (I - R_j) D_k
 *    (eq. 5); stacked they are A s = b (eq. 6: 9x4 for the paper's four cameras), solved in the
 *    least-squares sense (eq. 7, here by QR: rp_la_lstsq). The rig translation is S_j d_j.
 *  - Degenerate geometry is detected, not divided through: a reference translation |d_j| under
 *    min_trans_m (pure rotation: eq. 5 does not fix S_j), a rank-deficient A (rp_la_lstsq's
 *    RP_E_SINGULAR), a non-finite solution, or a scale S_j outside [min_scale, max_scale] or a
 *    non-positive S_kj (absurd geometry, e.g. opposite motions), or a poorly determined S_j
 *    (its least-squares standard error above max_scale_se). Then the fallback scale is used
 *    (the caller passes the last accepted S_j, or 1 = the cameras' own assumed-depth scale), the
 *    result is flagged RP_EST_SCALE_WEAK and the function returns RP_E_DEGENERATE (the rotation
 *    and the fallback translation are still filled in).
 */
#ifndef RP_RC_H
#define RP_RC_H

#include "rp_opts.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RP_RC_MAX_CAMS 4 /* the paper's layout; A is at most 9 x 4 */

typedef struct {
    rp_real min_trans_m; /* |d_j| below this: pure rotation, scale not determined (m) */
    rp_real min_scale;   /* accepted range of S_j */
    rp_real max_scale;
    rp_real max_scale_se; /* accept S_j only if its standard error (from the LSQ residual and
                           * (A^T A)^-1) is at most this; <= 0: no check */
} rp_rc_params_t;

/* Defaults: 1e-3 m, S_j in [0.25, 4], standard error of S_j at most 0.1. */
rp_rc_params_t rp_rc_default_params(void);

/* Fuse n (2..RP_RC_MAX_CAMS) cameras. cams[i] is the rig index of camera i; cams[0] must be the
 * reference camera (R = I, D = 0 in the rig, i.e. cam1). p_own[i] = [l_kj, angles of r_kj], the
 * camera's own pose in its own first-frame frame. fallback_scale (> 0) is used for S_j when the
 * geometry is degenerate. Outputs: p_rig (rig pose [d, angles]), s (n scales: S_j, S_kj...,
 * may be NULL), flags (|= RP_EST_SCALE_WEAK on degenerate geometry; may be NULL).
 * RP_OK; RP_E_DEGENERATE (fallback used, outputs filled); RP_E_ARG (bad n, camera index, cams[0]
 * not the reference, bad params or fallback); RP_E_NAN (non-finite input). */
rp_status_t rp_rc_fuse(const rp_rig_t *rig, const uint8_t *cams, uint8_t n,
                       const rp_real (*p_own)[6], const rp_rc_params_t *prm,
                       rp_real fallback_scale, rp_real p_rig[6], rp_real *s, uint32_t *flags);

/* Median of n (1..16) values (mean of the middle two when n is even); v is not changed.
 * RP_E_ARG, RP_E_NAN. */
rp_status_t rp_rc_median(const rp_real *v, uint8_t n, rp_real *med);

#ifdef __cplusplus
}
#endif

#endif /* RP_RC_H */
