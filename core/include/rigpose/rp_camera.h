/*
 * rp_camera.h - the pinhole camera with OpenCV's radial-tangential distortion (k1 k2 p1 p2 k3).
 *
 * Camera axes: x right, y down, z forward. Pixels (u, v), origin at the centre of the top-left
 * pixel. Normalised coordinates xn = (X/Z, Y/Z); distorted xd = distort(xn) as in OpenCV:
 *   r2 = x^2 + y^2, radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3,
 *   xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2),  yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y,
 *   u = fx xd + cx,  v = fy yd + cy.
 */
#ifndef RP_CAMERA_H
#define RP_CAMERA_H

#include "rp_opts.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint16_t width;  /* image width, pixels */
    uint16_t height; /* image height, pixels */
    rp_real fx, fy;  /* focal lengths, pixels */
    rp_real cx, cy;  /* principal point, pixels */
    rp_real k1, k2, p1, p2, k3; /* OpenCV distortion coefficients (dimensionless) */
} rp_camera_t;

/* Pinhole camera without distortion. */
rp_camera_t rp_cam_pinhole(uint16_t width, uint16_t height, rp_real fx, rp_real fy, rp_real cx,
                           rp_real cy);

/* RP_OK if the camera is usable: finite values, fx, fy > 0, width, height > 0; else RP_E_ARG
 * (non-positive focal or zero size) or RP_E_NAN. */
rp_status_t rp_cam_check(const rp_camera_t *cam);

/* Distort normalised xn into xd. J (2x2 row-major, d xd / d xn) may be NULL. RP_E_NAN. */
rp_status_t rp_cam_distort(const rp_camera_t *cam, const rp_real xn[2], rp_real xd[2],
                           rp_real J[4]);

/* Invert rp_cam_distort by Gauss-Newton (up to 20 iterations, to 1e-12 in double, 1e-6 in
 * float, in normalised units). RP_E_NO_CONVERGE if it does not get there or lands where the
 * model folds over (d xd / d xn not positive definite: no valid ray), RP_E_NAN. */
rp_status_t rp_cam_undistort(const rp_camera_t *cam, const rp_real xd[2], rp_real xn[2]);

/* Project camera-frame point P (m) to pixels uv. J (2x3 row-major, d uv / d P) may be NULL.
 * RP_E_BEHIND if P[2] < RP_MIN_DEPTH, RP_E_NAN. Does not check the image bounds. */
rp_status_t rp_cam_project(const rp_camera_t *cam, const rp_real P[3], rp_real uv[2],
                           rp_real J[6]);

/* Pixel uv to normalised coordinates xn (the ray is (xn[0], xn[1], 1)), undoing distortion.
 * Errors as rp_cam_undistort. */
rp_status_t rp_cam_unproject(const rp_camera_t *cam, const rp_real uv[2], rp_real xn[2]);

/* 1 if uv lies inside the image ([-0.5, width - 0.5) x [-0.5, height - 0.5)), else 0. */
int rp_cam_in_image(const rp_camera_t *cam, const rp_real uv[2]);

#ifdef __cplusplus
}
#endif

#endif /* RP_CAMERA_H */
