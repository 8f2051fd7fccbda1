/*
 * rp_stereo.h - a calibrated stereo pair: its fixed fundamental matrix, the epipolar check of
 * candidate matches, and triangulation.
 *
 * The pair is (a, b): two cameras of the rig. Their relative pose comes from the rig
 * extrinsics: a point P_a in camera a has P_b = R_ab^T (P_a - t_ab) in camera b, where
 * R_ab = R_a^T R_b and t_ab = R_a^T (D_b - D_a) (camera b's pose in camera a's frame).
 * F acts on undistorted pixel coordinates: x_b^T F x_a = 0.
 */
#ifndef RP_STEREO_H
#define RP_STEREO_H

#include "rp_opts.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint8_t a, b;       /* camera indices in the rig */
    rp_real R_ab[9];    /* rotation of camera b in camera a's frame */
    rp_real t_ab[3];    /* position of camera b in camera a's frame, m */
    rp_real E[9];       /* essential matrix on normalised coordinates: xb^T E xa = 0 */
    rp_real F[9];       /* fundamental matrix on undistorted pixels: xb^T F xa = 0 */
    rp_real baseline_m; /* |t_ab|, m */
} rp_stereo_pair_t;

/* Build the pair of cameras a and b of the rig. RP_E_ARG (bad index, a == b),
 * RP_E_DEGENERATE (baseline under 1 mm). */
rp_status_t rp_stereo_pair_init(const rp_rig_t *rig, uint8_t a, uint8_t b, rp_stereo_pair_t *sp);

/* Symmetric epipolar distance of a candidate match (pixels: the larger of the distances of
 * each point to the other's epipolar line, on undistorted pixels). RP_E_NAN, or the
 * undistortion's error. */
rp_status_t rp_stereo_epipolar_px(const rp_rig_t *rig, const rp_stereo_pair_t *sp,
                                  const rp_real uv_a[2], const rp_real uv_b[2], rp_real *dist_px);

/* Triangulate a match into camera a's frame (P_a, m): linear (midpoint of the rays), then
 * Gauss-Newton on the reprojection error in both images. reproj_px (may be NULL): the larger
 * reprojection error of the two images after refinement.
 * RP_E_BEHIND (the point is not in front of both cameras), RP_E_DEGENERATE (rays parallel: no
 * depth), RP_E_NAN, RP_E_ARG. */
rp_status_t rp_stereo_triangulate(const rp_rig_t *rig, const rp_stereo_pair_t *sp,
                                  const rp_real uv_a[2], const rp_real uv_b[2], rp_real P_a[3],
                                  rp_real *reproj_px);

#ifdef __cplusplus
}
#endif

#endif /* RP_STEREO_H */
