/*
 * rp_lowe.c - Lowe's method: the rig pose p = [tx ty tz alpha beta gamma] from 2-D/3-D
 * correspondences in any cameras of the rig, by Levenberg-Marquardt on the weighted
 * reprojection error of eq. (2):
 *
 *   min_p  sum_i w_i |uv_i - h_k(p, M_i)|^2,     h_k: rp_rig_project of camera k = obs[i].cam.
 *
 * Each iteration accumulates the 6x6 normal equations H = sum w J^T J, g = sum w J^T r
 * directly (no stacked Jacobian), and solves (H + lambda diag(H)) dp = g by Cholesky; dp is in
 * the pose chart of rp_rig.h (translation, world-frame rotation vector) and the step is
 * p <- p [+] dp (rp_pose_plus), so the problem has no singularity at beta = +-pi/2.
 * Observations behind their camera at the current pose are left out of that evaluation.
 */
#include "rigpose/rp_lowe.h"

#include <stddef.h>

#include "priv/rp_math.h"
#include "rigpose/rp_linalg.h"

#define LOWE_NP 6

/* Damping: start, factors, bounds. */
#define LOWE_LAMBDA0 RP_C(1e-3)
#define LOWE_LAMBDA_UP RP_C(10.0)
#define LOWE_LAMBDA_DOWN RP_C(0.1)
#define LOWE_LAMBDA_MIN RP_C(1e-9)
#define LOWE_LAMBDA_MAX RP_C(1e12)

/* Smallest reciprocal condition (min/max pivot squared of the Cholesky factor of H scaled to
 * unit diagonal) for which the geometry counts as fixing the pose. Measured on the paper's rig
 * (tests/unit/test_lowe.c, H in the rotation chart): 4 cameras ~0.97, one camera alone ~1e-2;
 * collinear points (truly singular) ~1e-13 in double and up to ~4e-5 in float (rounding
 * floor), hence the float limit 1e-3: a decade below one camera, over a decade above the floor. */
#if RP_REAL_IS_FLOAT
#define LOWE_MIN_RCOND RP_C(1e-3)
#else
#define LOWE_MIN_RCOND RP_C(1e-12)
#endif

/* Normal equations of one pose. */
typedef struct {
    rp_real H[LOWE_NP * LOWE_NP]; /* sum w J^T J, pixels^2 per unit of p^2 */
    rp_real g[LOWE_NP];           /* sum w J^T r */
    rp_real cost;                 /* sum w |r|^2, pixels^2 */
    rp_real wsum;                 /* sum of the weights used */
    uint32_t used;                /* observations used (in front of their camera, w > 0) */
} lowe_normal_t;

rp_lowe_params_t rp_lowe_default_params(void)
{
    rp_lowe_params_t prm;
    prm.max_iter = 30;
#if RP_REAL_IS_FLOAT
    prm.tol_step = RP_C(1e-6);
#else
    prm.tol_step = RP_C(1e-10);
#endif
    return prm;
}

/* Evaluate the normal equations at p. RP_E_TOO_FEW when fewer than 3 observations are
 * usable (6 equations for 6 unknowns), RP_E_NAN, or rp_rig_project's RP_E_ARG. */
static rp_status_t lowe_eval(const rp_rig_t *rig, const rp_obs_t *obs, uint32_t n,
                             const rp_real p[LOWE_NP], lowe_normal_t *ne)
{
    rp_pose_lin_t pl;
    rp_status_t st = rp_pose_lin_set(&pl, p);
    if (st != RP_OK) {
        return st;
    }
    for (int i = 0; i < LOWE_NP * LOWE_NP; ++i) {
        ne->H[i] = RP_C(0.0);
    }
    for (int i = 0; i < LOWE_NP; ++i) {
        ne->g[i] = RP_C(0.0);
    }
    ne->cost = RP_C(0.0);
    ne->wsum = RP_C(0.0);
    ne->used = 0;
    for (uint32_t k = 0; k < n; ++k) {
        const rp_obs_t *o = &obs[k];
        if (!(o->w > RP_C(0.0))) {
            continue;
        }
        rp_real uv[2], J[2 * LOWE_NP];
        st = rp_rig_project(rig, o->cam, &pl, o->M, uv, J, NULL);
        if (st == RP_E_BEHIND) {
            continue;
        }
        if (st != RP_OK) {
            return st;
        }
        const rp_real r0 = o->uv[0] - uv[0], r1 = o->uv[1] - uv[1];
        const rp_real *J0 = &J[0], *J1 = &J[LOWE_NP];
        for (int i = 0; i < LOWE_NP; ++i) {
            const rp_real a0 = o->w * J0[i], a1 = o->w * J1[i];
            ne->g[i] += a0 * r0 + a1 * r1;
            for (int j = 0; j <= i; ++j) {
                ne->H[LOWE_NP * i + j] += a0 * J0[j] + a1 * J1[j];
            }
        }
        ne->cost += o->w * (r0 * r0 + r1 * r1);
        ne->wsum += o->w;
        ne->used++;
    }
    for (int i = 0; i < LOWE_NP; ++i) {
        for (int j = i + 1; j < LOWE_NP; ++j) {
            ne->H[LOWE_NP * i + j] = ne->H[LOWE_NP * j + i];
        }
    }
    if (ne->used < 3) {
        return RP_E_TOO_FEW;
    }
    if (!rp_finite(ne->cost) || !rp_all_finite(ne->H, LOWE_NP * LOWE_NP)) {
        return RP_E_NAN;
    }
    return RP_OK;
}

/* Solve (H + lambda diag(H)) dp = g. RP_E_SINGULAR if the damped matrix is not positive
 * definite. */
static rp_status_t lowe_step(const lowe_normal_t *ne, rp_real lambda, rp_real dp[LOWE_NP])
{
    rp_real A[LOWE_NP * LOWE_NP];
    for (int i = 0; i < LOWE_NP * LOWE_NP; ++i) {
        A[i] = ne->H[i];
    }
    for (int i = 0; i < LOWE_NP; ++i) {
        A[LOWE_NP * i + i] *= RP_C(1.0) + lambda;
        dp[i] = ne->g[i];
    }
    rp_mat_t Am = RP_MAT(LOWE_NP, LOWE_NP, A), bm = RP_MAT(LOWE_NP, 1, dp);
    rp_status_t st = rp_la_chol(&Am, &Am);
    if (st == RP_OK) {
        st = rp_la_chol_solve(&Am, &bm, &bm);
    }
    if (st == RP_OK && !rp_all_finite(dp, LOWE_NP)) {
        st = RP_E_SINGULAR;
    }
    return st;
}

/* Does H fix all 6 parameters? Cholesky of D^-1/2 H D^-1/2 (D = diag(H), so units of
 * translation and angle do not matter), then the ratio of the smallest to the largest
 * squared pivot. RP_E_SINGULAR if not. */
static rp_status_t lowe_check_rank(const rp_real H[LOWE_NP * LOWE_NP])
{
    rp_real d[LOWE_NP], A[LOWE_NP * LOWE_NP];
    for (int i = 0; i < LOWE_NP; ++i) {
        if (!(H[LOWE_NP * i + i] > RP_C(0.0))) {
            return RP_E_SINGULAR;
        }
        d[i] = RP_C(1.0) / rp_sqrt(H[LOWE_NP * i + i]);
    }
    for (int i = 0; i < LOWE_NP; ++i) {
        for (int j = 0; j < LOWE_NP; ++j) {
            A[LOWE_NP * i + j] = d[i] * H[LOWE_NP * i + j] * d[j];
        }
    }
    rp_mat_t Am = RP_MAT(LOWE_NP, LOWE_NP, A);
    if (rp_la_chol(&Am, &Am) != RP_OK) {
        return RP_E_SINGULAR;
    }
    rp_real lo = A[0], hi = A[0];
    for (int i = 1; i < LOWE_NP; ++i) {
        const rp_real l = A[LOWE_NP * i + i];
        lo = l < lo ? l : lo;
        hi = l > hi ? l : hi;
    }
    if (!(lo * lo > LOWE_MIN_RCOND * hi * hi)) {
        return RP_E_SINGULAR;
    }
    return RP_OK;
}

rp_status_t rp_lowe_solve(const rp_rig_t *rig, const rp_obs_t *obs, uint32_t n,
                          const rp_lowe_params_t *prm, rp_real p[6], rp_real *rms_px,
                          rp_real cov[36])
{
    if (rig == NULL || p == NULL || (obs == NULL && n > 0)) {
        return RP_E_ARG;
    }
    const rp_lowe_params_t def = rp_lowe_default_params();
    if (prm == NULL) {
        prm = &def;
    }
    if (prm->max_iter == 0 || !(prm->tol_step >= RP_C(0.0))) {
        return RP_E_ARG;
    }
    if (n < 3) {
        return RP_E_TOO_FEW;
    }
    if (!rp_all_finite(p, LOWE_NP)) {
        return RP_E_NAN;
    }
    for (uint32_t k = 0; k < n; ++k) {
        if (!rp_all_finite(obs[k].uv, 2) || !rp_all_finite(obs[k].M, 3) ||
            !rp_finite(obs[k].w)) {
            return RP_E_NAN;
        }
        if (obs[k].cam >= rig->n_cams || obs[k].w < RP_C(0.0)) {
            return RP_E_ARG;
        }
    }

    static const lowe_normal_t zero_ne;
    lowe_normal_t cur = zero_ne, trial = zero_ne;
    rp_status_t st = lowe_eval(rig, obs, n, p, &cur);
    if (st != RP_OK) {
        return st;
    }

    rp_real lambda = LOWE_LAMBDA0;
    int converged = 0;
    for (uint16_t it = 0; it < prm->max_iter && !converged; ++it) {
        rp_real dp[LOWE_NP];
        st = lowe_step(&cur, lambda, dp);
        if (st != RP_OK) {
            if (lambda >= LOWE_LAMBDA_MAX) {
                break;
            }
            lambda *= LOWE_LAMBDA_UP;
            continue;
        }
        rp_real step2 = RP_C(0.0);
        for (int i = 0; i < LOWE_NP; ++i) {
            step2 += dp[i] * dp[i];
        }
        const int small = rp_sqrt(step2) <= prm->tol_step;

        rp_real pn[LOWE_NP];
        st = rp_pose_plus(p, dp, pn);
        if (st == RP_OK) {
            st = lowe_eval(rig, obs, n, pn, &trial);
        }
        /* Accept a step that brings more observations in front of their cameras, or keeps
         * the same ones and does not raise the cost; losing observations is a rejection. */
        const int better = st == RP_OK &&
                           (trial.used > cur.used ||
                            (trial.used == cur.used && trial.cost <= cur.cost));
        if (better) {
            for (int i = 0; i < LOWE_NP; ++i) {
                p[i] = pn[i];
            }
            cur = trial;
            lambda *= LOWE_LAMBDA_DOWN;
            if (lambda < LOWE_LAMBDA_MIN) {
                lambda = LOWE_LAMBDA_MIN;
            }
        } else if (st != RP_OK && st != RP_E_TOO_FEW) {
            return st; /* RP_E_NAN: the model broke down, p holds the last good pose */
        } else {
            if (lambda >= LOWE_LAMBDA_MAX) {
                converged = 1; /* no descent even for a vanishing step */
            }
            lambda *= LOWE_LAMBDA_UP;
        }
        if (small || cur.cost <= RP_C(0.0)) {
            converged = 1;
        }
    }

    if (rms_px != NULL) {
        /* Weighted RMS per pixel coordinate (u and v each count): sigma_px when the residuals
         * are the noise. */
        *rms_px = rp_sqrt(cur.cost / (RP_C(2.0) * cur.wsum));
    }
    st = lowe_check_rank(cur.H);
    if (st != RP_OK) {
        return st;
    }
    if (cov != NULL) {
        /* Covariance of p for unit pixel noise: (J^T W J)^-1 at the estimate. */
        rp_mat_t Hm = RP_MAT(LOWE_NP, LOWE_NP, cur.H), Cm = RP_MAT(LOWE_NP, LOWE_NP, cov);
        st = rp_la_inv_spd(&Hm, &Cm);
        if (st != RP_OK) {
            return st;
        }
    }
    return converged ? RP_OK : RP_E_NO_CONVERGE;
}
