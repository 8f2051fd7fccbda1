/*
 * rp_rot.h - rotations: 3x3 matrices (row-major, 9 elements), the paper's angles and quaternions.
 *
 * The paper's angles (alpha, beta, gamma) rotate about the fixed axes x1, y1, z1 and compose as
 * R = Rz(gamma) Ry(beta) Rx(alpha). Quaternions are unit, ordered (w, x, y, z), w >= 0 on output.
 * Rotation vectors (exp/log) are axis * angle, angle in [0, pi].
 */
#ifndef RP_ROT_H
#define RP_ROT_H

#include "rp_opts.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* R = Rz(abg[2]) Ry(abg[1]) Rx(abg[0]). */
void rp_rot_from_angles(const rp_real abg[3], rp_real R[9]);

/* Angles of R, alpha and gamma in (-pi, pi], beta in [-pi/2, pi/2].
 * Near gimbal lock (|cos beta| < 1e-9 in double, 1e-5 in float) only alpha -/+ gamma is
 * determined: the function sets alpha = 0, solves gamma, and still returns RP_OK.
 * RP_E_NAN if R has a non-finite element. */
rp_status_t rp_rot_to_angles(const rp_real R[9], rp_real abg[3]);

/* The estimators' rotation chart (singularity-free, unlike the angles at beta = +-pi/2): a
 * rotation near R(abg) is R(out) = Exp(w) R(abg), w a world-frame rotation vector (rad).
 * Box-plus: out = angles of Exp(w) R(abg) (rp_rot_to_angles' choice at gimbal lock, which
 * reproduces the rotation). RP_E_NAN for non-finite input; out may alias abg. */
rp_status_t rp_angles_plus(const rp_real abg[3], const rp_real w[3], rp_real out[3]);

/* Box-minus: w = Log(R(a) R(b)^T), so that R(a) = Exp(w) R(b), |w| in [0, pi]; w is the same
 * for every angle triple of the same two rotations. */
void rp_angles_minus(const rp_real a[3], const rp_real b[3], rp_real w[3]);

/* Derivatives of R(abg) with respect to alpha, beta and gamma: dR[i] = dR/d(abg[i]). */
void rp_rot_angle_derivs(const rp_real abg[3], rp_real dR[3][9]);

/* Unit quaternion (w, x, y, z), w >= 0, of R (Shepperd's method, numerically stable). */
void rp_rot_to_quat(const rp_real R[9], rp_real q[4]);

/* R of quaternion q (normalised here). RP_E_ARG if |q| < 1e-12 (1e-6 in float), RP_E_NAN. */
rp_status_t rp_rot_from_quat(const rp_real q[4], rp_real R[9]);

/* R = exp([w]x) (Rodrigues). */
void rp_rot_exp(const rp_real w[3], rp_real R[9]);

/* w = log(R), |w| in [0, pi] (stable near 0 and near pi). */
void rp_rot_log(const rp_real R[9], rp_real w[3]);

/* C = A B; C may alias A or B. */
void rp_rot_mul(const rp_real A[9], const rp_real B[9], rp_real C[9]);
/* C = A^T B; C may alias A or B. */
void rp_rot_mul_at_b(const rp_real A[9], const rp_real B[9], rp_real C[9]);
/* C = A B^T; C may alias A or B. */
void rp_rot_mul_a_bt(const rp_real A[9], const rp_real B[9], rp_real C[9]);
/* out = R v; out may alias v. */
void rp_rot_apply(const rp_real R[9], const rp_real v[3], rp_real out[3]);
/* out = R^T v; out may alias v. */
void rp_rot_apply_t(const rp_real R[9], const rp_real v[3], rp_real out[3]);
/* R^T, in place allowed. */
void rp_rot_transpose(const rp_real R[9], rp_real Rt[9]);
/* Nearest rotation to R (re-orthonormalise after accumulating products); in place. */
void rp_rot_orthonormalize(rp_real R[9]);
/* Rotation angle (rad, in [0, pi]) of A^T B: the geodesic distance between A and B. */
rp_real rp_rot_distance(const rp_real A[9], const rp_real B[9]);

/* x wrapped to [-pi, pi). */
rp_real rp_angle_wrap(rp_real x);

#ifdef __cplusplus
}
#endif

#endif /* RP_ROT_H */
