/*
 * rp_camera.c - pinhole projection with OpenCV's radial-tangential distortion (model and
 * notation in rp_camera.h), its Jacobians and its Gauss-Newton inverse.
 */
#include "rigpose/rp_camera.h"

#include <stddef.h>

#include "priv/rp_math.h"

#if RP_REAL_IS_FLOAT
#define UNDISTORT_TOL RP_C(1e-6) /* normalised units */
#else
#define UNDISTORT_TOL RP_C(1e-12)
#endif
#define UNDISTORT_ITERS 20

rp_camera_t rp_cam_pinhole(uint16_t width, uint16_t height, rp_real fx, rp_real fy, rp_real cx,
                           rp_real cy)
{
    rp_camera_t c;
    c.width = width;
    c.height = height;
    c.fx = fx;
    c.fy = fy;
    c.cx = cx;
    c.cy = cy;
    c.k1 = c.k2 = c.p1 = c.p2 = c.k3 = RP_C(0.0);
    return c;
}

rp_status_t rp_cam_check(const rp_camera_t *cam)
{
    if (cam == NULL) {
        return RP_E_ARG;
    }
    const rp_real v[9] = {cam->fx, cam->fy, cam->cx, cam->cy, cam->k1,
                          cam->k2, cam->p1, cam->p2, cam->k3};
    if (!rp_all_finite(v, 9)) {
        return RP_E_NAN;
    }
    if (!(cam->fx > RP_C(0.0)) || !(cam->fy > RP_C(0.0)) || cam->width == 0 ||
        cam->height == 0) {
        return RP_E_ARG;
    }
    return RP_OK;
}

/* The model without checks. J (d xd / d xn, 2x2) may be NULL:
 *   d xd/dx = radial + 2 x^2 dr + 2 p1 y + 6 p2 x,   d xd/dy = 2 x y dr + 2 p1 x + 2 p2 y,
 *   d yd/dx = 2 x y dr + 2 p1 x + 2 p2 y,            d yd/dy = radial + 2 y^2 dr + 6 p1 y + 2 p2 x,
 * with dr = d radial / d r2 = k1 + 2 k2 r2 + 3 k3 r2^2. */
static void distort(const rp_camera_t *c, rp_real x, rp_real y, rp_real xd[2], rp_real J[4])
{
    const rp_real xx = x * x, yy = y * y, xy = x * y;
    const rp_real r2 = xx + yy;
    const rp_real radial = RP_C(1.0) + r2 * (c->k1 + r2 * (c->k2 + r2 * c->k3));
    xd[0] = x * radial + RP_C(2.0) * c->p1 * xy + c->p2 * (r2 + RP_C(2.0) * xx);
    xd[1] = y * radial + c->p1 * (r2 + RP_C(2.0) * yy) + RP_C(2.0) * c->p2 * xy;
    if (J != NULL) {
        const rp_real dr = c->k1 + r2 * (RP_C(2.0) * c->k2 + RP_C(3.0) * c->k3 * r2);
        const rp_real off = RP_C(2.0) * (xy * dr + c->p1 * x + c->p2 * y);
        J[0] = radial + RP_C(2.0) * xx * dr + RP_C(2.0) * c->p1 * y + RP_C(6.0) * c->p2 * x;
        J[1] = off;
        J[2] = off;
        J[3] = radial + RP_C(2.0) * yy * dr + RP_C(6.0) * c->p1 * y + RP_C(2.0) * c->p2 * x;
    }
}

rp_status_t rp_cam_distort(const rp_camera_t *cam, const rp_real xn[2], rp_real xd[2],
                           rp_real J[4])
{
    if (cam == NULL || xn == NULL || xd == NULL) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(xn, 2)) {
        return RP_E_NAN;
    }
    distort(cam, xn[0], xn[1], xd, J);
    return RP_OK;
}

/* Newton on the 2x2 system distort(xn) = xd (Gauss-Newton with a square Jacobian), from
 * xn = xd. Stops when the step is below UNDISTORT_TOL in both coordinates; J is taken at the
 * last iterate, which differs from the root by at most the step. */
rp_status_t rp_cam_undistort(const rp_camera_t *cam, const rp_real xd[2], rp_real xn[2])
{
    if (cam == NULL || xd == NULL || xn == NULL) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(xd, 2)) {
        return RP_E_NAN;
    }
    rp_real x = xd[0], y = xd[1];
    for (int it = 0; it < UNDISTORT_ITERS; ++it) {
        rp_real f[2], J[4];
        distort(cam, x, y, f, J);
        const rp_real ex = f[0] - xd[0], ey = f[1] - xd[1];
        const rp_real det = J[0] * J[3] - J[1] * J[2];
        if (!(rp_fabs(det) > RP_REAL_EPS) || !rp_finite(ex) || !rp_finite(ey)) {
            return RP_E_NO_CONVERGE;
        }
        const rp_real dx = (J[3] * ex - J[1] * ey) / det;
        const rp_real dy = (J[0] * ey - J[2] * ex) / det;
        x -= dx;
        y -= dy;
        if (rp_fabs(dx) <= UNDISTORT_TOL && rp_fabs(dy) <= UNDISTORT_TOL) {
            /* The Jacobian is symmetric; a root where it is not positive definite lies
             * beyond the fold of the model (e.g. past the maximum of x (1 + k1 x^2), k1 < 0)
             * and is not the pixel's ray. */
            if (!rp_finite(x) || !rp_finite(y) || !(J[0] > RP_C(0.0)) || !(det > RP_C(0.0))) {
                return RP_E_NO_CONVERGE;
            }
            xn[0] = x;
            xn[1] = y;
            return RP_OK;
        }
    }
    return RP_E_NO_CONVERGE;
}

/* uv = diag(fx, fy) xd + c;  J = diag(fx, fy) Jd [1/Z 0 -x/Z; 0 1/Z -y/Z], x = X/Z, y = Y/Z. */
rp_status_t rp_cam_project(const rp_camera_t *cam, const rp_real P[3], rp_real uv[2],
                           rp_real J[6])
{
    if (cam == NULL || P == NULL || uv == NULL) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(P, 3)) {
        return RP_E_NAN;
    }
    if (P[2] < RP_C(RP_MIN_DEPTH)) {
        return RP_E_BEHIND;
    }
    const rp_real iz = RP_C(1.0) / P[2];
    const rp_real x = P[0] * iz, y = P[1] * iz;
    rp_real xd[2];
    if (J == NULL) {
        distort(cam, x, y, xd, NULL);
    } else {
        rp_real Jd[4];
        distort(cam, x, y, xd, Jd);
        const rp_real a = cam->fx * iz, b = cam->fy * iz;
        const rp_real j0 = a * Jd[0], j1 = a * Jd[1], j2 = b * Jd[2], j3 = b * Jd[3];
        J[0] = j0;
        J[1] = j1;
        J[2] = -(j0 * x + j1 * y);
        J[3] = j2;
        J[4] = j3;
        J[5] = -(j2 * x + j3 * y);
    }
    uv[0] = cam->fx * xd[0] + cam->cx;
    uv[1] = cam->fy * xd[1] + cam->cy;
    return RP_OK;
}

rp_status_t rp_cam_unproject(const rp_camera_t *cam, const rp_real uv[2], rp_real xn[2])
{
    if (cam == NULL || uv == NULL || xn == NULL) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(uv, 2)) {
        return RP_E_NAN;
    }
    const rp_real xd[2] = {(uv[0] - cam->cx) / cam->fx, (uv[1] - cam->cy) / cam->fy};
    return rp_cam_undistort(cam, xd, xn);
}

int rp_cam_in_image(const rp_camera_t *cam, const rp_real uv[2])
{
    const rp_real lo = RP_C(-0.5);
    return uv[0] >= lo && uv[0] < (rp_real)cam->width + lo && uv[1] >= lo &&
           uv[1] < (rp_real)cam->height + lo;
}
