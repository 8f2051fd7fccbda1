/*
 * rp_p3p.h - the perspective-three-point problem: the pose of one calibrated camera from three
 * bearing vectors and their three world points, by Lambda Twist (M. Persson, K. Nordberg,
 * "Lambda Twist: An Accurate Fast Robust Perspective Three Point (P3P) Solver", ECCV 2018).
 *
 * Convention (world -> camera): a world point X has camera coordinates  Xc = R X + t,  and
 * bearing y_i = Xc_i / |Xc_i|. For camera k of a rig at rig pose (d_j, R_j), eq. (2) of the
 * paper gives R = R_k^T R_j^T and t = -R_k^T (R_j^T d_j + D_k); rp_ransac.h converts back.
 *
 * The method (paper's section numbers): with b_ij = y_i . y_j and a_ij = |x_i - x_j|^2, the
 * unknown depths L = (l1, l2, l3) solve the three quadrics (eq. 4 of Lambda Twist)
 *     L^T M_ij L = l_i^2 + l_j^2 - 2 b_ij l_i l_j = a_ij .
 * Eliminating the scale gives two homogeneous conics D1 = a23 M12 - a12 M23 and
 * D2 = a23 M13 - a13 M23; a real root g of the cubic det(D1 + g D2) = 0 gives a degenerate
 * conic D0 = D1 + g D2 (a pair of planes through the origin). D0's eigen-decomposition, with
 * its known zero eigenvalue, splits it into two planes n.L = 0; each plane meets one remaining
 * ratio equation in at most two rays; the scale follows from a_ij; the depths are refined by a
 * few verified Gauss-Newton steps on the three quadrics (the paper's section 3.8), and (R, t)
 * from the two triangles {x_i} and {l_i y_i}. Up to four solutions.
 *
 * rigpose's choices where the paper leaves room: every real root of the cubic is a candidate and
 * the one whose degenerate conic splits best (most negative normalised product of its two
 * non-zero eigenvalues) is used; the cubic is solved in g or in 1/g (whichever is better
 * conditioned) and each root is polished by Newton steps on the cubic; the ratio equation is
 * chosen so that it is independent of D0 (13/23 when |g| <= 1, else 12/23); R is built from
 * orthonormal frames of the two triangles, so it is a rotation even on noisy input.
 */
#ifndef RP_P3P_H
#define RP_P3P_H

#include "rp_opts.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* At most four poses explain three correspondences. */
#define RP_P3P_MAX_SOLS 4

typedef struct {
    rp_real R[9]; /* world -> camera rotation, row-major: Xc = R X + t */
    rp_real t[3]; /* world origin in camera coordinates, m */
} rp_p3p_pose_t;

/* Solve P3P. y: three bearing vectors (camera frame, any non-zero length; normalised here);
 * X: their world points, m. sol: room for RP_P3P_MAX_SOLS poses; *n_sol: how many were found
 * (0..4; 0 is possible on noisy or inconsistent data), every one with all three points in front
 * of the camera (positive depth).
 * RP_E_ARG (a NULL pointer), RP_E_NAN (a non-finite input), RP_E_DEGENERATE (a zero bearing,
 * two bearings along the same ray, coincident or collinear world points: the answer is not
 * determined). */
rp_status_t rp_p3p_solve(const rp_real y[3][3], const rp_real X[3][3],
                         rp_p3p_pose_t sol[RP_P3P_MAX_SOLS], uint8_t *n_sol);

#ifdef __cplusplus
}
#endif

#endif /* RP_P3P_H */
