/*
 * rp_rig.h - the camera rig and the measurement model of the paper's eqs. (1)-(2).
 *
 * Camera k sits at D_k (m) with rotation R_k, both in cam1's frame (cam1: D = 0, R = I).
 * The rig pose at frame j is p = [tx ty tz alpha beta gamma]: d_j = (tx, ty, tz) is cam1's
 * position in the world and R_j = R(alpha, beta, gamma) its rotation (rp_rot.h). World point M
 * has, in camera k,   P = R_k^T R_j^T (M - d_j - R_j D_k)      (eq. 2; eq. 1 when k is cam1).
 */
#ifndef RP_RIG_H
#define RP_RIG_H

#include "rp_camera.h"
#include "rp_opts.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    rp_real R[9];    /* R_k: rotation of camera k in cam1's frame (camera-to-cam1), row-major */
    rp_real D[3];    /* D_k: position of camera k in cam1's frame, m */
    rp_camera_t cam; /* intrinsics */
} rp_rig_cam_t;

typedef struct {
    uint8_t n_cams;               /* cameras in use, 1..RP_MAX_CAMS */
    rp_rig_cam_t cam[RP_MAX_CAMS];
} rp_rig_t;

/* A pose prepared for linearisation: p and R_j, computed once per pose and reused for every
 * feature. */
typedef struct {
    rp_real p[6];     /* [tx ty tz alpha beta gamma], m and rad */
    rp_real R[9];     /* R_j */
} rp_pose_lin_t;

/* The estimators' pose chart. The angles are the representation of the mean only; every
 * Jacobian, increment, difference and covariance of a pose is in the minimal local chart
 * d = [dt; w]: translation d_j + dt (m, world frame) and rotation Exp(w) R_j (w a world-frame
 * rotation vector, rad), which has no singularity, unlike the angles at beta = +-pi/2.
 * rp_pose_plus: out = p [+] d. RP_E_NAN for non-finite input; out may alias p or d. */
rp_status_t rp_pose_plus(const rp_real p[6], const rp_real d[6], rp_real out[6]);

/* rp_pose_minus: d = a [-] b, so that a = b [+] d: d[0..2] = a - b (m), d[3..5] =
 * Log(R(a) R(b)^T) (rad, |.| <= pi), the same for every angle triple of the same rotations. */
void rp_pose_minus(const rp_real a[6], const rp_real b[6], rp_real d[6]);

/* RP_OK if the rig is usable: 1..RP_MAX_CAMS cameras, each rp_cam_check OK, each R_k a
 * rotation (orthonormal to 1e-6, det +1), finite D_k. Else RP_E_ARG or RP_E_NAN. */
rp_status_t rp_rig_check(const rp_rig_t *rig);

/* Prepare pose p. RP_E_NAN if p has a non-finite element. */
rp_status_t rp_pose_lin_set(rp_pose_lin_t *pl, const rp_real p[6]);

/* Prepare the pose delta seconds after p under constant rate xi = [v; omega] (m/s, world-frame
 * rad/s: the pose EKF's rate state): p [+] delta xi (translation + delta v, rotation
 * Exp(delta omega) R), the pose at a camera's capture time (rp_ekf.h). xi NULL or delta 0: p.
 * RP_E_NAN for non-finite input. */
rp_status_t rp_pose_lin_at(rp_pose_lin_t *pl, const rp_real p[6], const rp_real xi[6],
                           rp_real delta);

/* Camera-k coordinates P (m) of world point M at pose pl (eq. 2). RP_E_ARG for a bad k. */
rp_status_t rp_rig_cam_point(const rp_rig_t *rig, uint8_t k, const rp_pose_lin_t *pl,
                             const rp_real M[3], rp_real P[3]);

/* World position of camera-k point P at pose pl: M = d_j + R_j (D_k + R_k P). */
rp_status_t rp_rig_world_point(const rp_rig_t *rig, uint8_t k, const rp_pose_lin_t *pl,
                               const rp_real P[3], rp_real M[3]);

/* Pixel uv of world point M in camera k at pose pl, with the analytic Jacobians
 * J_pose (2x6 row-major, d uv / d d, d in the pose chart above: translation, then the world-
 * frame rotation vector w of R_j <- Exp(w) R_j) and J_M (2x3, d uv / d M), each may be NULL.
 * RP_E_BEHIND if the point is behind camera k, RP_E_NAN, RP_E_ARG. No image-bounds check. */
rp_status_t rp_rig_project(const rp_rig_t *rig, uint8_t k, const rp_pose_lin_t *pl,
                           const rp_real M[3], rp_real uv[2], rp_real J_pose[12],
                           rp_real J_M[6]);

#ifdef __cplusplus
}
#endif

#endif /* RP_RIG_H */
