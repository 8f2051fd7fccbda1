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
#define NO RP_MAX_CAMS
#define DMAX (N + NO - 1) /* the largest update: 12 states and an offset per camera but cam 0 */

RP_STATIC_ASSERT(DMAX <= RP_LA_MAX_DIM, "the timed update's decompositions exceed RP_LA_MAX_DIM");

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
    for (int k = 0; k < NO; ++k) {
        p.toff0_s[k] = RP_C(0.0);
    }
    p.toff_estimate = 0;
    p.toff_sigma_s = RP_C(0.02);
    p.toff_q = RP_C(1e-8);
    p.time_jitter_s = RP_C(0.0);
    p.group_time_noise = 1;
    return p;
}

static rp_status_t check_params(const rp_ekf_params_t *prm)
{
    if (!rp_finite(prm->sigma_px) || !rp_finite(prm->q_trans) || !rp_finite(prm->q_rot) ||
        !rp_finite(prm->gate_chi2) || !rp_finite(prm->max_predict_s) ||
        !rp_all_finite(prm->toff0_s, NO) || !rp_finite(prm->toff_sigma_s) ||
        !rp_finite(prm->toff_q) || !rp_finite(prm->time_jitter_s)) {
        return RP_E_NAN;
    }
    if (prm->sigma_px <= RP_C(0.0) || prm->q_trans < RP_C(0.0) || prm->q_rot < RP_C(0.0) ||
        prm->iterations == 0 || prm->min_features < 3 || !(prm->max_predict_s > RP_C(0.0)) ||
        !(prm->toff_sigma_s > RP_C(0.0)) || prm->toff_q < RP_C(0.0) ||
        prm->time_jitter_s < RP_C(0.0) || prm->group_time_noise > 1) {
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
    memcpy(ekf->toff, prm_copy.toff0_s, sizeof(ekf->toff));
    ekf->q_toff = prm_copy.toff_q;
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

rp_status_t rp_ekf_toff_set(rp_ekf_t *ekf, uint8_t mask, const rp_real toff0[RP_MAX_CAMS],
                            const rp_real sigma0[RP_MAX_CAMS], rp_real q)
{
    if (!ekf || (mask & 1u) || (NO < 8 && (mask >> NO) != 0) || (mask && !sigma0)) {
        return RP_E_ARG;
    }
    if (!rp_finite(q) || (toff0 && !rp_all_finite(toff0, NO))) {
        return RP_E_NAN;
    }
    if (q < RP_C(0.0)) {
        return RP_E_ARG;
    }
    for (int k = 0; k < NO; ++k) {
        if ((mask & (1u << k)) && !(sigma0[k] > RP_C(0.0) && rp_finite(sigma0[k]))) {
            return RP_E_ARG;
        }
    }
    ekf->toff_mask = mask;
    ekf->q_toff = q;
    memset(ekf->Pxo, 0, sizeof(ekf->Pxo));
    memset(ekf->Poo, 0, sizeof(ekf->Poo));
    for (int k = 0; k < NO; ++k) {
        ekf->toff[k] = toff0 ? toff0[k] : RP_C(0.0);
        if (mask & (1u << k)) {
            ekf->Poo[k * NO + k] = sigma0[k] * sigma0[k];
        }
    }
    return RP_OK;
}

rp_status_t rp_ekf_toff_carry(rp_ekf_t *dst, const rp_ekf_t *src)
{
    if (!dst || !src) {
        return RP_E_ARG;
    }
    if (dst != src) {
        dst->toff_mask = src->toff_mask;
        dst->q_toff = src->q_toff;
        memcpy(dst->toff, src->toff, sizeof(dst->toff));
        memcpy(dst->Poo, src->Poo, sizeof(dst->Poo));
    }
    memset(dst->Pxo, 0, sizeof(dst->Pxo));
    return RP_OK;
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

/* Rows 3..5 (the rotation) of the row-major matrix M (cols columns) <- Phi times them. */
static void rows_times_phi(rp_real *M, int cols, const rp_real Phi[9])
{
    for (int j = 0; j < cols; ++j) {
        rp_real t[3];
        for (int a = 0; a < 3; ++a) {
            t[a] = Phi[3 * a] * M[3 * cols + j] + Phi[3 * a + 1] * M[4 * cols + j] +
                   Phi[3 * a + 2] * M[5 * cols + j];
        }
        for (int a = 0; a < 3; ++a) {
            M[(3 + a) * cols + j] = t[a];
        }
    }
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
    rows_times_phi(P, N, Phi);
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
    /* The offsets' cross-covariance: Pxo <- F Pxo (rows 3..5 times Phi, then rows 0..5 plus
     * dt rows 6..11); the offset states walk: Poo += q_toff dt. */
    if (ekf->toff_mask) {
        rp_real *X = ekf->Pxo;
        rows_times_phi(X, NO, Phi);
        for (int j = 0; j < NO; ++j) {
            for (int i = 0; i < NP; ++i) {
                X[i * NO + j] += dt * X[(NP + i) * NO + j];
            }
        }
        for (int k = 0; k < NO; ++k) {
            if (ekf->toff_mask & (1u << k)) {
                ekf->Poo[k * NO + k] += ekf->q_toff * dt;
            }
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

/* r^T S^-1 r with S = H C H^T + s2 I (+ Rx: [xx xy yy], may be NULL): H 2xD, C DxD, both
 * row-major. cols (nc ascending indices, or NULL: all D) lists the columns where H may be
 * non-zero; the others are skipped (the same sums in the same order: the same result). The
 * dense branch stays for the pose-only update: indexing through cols there cost rigpose-sim's
 * synchronised stereo4 17 % more instructions (callgrind). */
static rp_real maha_d(const rp_real *H, const rp_real *C, int D, const int8_t *cols, int nc,
                      rp_real s2, const rp_real *Rx, const rp_real r[2])
{
    rp_real HC[2 * DMAX];
    rp_real S[4];
    if (cols == NULL || nc == D) {
        for (int a = 0; a < 2; ++a) {
            for (int j = 0; j < D; ++j) {
                rp_real acc = RP_C(0.0);
                for (int k = 0; k < D; ++k) {
                    acc += H[a * D + k] * C[k * D + j];
                }
                HC[a * D + j] = acc;
            }
        }
        for (int a = 0; a < 2; ++a) {
            for (int b = 0; b < 2; ++b) {
                rp_real acc = RP_C(0.0);
                for (int k = 0; k < D; ++k) {
                    acc += HC[a * D + k] * H[b * D + k];
                }
                S[a * 2 + b] = acc;
            }
        }
    } else {
        for (int a = 0; a < 2; ++a) {
            for (int q = 0; q < nc; ++q) {
                const int j = cols[q];
                rp_real acc = RP_C(0.0);
                for (int t = 0; t < nc; ++t) {
                    acc += H[a * D + cols[t]] * C[cols[t] * D + j];
                }
                HC[a * D + j] = acc;
            }
        }
        for (int a = 0; a < 2; ++a) {
            for (int b = 0; b < 2; ++b) {
                rp_real acc = RP_C(0.0);
                for (int t = 0; t < nc; ++t) {
                    acc += HC[a * D + cols[t]] * H[b * D + cols[t]];
                }
                S[a * 2 + b] = acc;
            }
        }
    }
    S[0] += s2;
    S[3] += s2;
    if (Rx) {
        S[0] += Rx[0];
        S[1] += Rx[1];
        S[2] += Rx[1];
        S[3] += Rx[2];
    }
    rp_real det = S[0] * S[3] - S[1] * S[2];
    if (!(det > RP_C(0.0))) {
        return RP_C(1e30); /* S not positive definite: farther than any gate */
    }
    return (S[3] * r[0] * r[0] - (S[1] + S[2]) * r[0] * r[1] + S[0] * r[1] * r[1]) / det;
}

rp_real rp_ekf_mahalanobis2(const rp_real J[12], const rp_real C[36], rp_real s2,
                            const rp_real r[2])
{
    return maha_d(J, C, NP, NULL, NP, s2, NULL, r);
}

/* Posterior covariance Cpost = L S^-1 L^T with S = I + L^T A L (all DxD). */
static rp_status_t posterior(const rp_real *L, const rp_real *A, int D, rp_real *Cpost)
{
    rp_real AL[DMAX * DMAX], S[DMAX * DMAX], Ls[DMAX * DMAX], Sinv_Lt[DMAX * DMAX],
        Lt[DMAX * DMAX];
    rp_status_t st = rp_la_mul(&RP_MAT(D, D, (rp_real *)A), &RP_MAT(D, D, (rp_real *)L),
                               &RP_MAT(D, D, AL));
    if (st != RP_OK) {
        return st;
    }
    st = rp_la_mul_at_b(&RP_MAT(D, D, (rp_real *)L), &RP_MAT(D, D, AL), &RP_MAT(D, D, S));
    if (st != RP_OK) {
        return st;
    }
    for (int i = 0; i < D; ++i) {
        S[i * D + i] += RP_C(1.0);
    }
    symmetrize(S, D);
    st = rp_la_chol(&RP_MAT(D, D, S), &RP_MAT(D, D, Ls));
    if (st != RP_OK) {
        return st;
    }
    st = rp_la_transpose(&RP_MAT(D, D, (rp_real *)L), &RP_MAT(D, D, Lt));
    if (st != RP_OK) {
        return st;
    }
    st = rp_la_chol_solve(&RP_MAT(D, D, Ls), &RP_MAT(D, D, Lt), &RP_MAT(D, D, Sinv_Lt));
    if (st != RP_OK) {
        return st;
    }
    st = rp_la_mul(&RP_MAT(D, D, (rp_real *)L), &RP_MAT(D, D, Sinv_Lt), &RP_MAT(D, D, Cpost));
    if (st != RP_OK) {
        return st;
    }
    symmetrize(Cpost, D);
    return RP_OK;
}

/* Discard a failed update: keep the predicted state, make the covariance symmetric and
 * inflate it by RP_EKF_RESET_INFLATION (the offsets' blocks too). */
static void reset_covariance(rp_ekf_t *ekf, const rp_ekf_t *e0)
{
    memcpy(ekf->P, e0->P, sizeof(ekf->P));
    memcpy(ekf->Pxo, e0->Pxo, sizeof(ekf->Pxo));
    memcpy(ekf->Poo, e0->Poo, sizeof(ekf->Poo));
    symmetrize(ekf->P, N);
    symmetrize(ekf->Poo, NO);
    for (int i = 0; i < N * N; ++i) {
        ekf->P[i] *= RP_EKF_RESET_INFLATION;
    }
    for (int i = 0; i < N * NO; ++i) {
        ekf->Pxo[i] *= RP_EKF_RESET_INFLATION;
    }
    for (int i = 0; i < NO * NO; ++i) {
        ekf->Poo[i] *= RP_EKF_RESET_INFLATION;
    }
}

/* The block y of the state an update solves for: the pose (D = 6), or the pose, the rate and
 * the offset states (D = 12 + n_off, a timed update). Offset state i is camera off_cam[i]. */
typedef struct {
    int D;
    uint8_t n_off;
    uint8_t off_cam[NO];
    int8_t off_of[NO];  /* camera k -> its offset's index in y, or -1 (not a state) */
    /* the columns of y where an observation's H can be non-zero, ascending: the pose and the
     * offset states (the rate is considered, its columns are zero: obs_predict); the gate and
     * the normal equations skip the others */
    int8_t cols[DMAX];
    int nc;
} yblock_t;

static void yblock_set(yblock_t *y, const rp_ekf_t *ekf, const rp_obs_t *obs, uint32_t n)
{
    int timed = ekf->toff_mask != 0 || ekf->prm.time_jitter_s > RP_C(0.0);
    for (uint32_t k = 0; k < n && !timed; ++k) {
        timed = obs[k].cam < NO && obs[k].dt + ekf->toff[obs[k].cam] != RP_C(0.0);
    }
    y->n_off = 0;
    for (uint8_t c = 0; c < NO; ++c) {
        y->off_of[c] = -1;
        if (ekf->toff_mask & (1u << c)) {
            y->off_of[c] = (int8_t)(N + y->n_off);
            y->off_cam[y->n_off++] = c;
        }
    }
    y->D = timed ? N + y->n_off : NP;
    y->nc = 0;
    for (int k = 0; k < y->D; ++k) {
        if (k < NP || k >= N) {
            y->cols[y->nc++] = (int8_t)k;
        }
    }
}

/* Prior covariance of y (DxD). */
static void yblock_prior(const yblock_t *y, const rp_ekf_t *ekf, rp_real *Pyy)
{
    const int D = y->D, nx = D < N ? D : N;
    for (int i = 0; i < nx; ++i) {
        for (int j = 0; j < nx; ++j) {
            Pyy[i * D + j] = ekf->P[i * N + j];
        }
    }
    for (int a = 0; a < (D > N ? y->n_off : 0); ++a) {
        const uint8_t ca = y->off_cam[a];
        for (int i = 0; i < N; ++i) {
            Pyy[i * D + N + a] = ekf->Pxo[i * NO + ca];
            Pyy[(N + a) * D + i] = ekf->Pxo[i * NO + ca];
        }
        for (int b = 0; b < y->n_off; ++b) {
            Pyy[(N + a) * D + N + b] = ekf->Poo[ca * NO + y->off_cam[b]];
        }
    }
}

/* The state at iterate dy: pose p = x0 [+] dy[0..5], rate xi and offsets toff. */
static rp_status_t yblock_iterate(const yblock_t *y, const rp_ekf_t *e0, const rp_real *dy,
                                  rp_real p[NP], rp_real xi[NP], rp_real toff[NO])
{
    memcpy(xi, e0->x + NP, NP * sizeof(rp_real));
    memcpy(toff, e0->toff, NO * sizeof(rp_real));
    if (y->D > NP) {
        for (int i = 0; i < NP; ++i) {
            xi[i] += dy[NP + i];
        }
        for (int a = 0; a < y->n_off; ++a) {
            toff[y->off_cam[a]] += dy[N + a];
        }
    }
    return rp_pose_plus(e0->x, dy, p);
}

/* One observation at the iterate: its predicted pixel and its Jacobian H (2xD) on y.
 * D = 6: H = J_pose at p. Timed: the pose at the camera's time, pc = p [+] delta xi with
 * delta = obs.dt + toff[cam], H = [J, 0, J xi at the camera's offset] (the chart's
 * composition Exp(delta omega) Exp(w) ~ Exp(delta omega + w) taken to first order, as the
 * predict's). The rate is a considered parameter of the camera-time pose, not solved for from
 * it: its prior uncertainty enters the pixel's noise, Rx = delta^2 J Pvv J^T ([xx xy yy]), and
 * the rate follows the pose through their prior correlation, as in a synchronised set; the
 * capture time's jitter adds jitter^2 (J xi)(J xi)^T. Why the rate is considered:
 * the rate's own information from delta J is the pixel noise over delta (at 2 ms, 800 px,
 * 0.5 px: 0.3 rad/s per feature), which a loose process noise lets through and which then
 * corrupts every prediction (rigpose-sim, gc with one camera at +2 ms given: 0.0038 m with it,
 * docs/time.md). plc caches the camera-time pose of the last camera and delta seen. */
typedef struct {
    uint8_t cam;
    rp_real delta;
    rp_pose_lin_t pl;
    int valid;
} camcache_t;

static rp_status_t obs_predict(const yblock_t *y, const rp_rig_t *rig, const rp_obs_t *o,
                               const rp_pose_lin_t *pl, const rp_real xi[NP],
                               const rp_real toff[NO], const rp_real *P0, rp_real jitter,
                               camcache_t *cc, rp_real uv[2], rp_real *H, rp_real Rx[3])
{
    Rx[0] = Rx[1] = Rx[2] = RP_C(0.0);
    const int D = y->D;
    if (D == NP) {
        return rp_rig_project(rig, o->cam, pl, o->M, uv, H, NULL);
    }
    const rp_real delta = o->dt + toff[o->cam];
    if (!cc->valid || cc->cam != o->cam || cc->delta != delta) {
        cc->valid = 0;
        if (rp_pose_lin_at(&cc->pl, pl->p, xi, delta) != RP_OK) {
            return RP_E_NAN;
        }
        cc->valid = 1;
        cc->cam = o->cam;
        cc->delta = delta;
    }
    rp_real J[12];
    const rp_status_t st = rp_rig_project(rig, o->cam, &cc->pl, o->M, uv, J, NULL);
    if (st != RP_OK) {
        return st;
    }
    const int oi = y->off_of[o->cam];
    rp_real JP[12]; /* J Pvv */
    for (int a = 0; a < 2; ++a) {
        for (int j = 0; j < NP; ++j) {
            rp_real acc = RP_C(0.0);
            for (int k = 0; k < NP; ++k) {
                acc += J[a * NP + k] * P0[(NP + k) * N + NP + j];
            }
            JP[a * NP + j] = acc;
        }
    }
    for (int i = 0; i < NP; ++i) {
        Rx[0] += JP[i] * J[i];
        Rx[1] += JP[i] * J[NP + i];
        Rx[2] += JP[NP + i] * J[NP + i];
    }
    rp_real Jx[2] = {RP_C(0.0), RP_C(0.0)}; /* J xi: the feature's image motion, px/s */
    for (int a = 0; a < 2; ++a) {
        for (int i = 0; i < NP; ++i) {
            Jx[a] += J[a * NP + i] * xi[i];
        }
    }
    const rp_real j2 = jitter * jitter;
    Rx[0] = delta * delta * Rx[0] + j2 * Jx[0] * Jx[0];
    Rx[1] = delta * delta * Rx[1] + j2 * Jx[0] * Jx[1];
    Rx[2] = delta * delta * Rx[2] + j2 * Jx[1] * Jx[1];
    for (int a = 0; a < 2; ++a) {
        rp_real *h = H + a * D;
        for (int i = 0; i < NP; ++i) {
            h[i] = J[a * NP + i];
            h[NP + i] = RP_C(0.0);
        }
        for (int i = N; i < D; ++i) {
            h[i] = RP_C(0.0);
        }
        if (oi >= 0) {
            h[oi] = Jx[a];
        }
    }
    return RP_OK;
}

/* A pose-only update (D = 6): the rate follows by conditioning on the pose posterior (see the
 * top of this file), e1 from e0 with pose p. */
static rp_status_t condition_rate(const rp_ekf_t *e0, const rp_real L[36], const rp_real Cpost[36],
                                  const rp_real dp[NP], const rp_real p[NP], rp_ekf_t *e1)
{
    const rp_real *x0 = e0->x, *P0 = e0->P;
    rp_real Ppv[36], M[36], Dm[36], DM[36];
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            Ppv[i * NP + j] = P0[i * N + NP + j];
            Dm[i * NP + j] = P0[i * N + j] - Cpost[i * NP + j];
        }
    }
    rp_status_t st = rp_la_chol_solve(&RP_MAT(6, 6, (rp_real *)L), &RP_MAT(6, 6, Ppv),
                                      &RP_MAT(6, 6, M));
    if (st == RP_OK) {
        st = rp_la_mul(&RP_MAT(6, 6, Dm), &RP_MAT(6, 6, M), &RP_MAT(6, 6, DM));
    }
    if (st != RP_OK) {
        return st;
    }
    rp_real *x_new = e1->x, *P_new = e1->P;
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
    return RP_OK;
}

/* The features of one capture time (delta) in a timed update share one error of the pose
 * extrapolated there: w ~ N(0, Q), Q = delta^2 Pvv (the considered rate) + jitter^2 xi xi^T +
 * the plant's white acceleration over |delta| (q |delta|^3 / 3 per axis, as the predict's).
 * Treating w as independent per feature (its J Q J^T in each pixel's noise) counts it once per
 * feature: with a stereo pair 25 ms off, stereo4 then did worse than its front pair alone
 * (rigpose-sim --motion smooth). So the features of one capture time and one offset state are a
 * group whose H is J E (E: 6 x D, the identity on the pose and xi on the offset's column), and
 * w is marginalised once per group: with Lw = sum J^T W J, bw = sum J^T W rr (W = w / s2, the
 * pixel noise alone) the group adds E^T (Lw - Lw M Lw) E to the normal equations and
 * E^T (bw - Lw M bw) to the right-hand side, M = (Q^-1 + Lw)^-1 = G (I + G^T Lw G)^-1 G^T with
 * Q = G G^T, G = [|delta| chol(Pvv), jitter xi, sqrt(q |delta|^3 / 3) I] (6 x 13). No Q^-1 is
 * formed (Q may be near singular), I + G^T Lw G >= I always factors, and the group's sums and
 * the difference are in double on every build (Lw ~ 1e8 px^-2 against a net information
 * ~ 1/Q: in float the difference loses every digit). Groups are formed per capture time and
 * offset state, so the rate's share, common to all capture times, is still counted once per
 * capture time. Features at the state's time without jitter (w = 0) take the per-feature path,
 * as do those beyond RP_MAX_CAMS groups and every feature when Pvv does not factor: their
 * pixel noise gains the rate's and the jitter's part (obs_predict's Rx), without the plant's
 * acceleration term, as with group_time_noise 0. */
#define TG_COLS 13
typedef struct {
    rp_real delta;
    int8_t oi;           /* the offset state's column in y, or -1 */
    rp_real Q[36];       /* for the gate: J Q J^T */
    double Lw[36], bw[NP];
    int used;
} tgroup_t;

static tgroup_t *tgroup_find(tgroup_t *g, int *n_g, rp_real delta, int8_t oi, const rp_ekf_t *e0,
                             const rp_real xi[NP], rp_real jitter)
{
    for (int k = 0; k < *n_g; ++k) {
        if (g[k].delta == delta && g[k].oi == oi) {
            return &g[k];
        }
    }
    if (*n_g >= NO) {
        return NULL;
    }
    tgroup_t *t = &g[(*n_g)++];
    memset(t, 0, sizeof(*t));
    t->delta = delta;
    t->oi = oi;
    const rp_real ad = rp_fabs(delta);
    const rp_real a3 = ad * ad * ad / RP_C(3.0);
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            t->Q[i * NP + j] = delta * delta * e0->P[(NP + i) * N + NP + j] +
                               jitter * jitter * xi[i] * xi[j];
        }
        t->Q[i * NP + i] += (i < 3 ? e0->prm.q_trans : e0->prm.q_rot) * a3;
    }
    return t;
}

/* The group's net contribution (see tgroup_t), added to A (lower triangle over y's cols) and b.
 * Lv: chol(Pvv) in double. RP_E_SINGULAR if I + G^T Lw G does not factor (not for finite
 * input: it is >= I). */
static rp_status_t tgroup_apply(const tgroup_t *t, const double Lv[36], const rp_real xi[NP],
                                rp_real jitter, const rp_ekf_params_t *prm, int D,
                                const int8_t *cols, int nc, rp_real *A, rp_real *b)
{
    double G[NP * TG_COLS] = {0};
    const double ad = fabs((double)t->delta), a3 = ad * ad * ad / 3.0;
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j <= i; ++j) {
            G[i * TG_COLS + j] = ad * Lv[i * NP + j];
        }
        G[i * TG_COLS + NP] = (double)jitter * (double)xi[i];
        G[i * TG_COLS + NP + 1 + i] = sqrt(a3 * (double)(i < 3 ? prm->q_trans : prm->q_rot));
    }
    double LG[NP * TG_COLS], S[TG_COLS * TG_COLS];
    for (int i = 0; i < NP; ++i) {
        for (int c = 0; c < TG_COLS; ++c) {
            double acc = 0.0;
            for (int k = 0; k < NP; ++k) {
                acc += t->Lw[i * NP + k] * G[k * TG_COLS + c];
            }
            LG[i * TG_COLS + c] = acc;
        }
    }
    for (int r = 0; r < TG_COLS; ++r) {
        for (int c = 0; c < TG_COLS; ++c) {
            double acc = r == c ? 1.0 : 0.0;
            for (int k = 0; k < NP; ++k) {
                acc += G[k * TG_COLS + r] * LG[k * TG_COLS + c];
            }
            S[r * TG_COLS + c] = acc;
        }
    }
    if (rp_la_chol_d(S, TG_COLS) != RP_OK) {
        return RP_E_SINGULAR;
    }
    /* LM = Lw M = LG S^-1 LG^T (6x6), then net = Lw - LM Lw... = Lw - LG S^-1 LG^T */
    double X[TG_COLS * NP]; /* S^-1 LG^T, column by column */
    for (int i = 0; i < NP; ++i) {
        double rhs[TG_COLS], x[TG_COLS];
        for (int c = 0; c < TG_COLS; ++c) {
            rhs[c] = LG[i * TG_COLS + c];
        }
        if (rp_la_chol_solve_d(S, TG_COLS, rhs, x) != RP_OK) {
            return RP_E_SINGULAR;
        }
        for (int c = 0; c < TG_COLS; ++c) {
            X[c * NP + i] = x[c];
        }
    }
    double Ln[36], bn[NP];
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            double acc = 0.0;
            for (int c = 0; c < TG_COLS; ++c) {
                acc += LG[i * TG_COLS + c] * X[c * NP + j];
            }
            Ln[i * NP + j] = t->Lw[i * NP + j] - acc;
        }
    }
    /* bn = bw - Lw M bw = bw - LG S^-1 G^T bw */
    double gb[TG_COLS], y[TG_COLS];
    for (int c = 0; c < TG_COLS; ++c) {
        double acc = 0.0;
        for (int k = 0; k < NP; ++k) {
            acc += G[k * TG_COLS + c] * t->bw[k];
        }
        gb[c] = acc;
    }
    if (rp_la_chol_solve_d(S, TG_COLS, gb, y) != RP_OK) {
        return RP_E_SINGULAR;
    }
    for (int i = 0; i < NP; ++i) {
        double acc = 0.0;
        for (int c = 0; c < TG_COLS; ++c) {
            acc += LG[i * TG_COLS + c] * y[c];
        }
        bn[i] = t->bw[i] - acc;
    }
    /* E^T Ln E and E^T bn: the pose block, and with an offset state its column (Ln xi) and
     * corner (xi^T Ln xi) */
    double Lx[NP], xLx = 0.0, bx = 0.0;
    for (int i = 0; i < NP; ++i) {
        double acc = 0.0;
        for (int k = 0; k < NP; ++k) {
            acc += Ln[i * NP + k] * (double)xi[k];
        }
        Lx[i] = acc;
        xLx += (double)xi[i] * acc;
        bx += (double)xi[i] * bn[i];
    }
    for (int q = 0; q < nc; ++q) {
        const int i = cols[q];
        const int ip = i < NP ? i : (i == t->oi ? -1 : -2); /* pose row, offset row, other */
        if (ip == -2) {
            continue;
        }
        b[i] += (rp_real)(ip >= 0 ? bn[ip] : bx);
        for (int u = 0; u <= q; ++u) {
            const int j = cols[u];
            const int jp = j < NP ? j : (j == t->oi ? -1 : -2);
            if (jp == -2) {
                continue;
            }
            const double v = ip >= 0 && jp >= 0 ? Ln[ip * NP + jp]
                             : ip >= 0         ? Lx[ip]
                             : jp >= 0         ? Lx[jp]
                                               : xLx;
            A[i * D + j] += (rp_real)v;
        }
    }
    return RP_OK;
}

static rp_status_t update_once(rp_ekf_t *ekf, const rp_rig_t *rig, const rp_obs_t *obs,
                               uint32_t n, uint8_t *used, rp_ekf_info_t *info)
{
    memset(info, 0, sizeof(*info));
    if (!ekf || !rig || (n > 0 && !obs)) {
        return RP_E_ARG;
    }
    if (used) {
        memset(used, 0, n);
    }
    const rp_ekf_params_t *prm = &ekf->prm;
    const rp_real s2 = prm->sigma_px * prm->sigma_px;

    const rp_ekf_t e0 = *ekf; /* the prior: state, covariance, offsets */
    const rp_real *x0 = e0.x, *P0 = e0.P;
    yblock_t y;
    yblock_set(&y, &e0, obs, n);
    const int D = y.D;
    rp_real Pyy[DMAX * DMAX], L[DMAX * DMAX], Cpost[DMAX * DMAX];
    yblock_prior(&y, &e0, Pyy);
    if (!rp_all_finite(P0, N * N) || !rp_all_finite(x0, N) ||
        !rp_all_finite(e0.Pxo, N * NO) || !rp_all_finite(e0.Poo, NO * NO) ||
        !rp_all_finite(e0.toff, NO) ||
        rp_la_chol(&RP_MAT(D, D, Pyy), &RP_MAT(D, D, L)) != RP_OK) {
        reset_covariance(ekf, &e0);
        info->cov_reset = 1;
        return RP_E_DIVERGED;
    }

    rp_real p[NP], xi[NP], toff[NO]; /* current iterate (yblock_iterate) */
    rp_real dy[DMAX] = {0};
    memcpy(p, x0, sizeof(p));
    memcpy(xi, x0 + NP, sizeof(xi));
    memcpy(toff, e0.toff, sizeof(toff));
    memcpy(Cpost, Pyy, sizeof(rp_real) * (size_t)(D * D)); /* covariance used by the gate */
    uint16_t n_used = 0, n_gated = 0, n_bad = 0, n_outside = 0;
    rp_real sq_sum = RP_C(0.0);

    /* chol(Pvv) in double for the groups' factor of Q (tgroup_t); if the rate's prior block
     * is not positive definite (no plant noise), the per-feature path */
    double Lv[36];
    int lv_ok = 0;
    if (D > NP && prm->group_time_noise) {
        for (int i = 0; i < 36; ++i) {
            Lv[i] = (double)P0[(NP + i / NP) * N + NP + i % NP];
        }
        lv_ok = rp_la_chol_d(Lv, NP) == RP_OK;
    }
    for (uint8_t it = 0; it < prm->iterations; ++it) {
        rp_pose_lin_t pl;
        if (rp_pose_lin_set(&pl, p) != RP_OK) {
            reset_covariance(ekf, &e0);
            info->cov_reset = 1;
            return RP_E_DIVERGED;
        }
        camcache_t cc = {0};
        rp_real A[DMAX * DMAX] = {0}, b[DMAX] = {0};
        /* Gate against the current estimate and covariance. If that rejects more features
         * than it keeps, the estimate is still poor (a bad prior, or an iteration not yet
         * converged: residuals are linearisation error, not noise), so this iteration keeps
         * them all and a later one gates. */
        int gate = prm->gate_chi2 > RP_C(0.0);
        for (int pass = 0; pass < 2; ++pass) {
            memset(A, 0, sizeof(A));
            memset(b, 0, sizeof(b));
            memset(info->n_used_cam, 0, sizeof(info->n_used_cam));
            memset(info->n_gated_cam, 0, sizeof(info->n_gated_cam));
            n_used = n_gated = n_bad = 0;
            sq_sum = RP_C(0.0);
            tgroup_t grp[NO];
            int n_grp = 0, grp_ok = 1;
            for (uint32_t k = 0; k < n; ++k) {
                const rp_obs_t *o = &obs[k];
                rp_real uv[2], H[2 * DMAX], Rx[3];
                tgroup_t *tg = NULL;
                if (!rp_finite(o->w) || o->w <= RP_C(0.0) || !rp_all_finite(o->uv, 2) ||
                    !rp_finite(o->dt) || o->cam >= rig->n_cams ||
                    obs_predict(&y, rig, o, &pl, xi, toff, P0, prm->time_jitter_s, &cc, uv, H,
                                Rx) != RP_OK) {
                    n_bad++;
                    if (used) {
                        used[k] = 0;
                    }
                    continue;
                }
                rp_real r[2] = {o->uv[0] - uv[0], o->uv[1] - uv[1]};
                if (D > NP && lv_ok) {
                    const rp_real dl = o->dt + toff[o->cam];
                    if (dl != RP_C(0.0) || prm->time_jitter_s > RP_C(0.0)) {
                        tg = tgroup_find(grp, &n_grp, dl, y.off_of[o->cam], &e0, xi,
                                         prm->time_jitter_s);
                    }
                }
                if (tg) { /* the shared error's marginal for the gate: J Q J^T */
                    rp_real JQ[12];
                    for (int a = 0; a < 2; ++a) {
                        for (int j = 0; j < NP; ++j) {
                            rp_real acc = RP_C(0.0);
                            for (int q = 0; q < NP; ++q) {
                                acc += H[a * D + q] * tg->Q[q * NP + j];
                            }
                            JQ[a * NP + j] = acc;
                        }
                    }
                    Rx[0] = Rx[1] = Rx[2] = RP_C(0.0);
                    for (int j = 0; j < NP; ++j) {
                        Rx[0] += JQ[j] * H[j];
                        Rx[1] += JQ[j] * H[D + j];
                        Rx[2] += JQ[NP + j] * H[D + j];
                    }
                }
                if (gate) {
                    /* innovation of this feature against the current estimate */
                    rp_real d2 = maha_d(H, Cpost, D, y.cols, y.nc, s2 / o->w,
                                        D == NP ? NULL : Rx, r);
                    if (d2 > prm->gate_chi2) {
                        n_gated++;
                        info->n_gated_cam[o->cam]++;
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
                info->n_used_cam[o->cam]++;
                sq_sum += r[0] * r[0] + r[1] * r[1];
                const rp_real wk = o->w / s2;
                rp_real rr[2];
                for (int a = 0; a < 2; ++a) {
                    rp_real jd = RP_C(0.0);
                    for (int j = 0; j < D; ++j) {
                        jd += H[a * D + j] * dy[j];
                    }
                    rr[a] = r[a] + jd; /* r + H (y_k - y0) */
                }
                if (D == NP) {
                    for (int i = 0; i < D; ++i) {
                        const rp_real j0 = H[i] * wk, j1 = H[D + i] * wk;
                        b[i] += j0 * rr[0] + j1 * rr[1];
                        for (int j = 0; j <= i; ++j) {
                            A[i * D + j] += j0 * H[j] + j1 * H[D + j];
                        }
                    }
                } else if (tg) {
                    /* the pixel noise alone, summed per group in double (tgroup_t) */
                    tg->used = 1;
                    for (int q = 0; q < NP; ++q) {
                        const double j0 = (double)H[q] * (double)wk;
                        const double j1 = (double)H[D + q] * (double)wk;
                        tg->bw[q] += j0 * (double)rr[0] + j1 * (double)rr[1];
                        for (int u = 0; u <= q; ++u) {
                            tg->Lw[q * NP + u] += j0 * (double)H[u] + j1 * (double)H[D + u];
                        }
                    }
                } else {
                    /* the pixel's noise s2 / w I + Rx, inverted: W (2x2 symmetric) */
                    const rp_real n0 = s2 / o->w + Rx[0], n1 = Rx[1], n2 = s2 / o->w + Rx[2];
                    const rp_real det = n0 * n2 - n1 * n1;
                    const rp_real W0 = n2 / det, W1 = -n1 / det, W2 = n0 / det;
                    for (int t = 0; t < y.nc; ++t) { /* H's zero columns add nothing */
                        const int i = y.cols[t];
                        const rp_real j0 = H[i] * W0 + H[D + i] * W1;
                        const rp_real j1 = H[i] * W1 + H[D + i] * W2;
                        b[i] += j0 * rr[0] + j1 * rr[1];
                        for (int u = 0; u <= t; ++u) {
                            const int j = y.cols[u];
                            A[i * D + j] += j0 * H[j] + j1 * H[D + j];
                        }
                    }
                }
            }
            /* each group's net information, its shared error marginalised (tgroup_t) */
            for (int g = 0; g < n_grp && grp_ok; ++g) {
                tgroup_t *tg = &grp[g];
                if (!tg->used) {
                    continue;
                }
                for (int q = 0; q < NP; ++q) { /* the upper triangle from the lower */
                    for (int u = q + 1; u < NP; ++u) {
                        tg->Lw[q * NP + u] = tg->Lw[u * NP + q];
                    }
                }
                grp_ok = tgroup_apply(tg, Lv, xi, prm->time_jitter_s, prm, D, y.cols, y.nc, A,
                                      b) == RP_OK;
            }
            if (!grp_ok) { /* not for finite input: I + G^T Lw G >= I */
                reset_covariance(ekf, &e0);
                info->cov_reset = 1;
                return RP_E_DIVERGED;
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
            *ekf = e0;
            return RP_E_TOO_FEW;
        }
        for (int i = 0; i < D; ++i) {
            for (int j = i + 1; j < D; ++j) {
                A[i * D + j] = A[j * D + i];
            }
        }
        if (posterior(L, A, D, Cpost) != RP_OK) {
            reset_covariance(ekf, &e0);
            info->cov_reset = 1;
            return RP_E_DIVERGED;
        }
        for (int i = 0; i < D; ++i) {
            rp_real acc = RP_C(0.0);
            for (int j = 0; j < D; ++j) {
                acc += Cpost[i * D + j] * b[j];
            }
            dy[i] = acc;
        }
        if (yblock_iterate(&y, &e0, dy, p, xi, toff) != RP_OK) {
            reset_covariance(ekf, &e0);
            info->cov_reset = 1;
            return RP_E_DIVERGED;
        }
    }

    rp_ekf_t e1 = e0;
    if (D == NP) {
        if (condition_rate(&e0, L, Cpost, dy, p, &e1) != RP_OK) {
            reset_covariance(ekf, &e0);
            info->cov_reset = 1;
            return RP_E_DIVERGED;
        }
    } else {
        /* Timed: y is the whole state (pose, rate, offset states): its posterior is the
         * state's. */
        memcpy(e1.x, p, sizeof(p));
        memcpy(e1.x + NP, xi, sizeof(xi));
        memcpy(e1.toff, toff, sizeof(toff));
        for (int i = 0; i < N; ++i) {
            for (int j = 0; j < N; ++j) {
                e1.P[i * N + j] = Cpost[i * D + j];
            }
            for (int a = 0; a < y.n_off; ++a) {
                e1.Pxo[i * NO + y.off_cam[a]] = Cpost[i * D + N + a];
            }
        }
        for (int a = 0; a < y.n_off; ++a) {
            for (int c = 0; c < y.n_off; ++c) {
                e1.Poo[y.off_cam[a] * NO + y.off_cam[c]] = Cpost[(N + a) * D + N + c];
            }
        }
    }
    rp_real Lfull[N * N];
    if (!rp_all_finite(e1.x, N) || !rp_all_finite(e1.toff, NO) ||
        rp_la_chol(&RP_MAT(N, N, e1.P), &RP_MAT(N, N, Lfull)) != RP_OK) {
        reset_covariance(ekf, &e0);
        info->cov_reset = 1;
        return RP_E_DIVERGED;
    }
    *ekf = e1;
    ekf->t_unobs = RP_C(0.0);
    ekf->held = 0;
    info->n_used = n_used;
    info->n_gated = n_gated;
    info->n_bad = n_bad;
    info->n_outside = n_outside;
    info->rms_px = n_used ? rp_sqrt(sq_sum / (RP_C(2.0) * (rp_real)n_used)) : RP_C(0.0);
    return RP_OK;
}

uint8_t rp_ekf_clock_jumps(const rp_ekf_t *e, const uint16_t n_used[RP_MAX_CAMS],
                           const uint16_t n_left[RP_MAX_CAMS])
{
    uint8_t jumped = 0;
    if (!e || !n_used || !n_left) {
        return 0;
    }
    for (uint8_t c = 0; c < NO; ++c) {
        const uint32_t nc = (uint32_t)n_used[c] + n_left[c];
        if (!(e->toff_mask & (1u << c)) || nc < e->prm.min_features || 2u * n_left[c] <= nc) {
            continue;
        }
        uint32_t n_o = 0, l_o = 0;
        for (uint8_t d = 0; d < NO; ++d) {
            n_o += d != c ? (uint32_t)n_used[d] + n_left[d] : 0u;
            l_o += d != c ? n_left[d] : 0u;
        }
        if (n_o >= e->prm.min_features && 2u * l_o <= n_o) {
            jumped = (uint8_t)(jumped | (1u << c));
        }
    }
    return jumped;
}

void rp_ekf_toff_restart(rp_ekf_t *ekf, uint8_t cams)
{
    for (uint8_t c = 0; ekf && c < NO; ++c) {
        if ((cams & (1u << c)) && (ekf->toff_mask & (1u << c))) {
            for (int i = 0; i < N; ++i) {
                ekf->Pxo[i * NO + c] = RP_C(0.0);
            }
            for (uint8_t d = 0; d < NO; ++d) {
                ekf->Poo[c * NO + d] = ekf->Poo[d * NO + c] = RP_C(0.0);
            }
            ekf->Poo[c * NO + c] = ekf->prm.toff_sigma_s * ekf->prm.toff_sigma_s;
        }
    }
}

rp_status_t rp_ekf_update(rp_ekf_t *ekf, const rp_rig_t *rig, const rp_obs_t *obs, uint32_t n,
                          uint8_t *used, rp_ekf_info_t *info)
{
    rp_ekf_info_t dummy;
    if (!info) {
        info = &dummy;
    }
    if (!ekf || !ekf->toff_mask) {
        return update_once(ekf, rig, obs, n, used, info);
    }
    const rp_ekf_t prior = *ekf;
    rp_status_t st = update_once(ekf, rig, obs, n, used, info);
    const uint8_t jumped = st == RP_OK || st == RP_E_TOO_FEW
                               ? rp_ekf_clock_jumps(&prior, info->n_used_cam, info->n_gated_cam)
                               : 0;
    if (!jumped) {
        return st;
    }
    /* Each such camera's offset starts again from its start sigma (its correlations dropped),
     * and the update runs again from the prior. */
    *ekf = prior;
    rp_ekf_toff_restart(ekf, jumped);
    st = update_once(ekf, rig, obs, n, used, info);
    info->toff_reset = jumped;
    return st;
}
