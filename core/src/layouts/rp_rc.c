/*
 * rp_rc.c - rigidity constraints of the paper (see rp_rc.h).
 */
#include <string.h>

#include "priv/rp_math.h"
#include "rigpose/rp_frame.h"
#include "rigpose/rp_linalg.h"
#include "rigpose/rp_rc.h"
#include "rigpose/rp_rot.h"

rp_rc_params_t rp_rc_default_params(void)
{
    rp_rc_params_t p;
    p.min_trans_m = RP_C(1e-3);
    p.min_scale = RP_C(0.25);
    p.max_scale = RP_C(4.0);
    p.max_scale_se = RP_C(0.1);
    return p;
}

rp_status_t rp_rc_median(const rp_real *v, uint8_t n, rp_real *med)
{
    if (!v || !med || n < 1 || n > 16) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(v, n)) {
        return RP_E_NAN;
    }
    rp_real s[16];
    memcpy(s, v, (size_t)n * sizeof(rp_real));
    for (uint8_t i = 1; i < n; ++i) { /* insertion sort: n is tiny */
        rp_real x = s[i];
        int j = (int)i - 1;
        while (j >= 0 && s[j] > x) {
            s[j + 1] = s[j];
            --j;
        }
        s[j + 1] = x;
    }
    *med = (n & 1u) ? s[n / 2] : RP_C(0.5) * (s[n / 2 - 1] + s[n / 2]);
    return RP_OK;
}

static int is_reference(const rp_rig_cam_t *c)
{
    for (int i = 0; i < 9; ++i) {
        const rp_real want = (i % 4 == 0) ? RP_C(1.0) : RP_C(0.0);
        if (rp_fabs(c->R[i] - want) > RP_C(1e-6)) {
            return 0;
        }
    }
    return rp_fabs(c->D[0]) <= RP_C(1e-9) && rp_fabs(c->D[1]) <= RP_C(1e-9) &&
           rp_fabs(c->D[2]) <= RP_C(1e-9);
}

rp_status_t rp_rc_fuse(const rp_rig_t *rig, const uint8_t *cams, uint8_t n,
                       const rp_real (*p_own)[6], const rp_rc_params_t *prm,
                       rp_real fallback_scale, rp_real p_rig[6], rp_real *s, uint32_t *flags)
{
    if (!rig || !cams || !p_own || !prm || !p_rig || n < 2 || n > RP_RC_MAX_CAMS ||
        !(fallback_scale > RP_C(0.0)) || !rp_finite(fallback_scale) ||
        !(prm->min_trans_m >= RP_C(0.0)) || !(prm->min_scale > RP_C(0.0)) ||
        !(prm->max_scale > prm->min_scale)) {
        return RP_E_ARG;
    }
    for (uint8_t i = 0; i < n; ++i) {
        if (cams[i] >= rig->n_cams || cams[i] >= RP_MAX_CAMS) {
            return RP_E_ARG;
        }
        if (!rp_all_finite(p_own[i], 6)) {
            return RP_E_NAN;
        }
    }
    if (!is_reference(&rig->cam[cams[0]])) {
        return RP_E_ARG;
    }

    /* Rotation: eq. (3) per camera, then the per-axis median in the chart of rp_rig.h at the
     * reference camera's R_1j: w_i = Log(R_kj R_1j^T), R_j = Exp(median w) R_1j. The paper's
     * per-angle median is not defined near beta = +-pi/2, where alpha and gamma of nearby
     * rotations are far apart (only their sum or difference is determined). */
    rp_real w[3][RP_RC_MAX_CAMS], Rref[9];
    for (uint8_t i = 0; i < n; ++i) {
        const rp_real *Rk = rig->cam[cams[i]].R;
        rp_real r[9], Rkj[9], wi[3];
        rp_rot_from_angles(&p_own[i][3], r);
        rp_rot_mul(Rk, r, Rkj);
        rp_rot_mul_a_bt(Rkj, Rk, Rkj);
        if (i == 0) {
            memcpy(Rref, Rkj, sizeof(Rref));
        }
        rp_rot_mul_a_bt(Rkj, Rref, Rkj);
        rp_rot_log(Rkj, wi);
        for (int c = 0; c < 3; ++c) {
            w[c][i] = wi[c];
        }
    }
    rp_real out[6], wm[3], Rj[9];
    for (int c = 0; c < 3; ++c) {
        rp_status_t st = rp_rc_median(w[c], n, &wm[c]);
        if (st != RP_OK) {
            return st;
        }
    }
    rp_rot_exp(wm, Rj);
    rp_rot_mul(Rj, Rref, Rj);
    rp_status_t st_ang = rp_rot_to_angles(Rj, &out[3]);
    if (st_ang != RP_OK) {
        return st_ang;
    }

    /* Translation: A s = b (eqs. 5-7). */
    const rp_real *d = p_own[0]; /* d_j = l_1j */
    const uint16_t m = (uint16_t)(3u * (n - 1u));
    rp_real A[3 * (RP_RC_MAX_CAMS - 1) * RP_RC_MAX_CAMS];
    rp_real b[3 * (RP_RC_MAX_CAMS - 1)];
    rp_real x[RP_RC_MAX_CAMS];
    memset(A, 0, sizeof(A));
    for (uint8_t i = 1; i < n; ++i) {
        const rp_rig_cam_t *ck = &rig->cam[cams[i]];
        rp_real Rl[3], RD[3];
        rp_rot_apply(ck->R, p_own[i], Rl);
        rp_rot_apply(Rj, ck->D, RD);
        for (int c = 0; c < 3; ++c) {
            const int row = 3 * (i - 1) + c;
            A[row * n + 0] = d[c];
            A[row * n + i] = -Rl[c];
            b[row] = ck->D[c] - RD[c];
        }
    }
    const rp_real dn = rp_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    int weak = !(dn >= prm->min_trans_m);
    if (!weak) {
        rp_mat_t Am = RP_MAT(m, n, A), bm = RP_MAT(m, 1, b), xm = RP_MAT(n, 1, x);
        rp_status_t st = rp_la_lstsq(&Am, &bm, &xm);
        if (st != RP_OK || !rp_all_finite(x, n) || !(x[0] >= prm->min_scale) ||
            !(x[0] <= prm->max_scale)) {
            weak = 1;
        }
        for (uint8_t i = 1; i < n && !weak; ++i) {
            if (!(x[i] > RP_C(0.0))) {
                weak = 1;
            }
        }
        if (!weak && prm->max_scale_se > RP_C(0.0) && m > n) {
            /* Standard error of S_j: sqrt(|A s - b|^2 / (m - n) * ((A^T A)^-1)_00). */
            rp_real r2 = RP_C(0.0);
            for (uint16_t row = 0; row < m; ++row) {
                rp_real r = -b[row];
                for (uint8_t c = 0; c < n; ++c) {
                    r += A[row * n + c] * x[c];
                }
                r2 += r * r;
            }
            rp_real N[RP_RC_MAX_CAMS * RP_RC_MAX_CAMS], Ni[RP_RC_MAX_CAMS * RP_RC_MAX_CAMS];
            rp_mat_t Nm = RP_MAT(n, n, N), Nim = RP_MAT(n, n, Ni);
            if (rp_la_mul_at_b(&Am, &Am, &Nm) != RP_OK || rp_la_inv_spd(&Nm, &Nim) != RP_OK) {
                weak = 1;
            } else {
                const rp_real var = r2 / (rp_real)(m - n) * Ni[0];
                if (!(var <= prm->max_scale_se * prm->max_scale_se)) {
                    weak = 1;
                }
            }
        }
    }
    if (weak) {
        /* Fallback: S_j = fallback_scale; each S_kj then is whatever eq. (5) gives for it alone
         * when its camera moved, else the fallback too. */
        x[0] = fallback_scale;
        for (uint8_t i = 1; i < n; ++i) {
            rp_real num = RP_C(0.0), den = RP_C(0.0);
            for (int c = 0; c < 3; ++c) {
                const int row = 3 * (i - 1) + c;
                const rp_real a = -A[row * n + i];
                num += a * (x[0] * d[c] - b[row]);
                den += a * a;
            }
            x[i] = den > RP_C(1e-12) ? num / den : fallback_scale;
        }
    }
    for (int c = 0; c < 3; ++c) {
        out[c] = x[0] * d[c];
    }
    memcpy(p_rig, out, sizeof(out));
    if (s) {
        memcpy(s, x, (size_t)n * sizeof(rp_real));
    }
    if (weak && flags) {
        *flags |= RP_EST_SCALE_WEAK;
    }
    return weak ? RP_E_DEGENERATE : RP_OK;
}
