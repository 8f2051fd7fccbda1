/*
 * rp_ekf.c - the 12-state pose EKF (paper section 2.1), iterated, in a numerically careful form.
 *
 * Notation: x = [p; v], p the pose (6), v its rate (6); P = [Ppp Ppv; Pvp Pvv], in the pose
 * chart of rp_rig.h (d = [dt; w], R = Exp(w) R^): the angles of x are the mean's
 * representation, never differentiated nor added to.
 * The measurements see only p, so the update is a 6-dimensional problem with prior (p0, Ppp):
 *   minimise d^T Ppp^-1 d + sum_i w_i/s^2 |z_i - h_i(p0 [+] d)|^2.
 * Gauss-Newton at iterate d_k, with A = sum J^T W J and b = sum J^T W (r + J d_k), J the
 * Jacobian in the chart at p0 [+] d_k (the chart's own Jacobian between d_k and a step at the
 * iterate, I + O(|w_k|), is taken as I: |w_k| is the update's size, a few mrad):
 *   d_{k+1} = (Ppp^-1 + A)^-1 b,   p_{k+1} = p0 [+] d_{k+1}.
 * With Ppp = L L^T and S = I + L^T A L (S >= I: well conditioned even in float),
 *   (Ppp^-1 + A)^-1 = L S^-1 L^T = Ppp+                                      (posterior pose cov)
 * The rate follows by conditioning on the pose posterior, with M = Ppp^-1 Ppv:
 *   v+ = v0 + M^T d,   Ppv+ = Ppp+ M,   Pvv+ = Pvv - M^T (Ppp - Ppp+) M.
 */
#include <string.h>

#include "priv/rp_math.h"
#include "rigpose/rp_ekf.h"
#include "rigpose/rp_linalg.h"
#include "rigpose/rp_rot.h"

#define N RP_EKF_N
#define NP 6

rp_ekf_params_t rp_ekf_default_params(void)
{
    rp_ekf_params_t p;
    p.sigma_px = RP_C(0.5);
    p.q_trans = RP_C(1.0);
    p.q_rot = RP_C(1.0);
    p.gate_chi2 = RP_C(13.8);
    p.iterations = 3;
    p.min_features = 6;
    p.max_predict_s = RP_C(1.0);
    return p;
}

static rp_status_t check_params(const rp_ekf_params_t *prm)
{
    if (!rp_finite(prm->sigma_px) || !rp_finite(prm->q_trans) || !rp_finite(prm->q_rot) ||
        !rp_finite(prm->gate_chi2) || !rp_finite(prm->max_predict_s)) {
        return RP_E_NAN;
    }
    if (prm->sigma_px <= RP_C(0.0) || prm->q_trans < RP_C(0.0) || prm->q_rot < RP_C(0.0) ||
        prm->iterations == 0 || prm->min_features < 3 || !(prm->max_predict_s > RP_C(0.0))) {
        return RP_E_ARG;
    }
    return RP_OK;
}

rp_status_t rp_ekf_init(rp_ekf_t *ekf, const rp_ekf_params_t *prm, const rp_real x0[N],
                        const rp_real P0diag[N])
{
    if (!ekf || !prm || !x0 || !P0diag) {
        return RP_E_ARG;
    }
    rp_status_t st = check_params(prm);
    if (st != RP_OK) {
        return st;
    }
    if (!rp_all_finite(x0, N) || !rp_all_finite(P0diag, N)) {
        return RP_E_NAN;
    }
    for (int i = 0; i < N; ++i) {
        if (P0diag[i] <= RP_C(0.0)) {
            return RP_E_ARG;
        }
    }
    /* The inputs may point into *ekf itself (re-initialising in place): copy them first. */
    const rp_ekf_params_t prm_copy = *prm;
    rp_real x_copy[N], d_copy[N];
    memcpy(x_copy, x0, sizeof(x_copy));
    memcpy(d_copy, P0diag, sizeof(d_copy));
    memset(ekf, 0, sizeof(*ekf));
    ekf->prm = prm_copy;
    memcpy(ekf->x, x_copy, sizeof(ekf->x));
    for (int i = 0; i < N; ++i) {
        ekf->P[i * N + i] = d_copy[i];
    }
    return RP_OK;
}

static void symmetrize(rp_real *P, int n)
{
    for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) {
            rp_real m = RP_C(0.5) * (P[i * n + j] + P[j * n + i]);
            P[i * n + j] = m;
            P[j * n + i] = m;
        }
    }
}

static rp_status_t predict_cv(rp_ekf_t *ekf, rp_real dt);

rp_status_t rp_ekf_predict(rp_ekf_t *ekf, rp_real dt)
{
    if (!ekf) {
        return RP_E_ARG;
    }
    if (!rp_finite(dt) || dt <= RP_C(0.0)) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(ekf->x, N)) {
        return RP_E_NAN;
    }
    /* a: the part of dt still within max_predict_s of the last update */
    const rp_real left = ekf->prm.max_predict_s - ekf->t_unobs;
    const rp_real a = ekf->held || !(left > RP_C(0.0)) ? RP_C(0.0) : left < dt ? left : dt;
    rp_status_t st = RP_OK;
    if (a > RP_C(0.0)) {
        st = predict_cv(ekf, a);
    }
    if (st == RP_OK && a < dt) {
        if (!ekf->held) {
            /* release the rate: mean 0, covariance its second moment Pvv + v v^T */
            rp_real *x = ekf->x, *P = ekf->P;
            for (int i = 0; i < NP; ++i) {
                for (int j = 0; j < NP; ++j) {
                    P[(NP + i) * N + NP + j] += x[NP + i] * x[NP + j];
                }
            }
            for (int i = 0; i < NP; ++i) {
                x[NP + i] = RP_C(0.0);
            }
            ekf->held = 1;
        }
        st = predict_cv(ekf, dt - a);
    }
    if (st == RP_OK) {
        ekf->t_unobs += dt;
    }
    return st;
}

/* The constant-velocity time update over dt > 0 (the plant of rp_ekf.h). */
static rp_status_t predict_cv(rp_ekf_t *ekf, rp_real dt)
{
    rp_real *x = ekf->x;
    rp_real *P = ekf->P;
    /* Translation t+ = t + dt v; rotation R+ = Exp(dt omega) R (omega: world-frame angular
     * rate, rad/s, the chart of rp_rig.h). */
    const rp_real wdt[3] = {dt * x[9], dt * x[10], dt * x[11]};
    rp_real ang[3], Phi[9];
    const rp_status_t st = rp_angles_plus(x + 3, wdt, ang);
    if (st != RP_OK) {
        return st;
    }
    for (int i = 0; i < 3; ++i) {
        x[i] += dt * x[NP + i];
        x[3 + i] = ang[i];
    }
    /* In the chart, R = Exp(e) R^ and omega = omega^ + e_w give, to first order,
     * e+ = Phi e + dt e_w with Phi = Exp(dt omega^) (Exp(dt omega) Exp(e) Exp(-dt omega) =
     * Exp(Phi e); the left Jacobian of Exp(dt omega) on dt e_w is I + O(dt |omega|)). So
     * F = F_cv G with G = diag(I, Phi, I, I) and F_cv = [I dt*I; 0 I]: first P <- G P G^T
     * (rows, then columns 3..5 times Phi), then F_cv below. */
    rp_rot_exp(wdt, Phi);
    for (int j = 0; j < N; ++j) { /* rows 3..5 <- Phi rows 3..5 */
        rp_real t[3];
        for (int a = 0; a < 3; ++a) {
            t[a] = Phi[3 * a] * P[3 * N + j] + Phi[3 * a + 1] * P[4 * N + j] +
                   Phi[3 * a + 2] * P[5 * N + j];
        }
        for (int a = 0; a < 3; ++a) {
            P[(3 + a) * N + j] = t[a];
        }
    }
    for (int i = 0; i < N; ++i) { /* columns 3..5 <- columns 3..5 Phi^T */
        rp_real t[3];
        for (int a = 0; a < 3; ++a) {
            t[a] = Phi[3 * a] * P[i * N + 3] + Phi[3 * a + 1] * P[i * N + 4] +
                   Phi[3 * a + 2] * P[i * N + 5];
        }
        for (int a = 0; a < 3; ++a) {
            P[i * N + 3 + a] = t[a];
        }
    }
    /* P+ = F P F^T + Q, by blocks: Ppp += dt (Ppv + Pvp) + dt^2 Pvv; Ppv += dt Pvv. */
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            rp_real pvv = P[(NP + i) * N + NP + j];
            P[i * N + j] += dt * (P[i * N + NP + j] + P[(NP + i) * N + j]) + dt * dt * pvv;
        }
    }
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            rp_real pvv = P[(NP + i) * N + NP + j];
            P[i * N + NP + j] += dt * pvv;
            P[(NP + j) * N + i] += dt * pvv; /* Pvp = Ppv^T */
        }
    }
    /* White acceleration noise q per axis: Q = q [dt^3/3 dt^2/2; dt^2/2 dt]. */
    for (int i = 0; i < NP; ++i) {
        rp_real q = i < 3 ? ekf->prm.q_trans : ekf->prm.q_rot;
        P[i * N + i] += q * dt * dt * dt / RP_C(3.0);
        P[i * N + NP + i] += q * dt * dt / RP_C(2.0);
        P[(NP + i) * N + i] += q * dt * dt / RP_C(2.0);
        P[(NP + i) * N + NP + i] += q * dt;
    }
    symmetrize(P, N);
    return RP_OK;
}

/* 2x2 Mahalanobis distance r^T S^-1 r with S = J C J^T + s2 I (J 2x6, C 6x6). */
rp_real rp_ekf_mahalanobis2(const rp_real J[12], const rp_real C[36], rp_real s2,
                            const rp_real r[2])
{
    rp_real JC[12];
    for (int a = 0; a < 2; ++a) {
        for (int j = 0; j < NP; ++j) {
            rp_real acc = RP_C(0.0);
            for (int k = 0; k < NP; ++k) {
                acc += J[a * NP + k] * C[k * NP + j];
            }
            JC[a * NP + j] = acc;
        }
    }
    rp_real S[4];
    for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
            rp_real acc = RP_C(0.0);
            for (int k = 0; k < NP; ++k) {
                acc += JC[a * NP + k] * J[b * NP + k];
            }
            S[a * 2 + b] = acc + (a == b ? s2 : RP_C(0.0));
        }
    }
    rp_real det = S[0] * S[3] - S[1] * S[2];
    if (!(det > RP_C(0.0))) {
        return RP_C(1e30); /* S not positive definite: farther than any gate */
    }
    return (S[3] * r[0] * r[0] - (S[1] + S[2]) * r[0] * r[1] + S[0] * r[1] * r[1]) / det;
}

/* Posterior pose covariance Cpost = L S^-1 L^T with S = I + L^T A L. */
static rp_status_t pose_posterior(const rp_real L[36], const rp_real A[36], rp_real Cpost[36])
{
    rp_real AL[36], S[36], Ls[36], Sinv_Lt[36], Lt[36];
    rp_status_t st = rp_la_mul(&RP_MAT(6, 6, (rp_real *)A), &RP_MAT(6, 6, (rp_real *)L),
                               &RP_MAT(6, 6, AL));
    if (st != RP_OK) {
        return st;
    }
    st = rp_la_mul_at_b(&RP_MAT(6, 6, (rp_real *)L), &RP_MAT(6, 6, AL), &RP_MAT(6, 6, S));
    if (st != RP_OK) {
        return st;
    }
    for (int i = 0; i < NP; ++i) {
        S[i * NP + i] += RP_C(1.0);
    }
    symmetrize(S, NP);
    st = rp_la_chol(&RP_MAT(6, 6, S), &RP_MAT(6, 6, Ls));
    if (st != RP_OK) {
        return st;
    }
    st = rp_la_transpose(&RP_MAT(6, 6, (rp_real *)L), &RP_MAT(6, 6, Lt));
    if (st != RP_OK) {
        return st;
    }
    st = rp_la_chol_solve(&RP_MAT(6, 6, Ls), &RP_MAT(6, 6, Lt), &RP_MAT(6, 6, Sinv_Lt));
    if (st != RP_OK) {
        return st;
    }
    st = rp_la_mul(&RP_MAT(6, 6, (rp_real *)L), &RP_MAT(6, 6, Sinv_Lt), &RP_MAT(6, 6, Cpost));
    if (st != RP_OK) {
        return st;
    }
    symmetrize(Cpost, NP);
    return RP_OK;
}

/* Discard a failed update: keep the predicted state, make the covariance symmetric and
 * inflate it by RP_EKF_RESET_INFLATION. */
static void reset_covariance(rp_ekf_t *ekf, const rp_real P0[N * N])
{
    memcpy(ekf->P, P0, sizeof(ekf->P));
    symmetrize(ekf->P, N);
    for (int i = 0; i < N * N; ++i) {
        ekf->P[i] *= RP_EKF_RESET_INFLATION;
    }
}

rp_status_t rp_ekf_update(rp_ekf_t *ekf, const rp_rig_t *rig, const rp_obs_t *obs, uint32_t n,
                          uint8_t *used, rp_ekf_info_t *info)
{
    rp_ekf_info_t dummy;
    if (!info) {
        info = &dummy;
    }
    memset(info, 0, sizeof(*info));
    if (!ekf || !rig || (n > 0 && !obs)) {
        return RP_E_ARG;
    }
    if (used) {
        memset(used, 0, n);
    }
    const rp_ekf_params_t *prm = &ekf->prm;
    const rp_real s2 = prm->sigma_px * prm->sigma_px;

    rp_real P0[N * N], x0[N], Ppp[36], L[36], Cpost[36];
    memcpy(P0, ekf->P, sizeof(P0));
    memcpy(x0, ekf->x, sizeof(x0));
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            Ppp[i * NP + j] = P0[i * N + j];
        }
    }
    if (!rp_all_finite(P0, N * N) || !rp_all_finite(x0, N) ||
        rp_la_chol(&RP_MAT(6, 6, Ppp), &RP_MAT(6, 6, L)) != RP_OK) {
        reset_covariance(ekf, P0);
        info->cov_reset = 1;
        return RP_E_DIVERGED;
    }

    rp_real p[NP];          /* current iterate, p = x0 [+] dp (rp_rig.h's chart) */
    rp_real dp[NP] = {0};
    memcpy(p, x0, sizeof(p));
    memcpy(Cpost, Ppp, sizeof(Cpost)); /* covariance used by the gate */
    uint16_t n_used = 0, n_gated = 0, n_bad = 0, n_outside = 0;
    rp_real sq_sum = RP_C(0.0);

    for (uint8_t it = 0; it < prm->iterations; ++it) {
        rp_pose_lin_t pl;
        if (rp_pose_lin_set(&pl, p) != RP_OK) {
            reset_covariance(ekf, P0);
            info->cov_reset = 1;
            return RP_E_DIVERGED;
        }
        rp_real A[36] = {0}, b[NP] = {0};
        /* Gate against the current estimate and covariance. If that rejects more features
         * than it keeps, the estimate is still poor (a bad prior, or an iteration not yet
         * converged: residuals are linearisation error, not noise), so this iteration keeps
         * them all and a later one gates. */
        int gate = prm->gate_chi2 > RP_C(0.0);
        for (int pass = 0; pass < 2; ++pass) {
            memset(A, 0, sizeof(A));
            memset(b, 0, sizeof(b));
            n_used = n_gated = n_bad = 0;
            sq_sum = RP_C(0.0);
            for (uint32_t k = 0; k < n; ++k) {
                const rp_obs_t *o = &obs[k];
                rp_real uv[2], J[12];
                if (!rp_finite(o->w) || o->w <= RP_C(0.0) || !rp_all_finite(o->uv, 2) ||
                    o->cam >= rig->n_cams ||
                    rp_rig_project(rig, o->cam, &pl, o->M, uv, J, NULL) != RP_OK) {
                    n_bad++;
                    if (used) {
                        used[k] = 0;
                    }
                    continue;
                }
                rp_real r[2] = {o->uv[0] - uv[0], o->uv[1] - uv[1]};
                if (gate) {
                    /* innovation of this feature against the current estimate */
                    rp_real d2 = rp_ekf_mahalanobis2(J, Cpost, s2 / o->w, r);
                    if (d2 > prm->gate_chi2) {
                        n_gated++;
                        if (used) {
                            used[k] = 0;
                        }
                        continue;
                    }
                }
                if (used) {
                    used[k] = 1;
                }
                n_used++;
                sq_sum += r[0] * r[0] + r[1] * r[1];
                const rp_real wk = o->w / s2;
                rp_real rr[2];
                for (int a = 0; a < 2; ++a) {
                    rp_real jd = RP_C(0.0);
                    for (int j = 0; j < NP; ++j) {
                        jd += J[a * NP + j] * dp[j];
                    }
                    rr[a] = r[a] + jd; /* r + J (p_k - p0) */
                }
                for (int i = 0; i < NP; ++i) {
                    const rp_real j0 = J[i] * wk, j1 = J[NP + i] * wk;
                    b[i] += j0 * rr[0] + j1 * rr[1];
                    for (int j = 0; j <= i; ++j) {
                        A[i * NP + j] += j0 * J[j] + j1 * J[NP + j];
                    }
                }
            }
            if (pass == 0) {
                n_outside = n_gated;
            }
            if (gate && pass == 0 && n_gated > n_used) {
                gate = 0;
                continue;
            }
            break;
        }
        if (n_used < prm->min_features) {
            /* Not enough to update: the state stays as predicted. */
            info->n_used = 0;
            info->n_gated = n_gated;
            info->n_bad = n_bad;
            info->n_outside = n_outside;
            if (used) {
                memset(used, 0, n);
            }
            memcpy(ekf->x, x0, sizeof(x0));
            memcpy(ekf->P, P0, sizeof(P0));
            return RP_E_TOO_FEW;
        }
        for (int i = 0; i < NP; ++i) {
            for (int j = i + 1; j < NP; ++j) {
                A[i * NP + j] = A[j * NP + i];
            }
        }
        if (pose_posterior(L, A, Cpost) != RP_OK) {
            reset_covariance(ekf, P0);
            info->cov_reset = 1;
            return RP_E_DIVERGED;
        }
        for (int i = 0; i < NP; ++i) {
            rp_real acc = RP_C(0.0);
            for (int j = 0; j < NP; ++j) {
                acc += Cpost[i * NP + j] * b[j];
            }
            dp[i] = acc;
        }
        if (rp_pose_plus(x0, dp, p) != RP_OK) {
            reset_covariance(ekf, P0);
            info->cov_reset = 1;
            return RP_E_DIVERGED;
        }
    }

    /* Velocity by conditioning on the pose posterior (see the top of this file). */
    rp_real Ppv[36], M[36], Dm[36], DM[36], x_new[N], P_new[N * N];
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            Ppv[i * NP + j] = P0[i * N + NP + j];
            Dm[i * NP + j] = Ppp[i * NP + j] - Cpost[i * NP + j];
        }
    }
    rp_status_t st = rp_la_chol_solve(&RP_MAT(6, 6, L), &RP_MAT(6, 6, Ppv), &RP_MAT(6, 6, M));
    if (st == RP_OK) {
        st = rp_la_mul(&RP_MAT(6, 6, Dm), &RP_MAT(6, 6, M), &RP_MAT(6, 6, DM));
    }
    if (st != RP_OK) {
        reset_covariance(ekf, P0);
        info->cov_reset = 1;
        return RP_E_DIVERGED;
    }
    memcpy(x_new, x0, sizeof(x_new));
    memcpy(P_new, P0, sizeof(P_new));
    for (int i = 0; i < NP; ++i) {
        x_new[i] = p[i];
        rp_real acc = RP_C(0.0);
        for (int k = 0; k < NP; ++k) {
            acc += M[k * NP + i] * dp[k];
        }
        x_new[NP + i] = x0[NP + i] + acc;
    }
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            rp_real pv = RP_C(0.0), vv = RP_C(0.0);
            for (int k = 0; k < NP; ++k) {
                pv += Cpost[i * NP + k] * M[k * NP + j];
                vv += M[k * NP + i] * DM[k * NP + j];
            }
            P_new[i * N + j] = Cpost[i * NP + j];
            P_new[i * N + NP + j] = pv;
            P_new[(NP + j) * N + i] = pv;
            P_new[(NP + i) * N + NP + j] = P0[(NP + i) * N + NP + j] - vv;
        }
    }
    symmetrize(P_new, N);
    rp_real Lfull[N * N];
    if (!rp_all_finite(x_new, N) ||
        rp_la_chol(&RP_MAT(N, N, P_new), &RP_MAT(N, N, Lfull)) != RP_OK) {
        reset_covariance(ekf, P0);
        info->cov_reset = 1;
        return RP_E_DIVERGED;
    }
    memcpy(ekf->x, x_new, sizeof(x_new));
    memcpy(ekf->P, P_new, sizeof(P_new));
    ekf->t_unobs = RP_C(0.0);
    ekf->held = 0;
    info->n_used = n_used;
    info->n_gated = n_gated;
    info->n_bad = n_bad;
    info->n_outside = n_outside;
    info->rms_px = n_used ? rp_sqrt(sq_sum / (RP_C(2.0) * (rp_real)n_used)) : RP_C(0.0);
    return RP_OK;
}
