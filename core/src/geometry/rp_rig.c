/*
 * rp_rig.c - the rig and the measurement model of eqs. (1)-(2) with its analytic Jacobians.
 *
 * With m = M - d_j (world frame), eq. (2) reads P = R_k^T (R_j^T m - D_k): R_j^T m is M in
 * cam1's (the rig's) frame. Differentiating, with J_c = d uv / d P (2x3, row r is j_r) and
 * h_r = R_j R_k j_r (the world-frame gradient of uv_r with respect to M):
 *   d uv_r / d M     =  h_r^T
 *   d uv_r / d d_j   = -h_r^T
 *   d uv_r / d w     =  h_r x m,
 * w the world-frame rotation vector of the pose chart (rp_rig.h: R_j <- Exp(w) R_j, so
 * dR_j = [dw]x R_j, d(R_j^T m) = R_j^T [dw]x^T m = R_j^T (m x dw), and
 * j_r . R_k^T R_j^T (m x dw) = h_r . (m x dw) = dw . (h_r x m)). Unlike the derivatives in the
 * paper's angles (w_i . (h_r x m) with w_beta = Rz(gamma) e_y parallel to R_j e_x at
 * beta = +-pi/2), these three columns never lose rank.
 */
#include "rigpose/rp_rig.h"

#include <stddef.h>

#include "priv/rp_math.h"
#include "rigpose/rp_rot.h"

#define ROT_TOL RP_C(1e-6) /* orthonormality of R_k accepted by rp_rig_check */

/* Local copies of rp_rot_apply / rp_rot_apply_t (no aliasing) so that the per-feature path
 * inlines them. */
static inline void mv(const rp_real R[9], const rp_real v[3], rp_real out[3])
{
    out[0] = R[0] * v[0] + R[1] * v[1] + R[2] * v[2];
    out[1] = R[3] * v[0] + R[4] * v[1] + R[5] * v[2];
    out[2] = R[6] * v[0] + R[7] * v[1] + R[8] * v[2];
}

static inline void mtv(const rp_real R[9], const rp_real v[3], rp_real out[3])
{
    out[0] = R[0] * v[0] + R[3] * v[1] + R[6] * v[2];
    out[1] = R[1] * v[0] + R[4] * v[1] + R[7] * v[2];
    out[2] = R[2] * v[0] + R[5] * v[1] + R[8] * v[2];
}

static int rot_ok(const rp_real R[9])
{
    for (int i = 0; i < 3; ++i) {
        for (int j = i; j < 3; ++j) {
            const rp_real d = R[3 * i] * R[3 * j] + R[3 * i + 1] * R[3 * j + 1] +
                              R[3 * i + 2] * R[3 * j + 2];
            const rp_real want = (i == j) ? RP_C(1.0) : RP_C(0.0);
            if (!(rp_fabs(d - want) <= ROT_TOL)) {
                return 0;
            }
        }
    }
    const rp_real det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                        R[2] * (R[3] * R[7] - R[4] * R[6]);
    return det > RP_C(0.0);
}

rp_status_t rp_rig_check(const rp_rig_t *rig)
{
    if (rig == NULL || rig->n_cams < 1 || rig->n_cams > RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    for (unsigned k = 0; k < rig->n_cams; ++k) {
        const rp_rig_cam_t *c = &rig->cam[k];
        const rp_status_t st = rp_cam_check(&c->cam);
        if (st != RP_OK) {
            return st;
        }
        if (!rp_all_finite(c->R, 9) || !rp_all_finite(c->D, 3)) {
            return RP_E_NAN;
        }
        if (!rot_ok(c->R)) {
            return RP_E_ARG;
        }
    }
    return RP_OK;
}

rp_status_t rp_pose_lin_set(rp_pose_lin_t *pl, const rp_real p[6])
{
    if (pl == NULL || p == NULL) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(p, 6)) {
        return RP_E_NAN;
    }
    for (int i = 0; i < 6; ++i) {
        pl->p[i] = p[i];
    }
    rp_rot_from_angles(p + 3, pl->R);
    return RP_OK;
}

rp_status_t rp_pose_lin_at(rp_pose_lin_t *pl, const rp_real p[6], const rp_real xi[6],
                           rp_real delta)
{
    if (!pl || !p) {
        return RP_E_ARG;
    }
    if (xi == NULL || delta == RP_C(0.0)) {
        return rp_pose_lin_set(pl, p);
    }
    rp_real d[6], q[6];
    for (int i = 0; i < 6; ++i) {
        d[i] = delta * xi[i];
    }
    const rp_status_t st = rp_pose_plus(p, d, q);
    return st == RP_OK ? rp_pose_lin_set(pl, q) : st;
}

rp_status_t rp_pose_plus(const rp_real p[6], const rp_real d[6], rp_real out[6])
{
    if (p == NULL || d == NULL || out == NULL) {
        return RP_E_ARG;
    }
    rp_real ang[3];
    const rp_status_t st = rp_angles_plus(p + 3, d + 3, ang);
    if (st != RP_OK) {
        return st;
    }
    for (int i = 0; i < 3; ++i) {
        out[i] = p[i] + d[i];
        out[3 + i] = ang[i];
    }
    return RP_OK;
}

void rp_pose_minus(const rp_real a[6], const rp_real b[6], rp_real d[6])
{
    rp_real w[3];
    rp_angles_minus(a + 3, b + 3, w);
    for (int i = 0; i < 3; ++i) {
        d[i] = a[i] - b[i];
        d[3 + i] = w[i];
    }
}

/* P = R_k^T (R_j^T m - D_k), m = M - d_j (eq. 2); also returns m. */
static inline void cam_point(const rp_rig_cam_t *c, const rp_pose_lin_t *pl, const rp_real M[3],
                      rp_real m[3], rp_real P[3])
{
    rp_real y[3];
    m[0] = M[0] - pl->p[0];
    m[1] = M[1] - pl->p[1];
    m[2] = M[2] - pl->p[2];
    mtv(pl->R, m, y);
    y[0] -= c->D[0];
    y[1] -= c->D[1];
    y[2] -= c->D[2];
    mtv(c->R, y, P);
}

rp_status_t rp_rig_cam_point(const rp_rig_t *rig, uint8_t k, const rp_pose_lin_t *pl,
                             const rp_real M[3], rp_real P[3])
{
    if (rig == NULL || pl == NULL || M == NULL || P == NULL || k >= rig->n_cams ||
        k >= RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(M, 3)) {
        return RP_E_NAN;
    }
    rp_real m[3];
    cam_point(&rig->cam[k], pl, M, m, P);
    return RP_OK;
}

rp_status_t rp_rig_world_point(const rp_rig_t *rig, uint8_t k, const rp_pose_lin_t *pl,
                               const rp_real P[3], rp_real M[3])
{
    if (rig == NULL || pl == NULL || M == NULL || P == NULL || k >= rig->n_cams ||
        k >= RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(P, 3)) {
        return RP_E_NAN;
    }
    const rp_rig_cam_t *c = &rig->cam[k];
    rp_real y[3];
    mv(c->R, P, y);
    y[0] += c->D[0];
    y[1] += c->D[1];
    y[2] += c->D[2];
    mv(pl->R, y, M);
    M[0] += pl->p[0];
    M[1] += pl->p[1];
    M[2] += pl->p[2];
    return RP_OK;
}

rp_status_t rp_rig_project(const rp_rig_t *rig, uint8_t k, const rp_pose_lin_t *pl,
                           const rp_real M[3], rp_real uv[2], rp_real J_pose[12],
                           rp_real J_M[6])
{
    if (rig == NULL || pl == NULL || M == NULL || uv == NULL || k >= rig->n_cams ||
        k >= RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(M, 3)) {
        return RP_E_NAN;
    }
    const rp_rig_cam_t *c = &rig->cam[k];
    rp_real m[3], P[3];
    cam_point(c, pl, M, m, P);
    if (J_pose == NULL && J_M == NULL) {
        return rp_cam_project(&c->cam, P, uv, NULL);
    }
    rp_real Jc[6];
    const rp_status_t st = rp_cam_project(&c->cam, P, uv, Jc);
    if (st != RP_OK) {
        return st;
    }
    for (int r = 0; r < 2; ++r) {
        rp_real g[3], h[3];
        mv(c->R, Jc + 3 * r, g);
        mv(pl->R, g, h);
        if (J_M != NULL) {
            J_M[3 * r] = h[0];
            J_M[3 * r + 1] = h[1];
            J_M[3 * r + 2] = h[2];
        }
        if (J_pose != NULL) {
            const rp_real hm0 = h[1] * m[2] - h[2] * m[1];
            const rp_real hm1 = h[2] * m[0] - h[0] * m[2];
            const rp_real hm2 = h[0] * m[1] - h[1] * m[0];
            rp_real *row = J_pose + 6 * r;
            row[0] = -h[0];
            row[1] = -h[1];
            row[2] = -h[2];
            row[3] = hm0;
            row[4] = hm1;
            row[5] = hm2;
        }
    }
    return RP_OK;
}
