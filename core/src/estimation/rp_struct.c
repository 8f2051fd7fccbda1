/*
 * rp_struct.c - the per-feature structure EKF (see rp_struct.h). Fixed 3x3 algebra inline.
 */
#include <string.h>

#include "priv/rp_inv3.h"
#include "priv/rp_math.h"
#include "priv/rp_sym3.h"
#include "rigpose/rp_struct.h"


RP_DEFINE_INV3_SPD(inv3_spd, rp_real)

rp_status_t rp_struct_init(rp_point3_t *pt, const rp_rig_t *rig, const uint8_t *cams,
                           uint8_t n, const rp_pose_lin_t *pl, const rp_real M[3],
                           rp_real sigma_px)
{
    if (!pt || !rig || !cams || !pl || !M || n == 0 || !(sigma_px > RP_C(0.0))) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(M, 3)) {
        return RP_E_NAN;
    }
    rp_real info[9] = {0};
    for (uint8_t i = 0; i < n; ++i) {
        rp_real uv[2], J[6];
        rp_status_t st = rp_rig_project(rig, cams[i], pl, M, uv, NULL, J);
        if (st != RP_OK) {
            return st;
        }
        for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3; ++b) {
                info[a * 3 + b] += J[a] * J[b] + J[3 + a] * J[3 + b];
            }
        }
    }
    rp_real C[9];
    rp_status_t st = inv3_spd(info, C) ? RP_OK : RP_E_SINGULAR;
    if (st != RP_OK) {
        return st;
    }
    const rp_real s2 = sigma_px * sigma_px;
    for (int i = 0; i < 9; ++i) {
        C[i] *= s2;
    }
    memcpy(pt->M, M, sizeof(pt->M));
    rp_sym3_pack(C, pt->C);
    return RP_OK;
}

rp_status_t rp_struct_update(rp_point3_t *pt, const rp_rig_t *rig, uint8_t cam,
                             const rp_pose_lin_t *pl, const rp_real uv[2], rp_real sigma_px,
                             rp_real gate_chi2)
{
    if (!pt || !rig || !pl || !uv || !(sigma_px > RP_C(0.0))) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(uv, 2)) {
        return RP_E_NAN;
    }
    rp_real h[2], J[6], C[9];
    rp_status_t st = rp_rig_project(rig, cam, pl, pt->M, h, NULL, J);
    if (st != RP_OK) {
        return st;
    }
    rp_sym3_unpack(pt->C, C);
    /* CJt = C J^T (3x2), S = J C J^T + s2 I (2x2) */
    rp_real CJt[6], S[4];
    for (int a = 0; a < 3; ++a) {
        for (int r = 0; r < 2; ++r) {
            CJt[a * 2 + r] = C[a * 3 + 0] * J[r * 3 + 0] + C[a * 3 + 1] * J[r * 3 + 1] +
                             C[a * 3 + 2] * J[r * 3 + 2];
        }
    }
    const rp_real s2 = sigma_px * sigma_px;
    for (int r = 0; r < 2; ++r) {
        for (int q = 0; q < 2; ++q) {
            S[r * 2 + q] = J[r * 3 + 0] * CJt[0 * 2 + q] + J[r * 3 + 1] * CJt[1 * 2 + q] +
                           J[r * 3 + 2] * CJt[2 * 2 + q] + (r == q ? s2 : RP_C(0.0));
        }
    }
    const rp_real det = S[0] * S[3] - S[1] * S[2];
    if (!(det > RP_C(0.0))) {
        return RP_E_SINGULAR;
    }
    const rp_real Si[4] = {S[3] / det, -S[1] / det, -S[2] / det, S[0] / det};
    const rp_real r0 = uv[0] - h[0], r1 = uv[1] - h[1];
    const rp_real d2 = r0 * (Si[0] * r0 + Si[1] * r1) + r1 * (Si[2] * r0 + Si[3] * r1);
    if (gate_chi2 > RP_C(0.0) && d2 > gate_chi2) {
        return RP_E_RANGE;
    }
    /* K = C J^T S^-1 (3x2) */
    rp_real K[6];
    for (int a = 0; a < 3; ++a) {
        K[a * 2 + 0] = CJt[a * 2 + 0] * Si[0] + CJt[a * 2 + 1] * Si[2];
        K[a * 2 + 1] = CJt[a * 2 + 0] * Si[1] + CJt[a * 2 + 1] * Si[3];
    }
    rp_real Mn[3], Cn[9];
    for (int a = 0; a < 3; ++a) {
        Mn[a] = pt->M[a] + K[a * 2 + 0] * r0 + K[a * 2 + 1] * r1;
    }
    /* C+ = C - K (C J^T)^T */
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            Cn[a * 3 + b] = C[a * 3 + b] - (K[a * 2 + 0] * CJt[b * 2 + 0] +
                                             K[a * 2 + 1] * CJt[b * 2 + 1]);
        }
    }
    if (!rp_all_finite(Mn, 3) || !rp_all_finite(Cn, 9) || !(Cn[0] > RP_C(0.0)) ||
        !(Cn[4] > RP_C(0.0)) || !(Cn[8] > RP_C(0.0))) {
        return RP_E_SINGULAR;
    }
    memcpy(pt->M, Mn, sizeof(Mn));
    rp_sym3_pack(Cn, pt->C);
    return RP_OK;
}
