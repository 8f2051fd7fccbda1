/*
 * rp_gcba.c - window bundle adjustment for the generalised camera's metric scale (rp_gcba.h).
 */
#include <string.h>

#include "priv/rp_inv3.h"
#include "priv/rp_math.h"
#include "rigpose/rp_camera.h"
#include "rigpose/rp_gcba.h"
#include "rigpose/rp_idmap.h"
#include "rigpose/rp_linalg.h"

#define rp_sqrt_d sqrt /* the adjustment is double throughout (rp_gcba.h) */

rp_gcba_cfg_t rp_gcba_default_cfg(void)
{
    rp_gcba_cfg_t c;
    memset(&c, 0, sizeof(c));
    c.iterations = 8;
    c.min_obs = 3;
    c.sigma_px = RP_C(0.5);
    c.huber_px = RP_C(1.5);
    c.min_angle = RP_C(0.5) * RP_PI / RP_C(180.0);
    return c;
}

rp_status_t rp_gcba_reset(rp_gcba_t *ba, uint8_t max_kf)
{
    if (!ba || max_kf < 3 || max_kf > RP_GCBA_MAX_KF) {
        return RP_E_ARG;
    }
    ba->cap = max_kf;
    ba->n_kf = 0;
    ba->head = 0;
    ba->state = RP_GCBA_IDLE;
    return RP_OK;
}

rp_status_t rp_gcba_add_keyframe(rp_gcba_t *ba, const rp_real p[6], const rp_gcba_obs_t *obs,
                                 uint16_t n, const rp_real rate[6],
                                 const rp_real cam_dt[RP_MAX_CAMS])
{
    if (!ba || !p || (n > 0 && !obs) || ba->cap < 3 || ba->cap > RP_GCBA_MAX_KF ||
        ba->state != RP_GCBA_IDLE || (!rate) != (!cam_dt)) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(p, 6) || (rate && (!rp_all_finite(rate, 6) ||
                                          !rp_all_finite(cam_dt, RP_MAX_CAMS)))) {
        return RP_E_NAN;
    }
    uint8_t slot;
    if (ba->n_kf < ba->cap) {
        slot = (uint8_t)((ba->head + ba->n_kf) % ba->cap);
        ba->n_kf++;
    } else {
        slot = ba->head;
        ba->head = (uint8_t)((ba->head + 1) % ba->cap);
    }
    rp_gcba_kf_t *kf = &ba->kf[slot];
    memcpy(kf->p, p, sizeof(kf->p));
    for (int i = 0; i < 6; ++i) {
        kf->rate[i] = rate ? rate[i] : RP_C(0.0);
    }
    for (int c = 0; c < RP_MAX_CAMS; ++c) {
        kf->cam_dt[c] = cam_dt ? cam_dt[c] : RP_C(0.0);
    }
    kf->n = n < RP_GCBA_MAX_OBS_KF ? n : (uint16_t)RP_GCBA_MAX_OBS_KF;
    if (kf->n > 0) {
        memcpy(kf->obs, obs, kf->n * sizeof(obs[0]));
    }
    return RP_OK;
}

/* ---- small double helpers ---------------------------------------------------------------- */

RP_DEFINE_INV3_SPD(inv3, double)
RP_STATIC_ASSERT(RP_GCBA_NP <= RP_LA_D_MAX_DIM, "the pose system fits rp_la_chol_d");

/* ---- the window -------------------------------------------------------------------------- */

static const rp_gcba_kf_t *kf_at(const rp_gcba_t *ba, int k)
{
    return &ba->kf[(ba->head + k) % ba->cap];
}

/* Landmark index of id, inserting it; -1 when the table is full. */
static int lm_index(rp_gcba_t *ba, uint32_t id, uint8_t cam, uint16_t *n_lm)
{
    const uint32_t mask = 2u * RP_GCBA_MAX_LM - 1u;
    for (uint32_t h = rp_idmap_hash(id) & mask, probe = 0; probe <= mask; ++probe, h = (h + 1) & mask) {
        const uint16_t e = ba->hash[h];
        if (e == 0) {
            if (*n_lm >= RP_GCBA_MAX_LM) {
                return -1;
            }
            const uint16_t L = (*n_lm)++;
            ba->hash[h] = (uint16_t)(L + 1);
            ba->lm_id[L] = id;
            ba->lm_cam[L] = cam;
            ba->lm_n[L] = 0;
            ba->lm_ok[L] = 1;
            return L;
        }
        if (ba->lm_id[e - 1] == id) {
            if (ba->lm_cam[e - 1] != cam) {
                ba->lm_ok[e - 1] = 0; /* one id in two cameras: not a landmark of one */
            }
            return e - 1;
        }
    }
    return -1;
}

/* An observation of a camera of the rig with a finite pixel. */
static int usable(const rp_gcba_obs_t *o, const rp_rig_t *rig)
{
    return o->cam < rig->n_cams && isfinite(o->uv[0]) && isfinite(o->uv[1]);
}

static void pose_real(const double x[6], rp_real p[6])
{
    for (int a = 0; a < 6; ++a) {
        p[a] = (rp_real)x[a];
    }
}

/* x <- x [+] d in double (rp_rig.h's pose chart: t + dt, Exp(w) R): R(x) from the angles,
 * Exp(w) by Rodrigues, the angles back as rp_rot_to_angles takes them (alpha = 0 at gimbal
 * lock, alpha from row 1 of Rz(gamma)^T R elsewhere, so that R is reproduced). */
static void pose_plus_d(double x[6], const double d[6])
{
    const double ca = cos(x[3]), sa = sin(x[3]), cb = cos(x[4]), sb = sin(x[4]);
    const double cg = cos(x[5]), sg = sin(x[5]);
    const double R[9] = {cg * cb, cg * sb * sa - sg * ca, cg * sb * ca + sg * sa,
                         sg * cb, sg * sb * sa + cg * ca, sg * sb * ca - cg * sa,
                         -sb,     cb * sa,                cb * ca};
    const double *w = d + 3;
    const double t2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2], t = rp_sqrt_d(t2);
    double a = 1.0 - t2 / 6.0, b = 0.5 - t2 / 24.0; /* sin t / t, (1 - cos t) / t^2 */
    if (t >= 1e-4) {
        const double sh = sin(0.5 * t);
        a = sin(t) / t;
        b = 2.0 * sh * sh / t2;
    }
    const double E[9] = {1.0 - b * (w[1] * w[1] + w[2] * w[2]), -a * w[2] + b * w[0] * w[1],
                         a * w[1] + b * w[0] * w[2],            a * w[2] + b * w[0] * w[1],
                         1.0 - b * (w[0] * w[0] + w[2] * w[2]), -a * w[0] + b * w[1] * w[2],
                         -a * w[1] + b * w[0] * w[2],           a * w[0] + b * w[1] * w[2],
                         1.0 - b * (w[0] * w[0] + w[1] * w[1])};
    double Q[9];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            Q[3 * i + j] = E[3 * i] * R[j] + E[3 * i + 1] * R[3 + j] + E[3 * i + 2] * R[6 + j];
        }
    }
    const double c = rp_sqrt_d(Q[0] * Q[0] + Q[3] * Q[3]);
    x[4] = atan2(-Q[6], c);
    if (c < 1e-9) {
        x[3] = 0.0;
        x[5] = atan2(-Q[1], Q[4]);
    } else {
        const double g = atan2(Q[3], Q[0]), cg2 = cos(g), sg2 = sin(g);
        x[3] = atan2(sg2 * Q[2] - cg2 * Q[5], cg2 * Q[4] - sg2 * Q[1]);
        x[5] = g;
    }
    for (int i = 0; i < 3; ++i) {
        x[i] += d[i];
    }
}

/* The pose camera cam of keyframe k saw its image from (m): x [+] cam_dt rate (rp_gcba_kf_t,
 * the rate's translation in metres: over mu). */
static rp_status_t cam_pose(const rp_gcba_t *ba, int k, uint8_t cam, rp_pose_lin_t *pl);

/* Ray of observation o of keyframe k: origin c and unit direction w (world, m). */
static rp_status_t obs_ray(const rp_gcba_t *ba, const rp_rig_t *rig, int k,
                           const rp_gcba_obs_t *o, double c[3], double w[3])
{
    rp_real xn[2];
    rp_pose_lin_t pl;
    const rp_real uv[2] = {(rp_real)o->uv[0], (rp_real)o->uv[1]};
    rp_status_t st = o->cam < RP_MAX_CAMS ? cam_pose(ba, k, o->cam, &pl) : RP_E_ARG;
    if (st == RP_OK) {
        st = rp_cam_unproject(&rig->cam[o->cam].cam, uv, xn);
    }
    if (st != RP_OK) {
        return st;
    }
    const rp_rig_cam_t *rc = &rig->cam[o->cam];
    const double dc[3] = {(double)xn[0], (double)xn[1], 1.0};
    double dr[3], n2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        dr[a] = (double)rc->R[a * 3 + 0] * dc[0] + (double)rc->R[a * 3 + 1] * dc[1] +
                (double)rc->R[a * 3 + 2] * dc[2];
    }
    for (int a = 0; a < 3; ++a) {
        w[a] = (double)pl.R[a * 3 + 0] * dr[0] + (double)pl.R[a * 3 + 1] * dr[1] +
               (double)pl.R[a * 3 + 2] * dr[2];
        c[a] = (double)pl.p[a] + (double)pl.R[a * 3 + 0] * (double)rc->D[0] +
               (double)pl.R[a * 3 + 1] * (double)rc->D[1] +
               (double)pl.R[a * 3 + 2] * (double)rc->D[2];
        n2 += w[a] * w[a];
    }
    const double in = 1.0 / rp_sqrt_d(n2);
    for (int a = 0; a < 3; ++a) {
        w[a] *= in;
    }
    return RP_OK;
}

/* Midpoint of the landmark's first and last rays; 0 if their angle is under min_angle or the
 * point is not in front of both. */
static int triangulate(rp_gcba_t *ba, const rp_rig_t *rig, int L, double min_angle)
{
    const int a = ba->lm_first[L], b = ba->lm_first[L] + ba->lm_n[L] - 1;
    const rp_gcba_obs_t *oa = &kf_at(ba, ba->ob_kf[a])->obs[ba->ob_i[a]];
    const rp_gcba_obs_t *ob = &kf_at(ba, ba->ob_kf[b])->obs[ba->ob_i[b]];
    double c1[3], w1[3], c2[3], w2[3];
    if (obs_ray(ba, rig, ba->ob_kf[a], oa, c1, w1) != RP_OK ||
        obs_ray(ba, rig, ba->ob_kf[b], ob, c2, w2) != RP_OK) {
        return 0;
    }
    /* c1 + s1 w1 ~ c2 + s2 w2: [1 -q; q -1] [s1 s2]^T = [e.w1 e.w2]^T, e = c2 - c1 */
    const double q = w1[0] * w2[0] + w1[1] * w2[1] + w1[2] * w2[2];
    const double sin2 = 1.0 - q * q;
    const double sa = rp_sqrt_d(sin2 > 0.0 ? sin2 : 0.0);
    if (!(sa > sin(min_angle))) {
        return 0;
    }
    const double e[3] = {c2[0] - c1[0], c2[1] - c1[1], c2[2] - c1[2]};
    const double e1 = e[0] * w1[0] + e[1] * w1[1] + e[2] * w1[2];
    const double e2 = e[0] * w2[0] + e[1] * w2[1] + e[2] * w2[2];
    const double s1 = (e1 - q * e2) / sin2;
    const double s2 = (q * e1 - e2) / sin2;
    if (!(s1 > 0.0) || !(s2 > 0.0)) {
        return 0;
    }
    for (int k = 0; k < 3; ++k) {
        ba->X[L][k] = 0.5 * (c1[k] + s1 * w1[k] + c2[k] + s2 * w2[k]);
    }
    return 1;
}

/* Residual, Jacobians and Huber weight (already divided by sigma^2) of observation j of a
 * landmark at X; 0 if it does not project. */
static int linearise(const rp_gcba_t *ba, const rp_rig_t *rig, int j, const double X[3],
                     const rp_gcba_cfg_t *cfg, double r[2], double Jp[12], double JM[6],
                     double *w, double *cost)
{
    const int k = ba->ob_kf[j];
    const rp_gcba_obs_t *o = &kf_at(ba, k)->obs[ba->ob_i[j]];
    rp_real M[3], uv[2], jp[12], jm[6];
    for (int a = 0; a < 3; ++a) {
        M[a] = (rp_real)X[a];
    }
    if (o->cam >= RP_MAX_CAMS || !ba->pl_ok[k][o->cam] ||
        rp_rig_project(rig, o->cam, &ba->pl[k][o->cam], M, uv, jp, jm) != RP_OK) {
        return 0;
    }
    r[0] = (double)o->uv[0] - (double)uv[0];
    r[1] = (double)o->uv[1] - (double)uv[1];
    for (int a = 0; a < 12; ++a) {
        Jp[a] = (double)jp[a];
    }
    for (int a = 0; a < 6; ++a) {
        JM[a] = (double)jm[a];
    }
    const double e = rp_sqrt_d(r[0] * r[0] + r[1] * r[1]);
    const double h = (double)cfg->huber_px;
    const double s2 = (double)cfg->sigma_px * (double)cfg->sigma_px;
    *w = (e <= h ? 1.0 : h / e) / s2;
    *cost += (e <= h ? e * e : 2.0 * h * e - h * h) / s2;
    return 1;
}

/* Build the reduced normal equations S dx = g at the current estimate; returns the robust cost
 * and fills the landmarks' Vi, v; *n_obs the observations used. */
/* The map's unit the window's poses imply now: the least-squares ratio of the keyframes'
 * translations from the oldest, as given (map units) over the estimate's (m); the start's unit
 * if they do not move. *den: the estimate's sum of squares. */
static double implied_mu(const rp_gcba_t *ba, int nk, double *den_out)
{
    double num = 0.0, den = 0.0;
    for (int k = 1; k < nk; ++k) {
        const rp_gcba_kf_t *kf = kf_at(ba, k), *k0 = kf_at(ba, 0);
        for (int a = 0; a < 3; ++a) {
            const double dt = ba->x[k][a] - ba->x[0][a];
            num += ((double)kf->p[a] - (double)k0->p[a]) * dt;
            den += dt * dt;
        }
    }
    if (den_out) {
        *den_out = den;
    }
    return den > 1e-12 && num > 0.0 ? num / den : ba->mu;
}

static rp_status_t cam_pose(const rp_gcba_t *ba, int k, uint8_t cam, rp_pose_lin_t *pl)
{
    const rp_gcba_kf_t *kf = kf_at(ba, k);
    rp_real p[6], xi[6];
    pose_real(ba->x[k], p);
    for (int i = 0; i < 6; ++i) {
        xi[i] = i < 3 ? (rp_real)((double)kf->rate[i] / ba->mu_now) : kf->rate[i];
    }
    return rp_pose_lin_at(pl, p, xi, kf->cam_dt[cam]);
}

/* Each keyframe's cameras' poses prepared for projection (once per pass): a camera's time
 * offset moves it by its rate, whose translation is in map units, so at the unit the
 * estimate implies now (the rate scales with the solution, as the keyframes' translations). */
static void prepare_poses(rp_gcba_t *ba, int nk)
{
    ba->mu_now = implied_mu(ba, nk, NULL);
    for (int k = 0; k < nk; ++k) {
        const rp_gcba_kf_t *kf = kf_at(ba, k);
        for (uint8_t c = 0; c < RP_MAX_CAMS; ++c) {
            uint8_t same = 0; /* a camera before c at the same time: its pose (synchronised: one) */
            while (same < c && kf->cam_dt[same] != kf->cam_dt[c]) {
                ++same;
            }
            if (same < c) {
                ba->pl[k][c] = ba->pl[k][same];
                ba->pl_ok[k][c] = ba->pl_ok[k][same];
            } else {
                ba->pl_ok[k][c] = (uint8_t)(cam_pose(ba, k, c, &ba->pl[k][c]) == RP_OK);
            }
        }
    }
}

static double build(rp_gcba_t *ba, const rp_rig_t *rig, uint16_t n_lm, int nk,
                    const rp_gcba_cfg_t *cfg, uint16_t *n_obs, double *sq)
{
    prepare_poses(ba, nk);
    const int np = 6 * (nk - 1);
    memset(ba->S, 0, sizeof(double) * (size_t)(np * np));
    memset(ba->g, 0, sizeof(double) * (size_t)np);
    double cost = 0.0;
    *n_obs = 0;
    *sq = 0.0;
    for (int L = 0; L < n_lm; ++L) {
        if (!ba->lm_ok[L]) {
            continue;
        }
        double W[RP_GCBA_MAX_KF][18], T[RP_GCBA_MAX_KF][18];
        int kk[RP_GCBA_MAX_KF], m = 0;
        double V[9] = {0}, v[3] = {0}, U[RP_GCBA_MAX_KF][36], gu[RP_GCBA_MAX_KF][6];
        double c_l = 0.0, sq_l = 0.0;
        for (int j = ba->lm_first[L]; j < ba->lm_first[L] + ba->lm_n[L]; ++j) {
            double r[2], Jp[12], JM[6], w;
            if (m >= RP_GCBA_MAX_KF ||
                !linearise(ba, rig, j, ba->X[L], cfg, r, Jp, JM, &w, &c_l)) {
                continue;
            }
            sq_l += r[0] * r[0] + r[1] * r[1];
            for (int a = 0; a < 3; ++a) {
                for (int b = 0; b < 3; ++b) {
                    V[a * 3 + b] += w * (JM[a] * JM[b] + JM[3 + a] * JM[3 + b]);
                }
                v[a] += w * (JM[a] * r[0] + JM[3 + a] * r[1]);
            }
            kk[m] = ba->ob_kf[j];
            for (int a = 0; a < 6; ++a) {
                for (int b = 0; b < 3; ++b) {
                    W[m][a * 3 + b] = w * (Jp[a] * JM[b] + Jp[6 + a] * JM[3 + b]);
                }
                for (int b = 0; b < 6; ++b) {
                    U[m][a * 6 + b] = w * (Jp[a] * Jp[b] + Jp[6 + a] * Jp[6 + b]);
                }
                gu[m][a] = w * (Jp[a] * r[0] + Jp[6 + a] * r[1]);
            }
            m++;
        }
        if (m < cfg->min_obs || !inv3(V, ba->Vi[L])) {
            ba->lm_ok[L] = 0;
            continue;
        }
        memcpy(ba->v[L], v, sizeof(v));
        cost += c_l;
        *sq += sq_l;
        *n_obs = (uint16_t)(*n_obs + m);
        const double *Vi = ba->Vi[L];
        for (int a = 0; a < m; ++a) {
            for (int r6 = 0; r6 < 6; ++r6) {
                for (int c3 = 0; c3 < 3; ++c3) {
                    T[a][r6 * 3 + c3] = W[a][r6 * 3 + 0] * Vi[0 * 3 + c3] +
                                        W[a][r6 * 3 + 1] * Vi[1 * 3 + c3] +
                                        W[a][r6 * 3 + 2] * Vi[2 * 3 + c3];
                }
            }
        }
        for (int a = 0; a < m; ++a) {
            if (kk[a] == 0) {
                continue; /* the oldest keyframe is held */
            }
            const int ra = 6 * (kk[a] - 1);
            for (int r6 = 0; r6 < 6; ++r6) {
                ba->g[ra + r6] += gu[a][r6] - (T[a][r6 * 3 + 0] * v[0] + T[a][r6 * 3 + 1] * v[1] +
                                               T[a][r6 * 3 + 2] * v[2]);
                for (int c6 = 0; c6 < 6; ++c6) {
                    ba->S[(ra + r6) * np + ra + c6] += U[a][r6 * 6 + c6];
                }
            }
            for (int b = 0; b < m; ++b) {
                if (kk[b] == 0 || kk[b] < kk[a]) {
                    continue; /* upper block triangle; mirrored below */
                }
                const int rb = 6 * (kk[b] - 1);
                for (int r6 = 0; r6 < 6; ++r6) {
                    for (int c6 = 0; c6 < 6; ++c6) {
                        ba->S[(ra + r6) * np + rb + c6] -=
                            T[a][r6 * 3 + 0] * W[b][c6 * 3 + 0] +
                            T[a][r6 * 3 + 1] * W[b][c6 * 3 + 1] +
                            T[a][r6 * 3 + 2] * W[b][c6 * 3 + 2];
                    }
                }
            }
        }
    }
    /* the lower triangle (what chol reads) from the upper */
    for (int i = 0; i < np; ++i) {
        for (int j = 0; j < i; ++j) {
            ba->S[i * np + j] = ba->S[j * np + i];
        }
    }
    return cost;
}

/* Landmark steps from the pose step: dX = Vi (v - sum_a W_a^T dx_a). */
static void back_substitute(rp_gcba_t *ba, const rp_rig_t *rig, uint16_t n_lm, int nk,
                            const rp_gcba_cfg_t *cfg)
{
    prepare_poses(ba, nk);
    for (int L = 0; L < n_lm; ++L) {
        if (!ba->lm_ok[L]) {
            continue;
        }
        double rhs[3] = {ba->v[L][0], ba->v[L][1], ba->v[L][2]}, dummy = 0.0;
        int m = 0;
        for (int j = ba->lm_first[L]; j < ba->lm_first[L] + ba->lm_n[L]; ++j) {
            double r[2], Jp[12], JM[6], w;
            if (m >= RP_GCBA_MAX_KF ||
                !linearise(ba, rig, j, ba->X[L], cfg, r, Jp, JM, &w, &dummy)) {
                continue;
            }
            m++;
            const int k = ba->ob_kf[j];
            if (k == 0) {
                continue;
            }
            const double *d = &ba->dx[6 * (k - 1)];
            double jd[2] = {0.0, 0.0};
            for (int a = 0; a < 6; ++a) {
                jd[0] += Jp[a] * d[a];
                jd[1] += Jp[6 + a] * d[a];
            }
            for (int b = 0; b < 3; ++b) {
                rhs[b] -= w * (JM[b] * jd[0] + JM[3 + b] * jd[1]);
            }
        }
        const double *Vi = ba->Vi[L];
        for (int a = 0; a < 3; ++a) {
            ba->X[L][a] += Vi[a * 3 + 0] * rhs[0] + Vi[a * 3 + 1] * rhs[1] + Vi[a * 3 + 2] * rhs[2];
        }
    }
}

rp_status_t rp_gcba_start(rp_gcba_t *ba, const rp_rig_t *rig, rp_real mu,
                          const rp_gcba_cfg_t *cfg)
{
    if (!ba || !rig || !cfg || !(mu > RP_C(0.0)) || !rp_finite(mu) ||
        cfg->iterations < 1 || cfg->min_obs < 2 || !(cfg->sigma_px > RP_C(0.0)) ||
        !(cfg->huber_px > RP_C(0.0)) || !(cfg->min_angle >= RP_C(0.0)) ||
        !rp_finite(cfg->sigma_px) || !rp_finite(cfg->huber_px) || !rp_finite(cfg->min_angle)) {
        return RP_E_ARG;
    }
    ba->state = RP_GCBA_IDLE;
    ba->rig = rig;
    ba->cfg = *cfg;
    ba->mu = (double)mu;
    ba->mu_now = (double)mu;
    ba->it = 0;
    ba->alpha = 1.0;
    memset(&ba->res, 0, sizeof(ba->res));
    const int nk = ba->n_kf;
    ba->res.n_kf = (uint16_t)nk;
    ba->n_lm_tab = 0;
    if (nk < 3) {
        return RP_E_TOO_FEW;
    }
    for (int k = 0; k < nk; ++k) {
        const rp_gcba_kf_t *kf = kf_at(ba, k);
        for (int a = 0; a < 6; ++a) {
            ba->x[k][a] = a < 3 ? (double)kf->p[a] / (double)mu : (double)kf->p[a];
        }
    }
    /* group the observations by landmark */
    memset(ba->hash, 0, sizeof(ba->hash));
    uint16_t n_lm = 0;
    for (int k = 0; k < nk; ++k) {
        const rp_gcba_kf_t *kf = kf_at(ba, k);
        for (uint16_t i = 0; i < kf->n; ++i) {
            const rp_gcba_obs_t *o = &kf->obs[i];
            const int L = usable(o, rig) ? lm_index(ba, o->id, o->cam, &n_lm) : -1;
            if (L >= 0) {
                ba->lm_n[L]++;
            }
        }
    }
    uint16_t total = 0;
    for (int L = 0; L < n_lm; ++L) {
        ba->lm_first[L] = total;
        total = (uint16_t)(total + ba->lm_n[L]);
        ba->lm_n[L] = 0; /* refilled below */
    }
    for (int k = 0; k < nk; ++k) {
        const rp_gcba_kf_t *kf = kf_at(ba, k);
        for (uint16_t i = 0; i < kf->n; ++i) {
            const rp_gcba_obs_t *o = &kf->obs[i];
            const int L = usable(o, rig) ? lm_index(ba, o->id, o->cam, &n_lm) : -1;
            if (L < 0) {
                continue;
            }
            const uint16_t j = (uint16_t)(ba->lm_first[L] + ba->lm_n[L]++);
            ba->ob_kf[j] = (uint16_t)k;
            ba->ob_i[j] = i;
        }
    }
    uint16_t n_usable = 0;
    ba->n_lm_tab = n_lm;
    for (int L = 0; L < n_lm; ++L) {
        if (ba->lm_ok[L] && ba->lm_n[L] >= cfg->min_obs && ba->lm_n[L] <= RP_GCBA_MAX_KF &&
            triangulate(ba, rig, L, (double)cfg->min_angle)) {
            n_usable++;
        } else {
            ba->lm_ok[L] = 0;
        }
    }
    if (n_usable < 12) {
        return RP_E_TOO_FEW;
    }
    ba->state = RP_GCBA_STARTED;
    return RP_OK;
}

/* The estimate before a step (poses, landmarks and which of them are usable) with the
 * equations built there (S, g, the landmarks' Vi and v, the cost, squared sum and count):
 * kept (back = 0), or put back (back = 1) when no length of the step lowers the cost. */
static void start_state(rp_gcba_t *ba, int np, uint16_t n_lm, int back)
{
    const struct {
        void *now, *kept;
        size_t n;
    } part[] = {
        {ba->x, ba->x0, sizeof(ba->x0)},
        {ba->X, ba->X0, sizeof(double) * 3 * n_lm},
        {ba->lm_ok, ba->ok0, n_lm},
        {ba->S, ba->S0, sizeof(double) * (size_t)(np * np)},
        {ba->g, ba->g0, sizeof(double) * (size_t)np},
        {ba->Vi, ba->Vi0, sizeof(double) * 9 * n_lm},
        {ba->v, ba->v0, sizeof(double) * 3 * n_lm},
        {&ba->cost, &ba->cost0, sizeof(ba->cost)},
        {&ba->sq, &ba->sq0, sizeof(ba->sq)},
        {&ba->n_obs, &ba->n_obs0, sizeof(ba->n_obs)},
    };
    for (size_t i = 0; i < sizeof(part) / sizeof(part[0]); ++i) {
        memcpy(back ? part[i].now : part[i].kept, back ? part[i].kept : part[i].now, part[i].n);
    }
}

/* Backtracking (rp_gcba_step): each try shortens the step by this factor; three lengths in all
 * (1, 1/4, 1/16). */
#define RP_GCBA_BACKTRACK_DIV 4.0

rp_status_t rp_gcba_step(rp_gcba_t *ba)
{
    if (!ba || ba->state == RP_GCBA_IDLE) {
        return RP_E_ARG;
    }
    if (ba->state == RP_GCBA_SOLVED) {
        return RP_OK;
    }
    const rp_rig_t *rig = ba->rig;
    const rp_gcba_cfg_t *cfg = &ba->cfg;
    const int nk = ba->n_kf, np = 6 * (nk - 1);
    const uint16_t n_lm = ba->n_lm_tab;
    if (ba->state == RP_GCBA_STARTED) {
        /* the first normal equations, at the triangulated start */
        ba->cost = build(ba, rig, n_lm, nk, cfg, &ba->n_obs, &ba->sq);
        ba->res.rms0_px = (rp_real)rp_sqrt_d(ba->sq / (2.0 * (ba->n_obs > 0 ? ba->n_obs : 1)));
        ba->state = RP_GCBA_ITERATING;
        return RP_OK;
    }
    /* Gauss-Newton (Levenberg-damped), globalised by backtracking: the step is kept if it
     * lowers the robust cost, else a shorter one along it is tried at the next call (the
     * direction descends the cost wherever S is positive definite, so a short enough one
     * lowers it; on real tracks a window's weakest direction, its scale, can make the full step
     * overshoot), and when no length RP_GCBA_BACKTRACK_DIV allows does (or the tries are used
     * up), the estimate stays where it was */
    ba->res.iterations = (uint8_t)++ba->it;
    if (ba->alpha == 1.0) {
        start_state(ba, np, n_lm, 0); /* S is factored below */
        for (int i = 0; i < np; ++i) {
            ba->S[i * np + i] *= 1.0 + 1e-4;
        }
        if (rp_la_chol_d(ba->S, np) != RP_OK) {
            ba->state = RP_GCBA_IDLE;
            return RP_E_SINGULAR;
        }
        (void)rp_la_chol_solve_d(ba->S, np, ba->g, ba->dx); /* S factored, np in range */
        back_substitute(ba, rig, n_lm, nk, cfg);
        for (int L = 0; L < n_lm; ++L) {
            for (int a = 0; a < 3; ++a) {
                ba->dX[L][a] = ba->X[L][a] - ba->X0[L][a];
            }
        }
    } else {
        memcpy(ba->lm_ok, ba->ok0, n_lm); /* the last try's build may have set some aside */
        for (int L = 0; L < n_lm; ++L) {
            for (int a = 0; a < 3; ++a) {
                ba->X[L][a] = ba->X0[L][a] + ba->alpha * ba->dX[L][a];
            }
        }
    }
    for (int k = 1; k < nk; ++k) {
        double d[6];
        for (int a = 0; a < 6; ++a) {
            d[a] = ba->alpha * ba->dx[6 * (k - 1) + a];
        }
        memcpy(ba->x[k], ba->x0[k], sizeof(ba->x[k]));
        pose_plus_d(ba->x[k], d);
    }
    uint16_t n2 = 0;
    double sq2 = 0.0;
    const double c2 = build(ba, rig, n_lm, nk, cfg, &n2, &sq2);
    if (!(c2 <= ba->cost) || n2 < ba->n_obs / 2) {
        if (ba->alpha > 1.0 / RP_GCBA_BACKTRACK_DIV / RP_GCBA_BACKTRACK_DIV &&
            ba->it < cfg->iterations) {
            ba->alpha /= RP_GCBA_BACKTRACK_DIV; /* a shorter step at the next call */
            return RP_OK;
        }
        /* worse at every length tried (or no try left): back to the previous estimate and its
         * equations (as they were built there), and stop */
        ba->alpha = 1.0;
        start_state(ba, np, n_lm, 1);
        prepare_poses(ba, nk);
        ba->state = RP_GCBA_SOLVED;
        return RP_OK;
    }
    ba->alpha = 1.0;
    const double gain = (ba->cost - c2) / (ba->cost > 0.0 ? ba->cost : 1.0);
    ba->cost = c2;
    ba->n_obs = n2;
    ba->sq = sq2;
    if (gain < 1e-4 || ba->it >= cfg->iterations) {
        ba->state = RP_GCBA_SOLVED; /* converged, or out of iterations */
    }
    return RP_OK;
}

rp_status_t rp_gcba_finish(rp_gcba_t *ba, rp_gcba_result_t *res)
{
    if (!ba || !res || ba->state == RP_GCBA_IDLE) {
        return RP_E_ARG;
    }
    while (ba->state != RP_GCBA_SOLVED) {
        const rp_status_t st = rp_gcba_step(ba);
        if (st != RP_OK) {
            *res = ba->res;
            return st;
        }
    }
    ba->state = RP_GCBA_IDLE;
    const int nk = ba->n_kf, np = 6 * (nk - 1);
    const uint16_t n_lm = ba->n_lm_tab;
    ba->res.rms_px = (rp_real)rp_sqrt_d(ba->sq / (2.0 * (ba->n_obs > 0 ? ba->n_obs : 1)));
    ba->res.n_obs = ba->n_obs;
    ba->res.n_lm = 0;
    for (int L = 0; L < n_lm; ++L) {
        ba->res.n_lm = (uint16_t)(ba->res.n_lm + (ba->lm_ok[L] ? 1 : 0));
    }
    *res = ba->res;

    /* the map's unit the solution implies, and its variance through the normal matrix */
    double den = 0.0;
    const double m = implied_mu(ba, nk, &den);
    if (!(den > 1e-12)) {
        return RP_E_DEGENERATE;
    }
    if (rp_la_chol_d(ba->S, np) != RP_OK) {
        return RP_E_SINGULAR;
    }
    for (int i = 0; i < np; ++i) {
        ba->g[i] = 0.0;
    }
    for (int k = 1; k < nk; ++k) {
        const rp_gcba_kf_t *kf = kf_at(ba, k), *k0 = kf_at(ba, 0);
        for (int a = 0; a < 3; ++a) {
            const double dt = ba->x[k][a] - ba->x[0][a];
            ba->g[6 * (k - 1) + a] = (((double)kf->p[a] - (double)k0->p[a]) - 2.0 * m * dt) / den;
        }
    }
    (void)rp_la_chol_solve_d(ba->S, np, ba->g, ba->dx); /* S factored, np in range */
    double var = 0.0;
    for (int i = 0; i < np; ++i) {
        var += ba->g[i] * ba->dx[i];
    }
    if (!(m > 0.0) || !(var > 0.0) || !(m < 1e30) || !(var < 1e30)) {
        return RP_E_NAN;
    }
    res->mu = (rp_real)m;
    res->mu_var = (rp_real)var;
    return RP_OK;
}

rp_status_t rp_gcba_scale(rp_gcba_t *ba, const rp_rig_t *rig, rp_real mu,
                          const rp_gcba_cfg_t *cfg, rp_gcba_result_t *res)
{
    if (!res) {
        return RP_E_ARG;
    }
    rp_status_t st = rp_gcba_start(ba, rig, mu, cfg);
    if (st != RP_OK) {
        memset(res, 0, sizeof(*res));
        if (ba) {
            *res = ba->res;
        }
        return st;
    }
    return rp_gcba_finish(ba, res);
}

rp_status_t rp_gcba_kf_pose(const rp_gcba_t *ba, uint8_t k, rp_real p[6])
{
    if (!ba || !p || k >= ba->n_kf) {
        return RP_E_ARG;
    }
    memcpy(p, kf_at(ba, k)->p, sizeof(rp_real) * 6);
    return RP_OK;
}

rp_status_t rp_gcba_solved_pose(const rp_gcba_t *ba, uint8_t k, rp_real p[6])
{
    if (!ba || !p || k >= ba->n_kf) {
        return RP_E_ARG;
    }
    pose_real(ba->x[k], p);
    return RP_OK;
}

rp_status_t rp_gcba_set_pose(rp_gcba_t *ba, uint8_t k, const rp_real p[6])
{
    if (!ba || !p || k >= ba->n_kf) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(p, 6)) {
        return RP_E_NAN;
    }
    memcpy(ba->kf[(ba->head + k) % ba->cap].p, p, sizeof(rp_real) * 6);
    return RP_OK;
}

rp_status_t rp_gcba_landmark(const rp_gcba_t *ba, uint16_t i, uint32_t *id, uint8_t *cam,
                             rp_real X[3], rp_real C[6])
{
    if (!ba || !id || !cam || !X || !C || i >= ba->n_lm_tab) {
        return RP_E_ARG;
    }
    if (!ba->lm_ok[i]) {
        return RP_E_NOT_FOUND;
    }
    *id = ba->lm_id[i];
    *cam = ba->lm_cam[i];
    const double *V = ba->Vi[i];
    for (int a = 0; a < 3; ++a) {
        X[a] = (rp_real)ba->X[i][a];
    }
    C[0] = (rp_real)V[0];
    C[1] = (rp_real)(0.5 * (V[1] + V[3]));
    C[2] = (rp_real)(0.5 * (V[2] + V[6]));
    C[3] = (rp_real)V[4];
    C[4] = (rp_real)(0.5 * (V[5] + V[7]));
    C[5] = (rp_real)V[8];
    return RP_OK;
}

rp_status_t rp_gcba_state(const rp_gcba_t *ba, rp_gcba_state_t *state)
{
    if (!ba || !state) {
        return RP_E_ARG;
    }
    *state = ba->state;
    return RP_OK;
}

rp_status_t rp_gcba_counts(const rp_gcba_t *ba, uint8_t *n_kf, uint16_t *n_lm)
{
    if (!ba) {
        return RP_E_ARG;
    }
    if (n_kf) {
        *n_kf = ba->n_kf;
    }
    if (n_lm) {
        *n_lm = ba->n_lm_tab;
    }
    return RP_OK;
}
