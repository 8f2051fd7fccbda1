/*
 * rp_struct.h - the structure EKF of one 3-D feature (paper sections 2.1, 2.2.2): state M, the
 * world position (m), with its 3x3 covariance, refined by each new pixel observation with the
 * pose taken as known (the paper's decoupling of pose and structure filters).
 */
#ifndef RP_STRUCT_H
#define RP_STRUCT_H

#include "rp_opts.h"
#include "rp_rig.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    rp_real M[3]; /* world position, m */
    rp_real C[6]; /* covariance, m^2, symmetric, stored xx xy xz yy yz zz */
} rp_point3_t;

/* Covariance of a point triangulated from observations in cameras cams[0..n-1] at pose pl with
 * pixel noise sigma_px: C = (sum J_M^T J_M / sigma^2)^-1. RP_E_SINGULAR if the views do not fix
 * the point (e.g. one view only), RP_E_BEHIND, RP_E_ARG. */
rp_status_t rp_struct_init(rp_point3_t *pt, const rp_rig_t *rig, const uint8_t *cams,
                           uint8_t n, const rp_pose_lin_t *pl, const rp_real M[3],
                           rp_real sigma_px);

/* EKF update of the point with pixel uv seen by camera cam at pose pl (pose as known):
 * S = J C J^T + sigma^2 I, K = C J^T S^-1, M += K r, C = (I - K J) C (kept symmetric).
 * RP_E_RANGE if the Mahalanobis distance r^T S^-1 r exceeds gate_chi2 (> 0; the point is left
 * unchanged), RP_E_BEHIND, RP_E_NAN, RP_E_ARG. */
rp_status_t rp_struct_update(rp_point3_t *pt, const rp_rig_t *rig, uint8_t cam,
                             const rp_pose_lin_t *pl, const rp_real uv[2], rp_real sigma_px,
                             rp_real gate_chi2);

#ifdef __cplusplus
}
#endif

#endif /* RP_STRUCT_H */
