/*
 * rp_ransac.c - minimal-solver RANSAC for the rig pose (P3P per camera, scored over every
 * camera through eq. (2)), then Lowe's method on the consensus. The algorithm, its equations and
 * its choices are in rp_ransac.h.
 */
#include "priv/rp_rng.h"
#include "rigpose/rp_ransac.h"

#include <stddef.h>
#include <string.h>

#include "priv/rp_math.h"
#include "rigpose/rp_camera.h"
#include "rigpose/rp_p3p.h"
#include "rigpose/rp_rot.h"

RP_STATIC_ASSERT(RP_RANSAC_MAX_OBS <= 0x7fffffff, "observation index range");

/* Draws of one sample that may fail (degenerate triple) before the sample counts as drawn. */
#define RANSAC_DRAW_TRIES 8

rp_ransac_params_t rp_ransac_default_params(void)
{
    rp_ransac_params_t prm;
    prm.sigma_px = RP_C(1.0);
    prm.chi2 = RP_C(9.21);
    prm.confidence = RP_C(0.999);
    prm.min_iter = 16;
    prm.max_iter = 2000;
    prm.min_inliers = 8;
    prm.refine_rounds = 3;
    prm.local_opt = 1;
    prm.lowe = rp_lowe_default_params();
    return prm;
}

/* ---- generator (priv/rp_rng.h) ------------------------------------------------------------ */

rp_status_t rp_ransac_seed(rp_ransac_t *rs, uint64_t seed)
{
    if (rs == NULL) {
        return RP_E_ARG;
    }
    rs->rng = rp_rng_state(seed);
    return RP_OK;
}

/* ---- scoring ------------------------------------------------------------------------------ */

typedef struct {
    uint32_t inl;                 /* inliers */
    rp_real cost;                 /* truncated cost sum min(w e^2, thr^2), px^2 */
    uint32_t per_cam[RP_MAX_CAMS];/* inliers per camera */
} score_t;

/* Score pose p over every usable observation. Stops early (returns 0) once it cannot beat
 * `best_inl` inliers; mask (may be NULL) gets the inlier flags when it runs to the end. */
static int score_pose(const rp_ransac_t *rs, const rp_rig_t *rig, const rp_obs_t *obs,
                      uint32_t n, uint32_t n_usable, const rp_real p[6], rp_real thr2,
                      uint32_t best_inl, uint8_t *mask, score_t *sc)
{
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, p) != RP_OK) {
        return 0;
    }
    memset(sc, 0, sizeof *sc);
    uint32_t seen = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (!rs->usable[i]) {
            if (mask) {
                mask[i] = 0;
            }
            continue;
        }
        ++seen;
        const rp_obs_t *o = &obs[i];
        rp_real uv[2];
        int in = 0;
        rp_real e2 = thr2;
        if (rp_rig_project(rig, o->cam, &pl, o->M, uv, NULL, NULL) == RP_OK) {
            const rp_real du = o->uv[0] - uv[0], dv = o->uv[1] - uv[1];
            const rp_real we = o->w * (du * du + dv * dv);
            if (we <= thr2) {
                in = 1;
                e2 = we;
            }
        }
        if (mask) {
            mask[i] = (uint8_t)in;
        }
        if (in) {
            sc->inl++;
            sc->per_cam[o->cam]++;
        }
        sc->cost += e2;
        if (mask == NULL && sc->inl + (n_usable - seen) < best_inl) {
            return 0;
        }
    }
    return 1;
}

/* a better than b: more inliers, or as many at a lower truncated cost */
static int better(const score_t *a, const score_t *b)
{
    return a->inl > b->inl || (a->inl == b->inl && a->cost < b->cost);
}

/* Draws needed for `confidence` given the best's per-camera inliers (rp_ransac.h, step 5). */
static uint32_t needed_iters(const rp_ransac_t *rs, const rp_rig_t *rig, const score_t *best,
                             uint32_t n_samp, const rp_ransac_params_t *prm)
{
    rp_real s = RP_C(0.0);
    for (uint8_t c = 0; c < rig->n_cams; ++c) {
        const uint32_t nc = rs->cam_start[c + 1] - rs->cam_start[c];
        const uint32_t kc = best->per_cam[c] < nc ? best->per_cam[c] : nc;
        if (nc < 3 || kc < 3) {
            continue;
        }
        const rp_real pc = ((rp_real)kc / (rp_real)nc) * ((rp_real)(kc - 1) / (rp_real)(nc - 1)) *
                           ((rp_real)(kc - 2) / (rp_real)(nc - 2));
        s += ((rp_real)nc / (rp_real)n_samp) * pc;
    }
    if (!(s > RP_C(0.0))) {
        return prm->max_iter;
    }
    if (s >= RP_C(1.0)) {
        return prm->min_iter;
    }
    const rp_real num = rp_log(RP_C(1.0) - prm->confidence);
    const rp_real den = rp_log(RP_C(1.0) - s);
    if (!(den < RP_C(0.0))) {
        return prm->max_iter;
    }
    const rp_real nf = num / den + RP_C(1.0);
    if (!(nf < (rp_real)prm->max_iter)) {
        return prm->max_iter;
    }
    const uint32_t ni = (uint32_t)nf;
    return ni > prm->min_iter ? ni : prm->min_iter;
}

/* Rig pose p of a world -> camera-k pose (rp_ransac.h, step 3). 0 if the angles fail. */
static int rig_pose_from_cam(const rp_rig_cam_t *ck, const rp_p3p_pose_t *cp, rp_real p[6])
{
    rp_real RkRc[9], Rj[9], v[3], d[3];
    rp_rot_mul(ck->R, cp->R, RkRc);
    rp_rot_transpose(RkRc, Rj);
    rp_rot_apply(ck->R, cp->t, v);
    for (int i = 0; i < 3; ++i) {
        v[i] += ck->D[i];
    }
    rp_rot_apply(Rj, v, d);
    for (int i = 0; i < 3; ++i) {
        p[i] = -d[i];
    }
    if (rp_rot_to_angles(Rj, &p[3]) != RP_OK) {
        return 0;
    }
    return rp_all_finite(p, 6);
}

/* Lowe's method on the inliers of pose p (score *sc), from p; the result replaces p and *sc
 * if it scores better (rp_ransac.h, step 5). Uses rs->cand and rs->sel. */
static void local_opt(rp_ransac_t *rs, const rp_rig_t *rig, const rp_obs_t *obs, uint32_t n,
                      uint32_t n_usable, const rp_ransac_params_t *prm, rp_real thr2,
                      rp_real p[6], score_t *sc)
{
    score_t s0, s1;
    if (!score_pose(rs, rig, obs, n, n_usable, p, thr2, 0, rs->cand, &s0)) {
        return;
    }
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (rs->cand[i]) {
            rs->sel[m++] = obs[i];
        }
    }
    rp_real q[6];
    memcpy(q, p, sizeof q);
    const rp_status_t st = rp_lowe_solve(rig, rs->sel, m, &prm->lowe, q, NULL, NULL);
    if (st != RP_OK && st != RP_E_NO_CONVERGE) {
        return;
    }
    if (score_pose(rs, rig, obs, n, n_usable, q, thr2, sc->inl, NULL, &s1) && better(&s1, sc)) {
        *sc = s1;
        memcpy(p, q, sizeof q);
    }
}

/* ---- the solver --------------------------------------------------------------------------- */

static rp_status_t check_params(const rp_ransac_params_t *prm)
{
    if (!(prm->sigma_px > RP_C(0.0)) || !(prm->chi2 > RP_C(0.0)) || !rp_finite(prm->sigma_px) ||
        !rp_finite(prm->chi2) || !(prm->confidence > RP_C(0.0)) ||
        !(prm->confidence < RP_C(1.0)) || prm->max_iter < 1 || prm->min_iter > prm->max_iter ||
        prm->min_inliers < 4) {
        return RP_E_ARG;
    }
    return RP_OK;
}

/* Validate the observations, unproject the usable ones, group them by camera. */
static rp_status_t prepare(rp_ransac_t *rs, const rp_rig_t *rig, const rp_obs_t *obs,
                           uint32_t n, uint32_t *n_usable)
{
    uint32_t count[RP_MAX_CAMS] = {0};
    *n_usable = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const rp_obs_t *o = &obs[i];
        if (o->cam >= rig->n_cams) {
            return RP_E_ARG;
        }
        if (!rp_all_finite(o->uv, 2) || !rp_all_finite(o->M, 3) || !rp_finite(o->w)) {
            return RP_E_NAN;
        }
        if (o->w < RP_C(0.0)) {
            return RP_E_ARG;
        }
        rs->usable[i] = 0;
        if (!(o->w > RP_C(0.0))) {
            continue;
        }
        rp_real xn[2];
        if (rp_cam_unproject(&rig->cam[o->cam].cam, o->uv, xn) != RP_OK) {
            continue;
        }
        const rp_real nr = rp_sqrt(xn[0] * xn[0] + xn[1] * xn[1] + RP_C(1.0));
        rs->ray[i][0] = xn[0] / nr;
        rs->ray[i][1] = xn[1] / nr;
        rs->ray[i][2] = RP_C(1.0) / nr;
        rs->usable[i] = 1;
        count[o->cam]++;
        (*n_usable)++;
    }
    /* counting sort of the usable observations by camera */
    rs->cam_start[0] = 0;
    for (uint8_t c = 0; c < RP_MAX_CAMS; ++c) {
        rs->cam_start[c + 1] = rs->cam_start[c] + (c < rig->n_cams ? count[c] : 0);
    }
    uint32_t fill[RP_MAX_CAMS];
    for (uint8_t c = 0; c < RP_MAX_CAMS; ++c) {
        fill[c] = rs->cam_start[c];
    }
    for (uint32_t i = 0; i < n; ++i) {
        if (rs->usable[i]) {
            rs->order[fill[obs[i].cam]++] = i;
        }
    }
    return RP_OK;
}

/* Draw three distinct usable observations of one camera (rp_ransac.h, step 2) from the n_samp
 * observations of sampleable cameras; idx gets their indices in obs. */
static void draw_sample(rp_ransac_t *rs, const rp_rig_t *rig, uint32_t n_samp, uint32_t idx[3])
{
    /* position among the sampleable observations -> camera */
    uint32_t r = rp_rng_below(&rs->rng, n_samp);
    uint8_t c = 0;
    for (c = 0; c < rig->n_cams; ++c) {
        const uint32_t nc = rs->cam_start[c + 1] - rs->cam_start[c];
        if (nc < 3) {
            continue;
        }
        if (r < nc) {
            break;
        }
        r -= nc;
    }
    const uint32_t base = rs->cam_start[c], nc = rs->cam_start[c + 1] - base;
    const uint32_t a = r;
    uint32_t b = rp_rng_below(&rs->rng, nc - 1);
    b += b >= a;
    uint32_t k = rp_rng_below(&rs->rng, nc - 2);
    /* k-th of the indices other than a and b, in increasing order */
    const uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    k += k >= lo;
    k += k >= hi;
    idx[0] = rs->order[base + a];
    idx[1] = rs->order[base + b];
    idx[2] = rs->order[base + k];
}

/* Weighted RMS per pixel coordinate of the inliers of mask at p. */
static rp_real inlier_rms(const rp_rig_t *rig, const rp_obs_t *obs, uint32_t n,
                          const uint8_t *mask, const rp_real p[6])
{
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, p) != RP_OK) {
        return RP_C(0.0);
    }
    rp_real cost = RP_C(0.0), wsum = RP_C(0.0);
    for (uint32_t i = 0; i < n; ++i) {
        rp_real uv[2];
        if (!mask[i] || rp_rig_project(rig, obs[i].cam, &pl, obs[i].M, uv, NULL, NULL) != RP_OK) {
            continue;
        }
        const rp_real du = obs[i].uv[0] - uv[0], dv = obs[i].uv[1] - uv[1];
        cost += obs[i].w * (du * du + dv * dv);
        wsum += obs[i].w;
    }
    return wsum > RP_C(0.0) ? rp_sqrt(cost / (RP_C(2.0) * wsum)) : RP_C(0.0);
}

rp_status_t rp_ransac_solve(rp_ransac_t *rs, const rp_rig_t *rig, const rp_obs_t *obs,
                            uint32_t n, const rp_ransac_params_t *prm_in, uint8_t *inlier,
                            rp_ransac_result_t *res)
{
    if (rs == NULL || rig == NULL || res == NULL || (obs == NULL && n > 0) ||
        n > RP_RANSAC_MAX_OBS) {
        return RP_E_ARG;
    }
    memset(res, 0, sizeof *res);
    const rp_ransac_params_t prm = prm_in ? *prm_in : rp_ransac_default_params();
    rp_status_t st = check_params(&prm);
    if (st == RP_OK) {
        st = rp_rig_check(rig);
    }
    if (st != RP_OK) {
        return st;
    }
    uint32_t n_usable = 0;
    st = prepare(rs, rig, obs, n, &n_usable);
    if (st != RP_OK) {
        return st;
    }
    uint8_t *mask = inlier ? inlier : rs->mask;
    for (uint32_t i = 0; i < n; ++i) {
        mask[i] = 0;
    }
    const rp_real thr = prm.sigma_px * rp_sqrt(prm.chi2), thr2 = thr * thr;
    res->n_usable = n_usable;
    res->thresh_px = thr;
    uint32_t n_samp = 0;
    for (uint8_t c = 0; c < rig->n_cams; ++c) {
        const uint32_t nc = rs->cam_start[c + 1] - rs->cam_start[c];
        n_samp += nc >= 3 ? nc : 0;
    }
    if (n_usable < 4 || n_samp == 0) {
        return RP_E_TOO_FEW;
    }

    /* ---- hypothesise and score ---- */
    score_t best;
    memset(&best, 0, sizeof best);
    best.cost = (rp_real)n_usable * thr2 + RP_C(1.0);
    rp_real best_p[6] = {0};
    int have = 0;
    uint32_t need = prm.max_iter, it = 0;
    for (it = 0; it < need && it < prm.max_iter; ++it) {
        rp_p3p_pose_t sol[RP_P3P_MAX_SOLS];
        uint8_t ns = 0;
        uint32_t idx[3];
        for (int tries = 0; tries < RANSAC_DRAW_TRIES && ns == 0; ++tries) {
            draw_sample(rs, rig, n_samp, idx);
            const rp_real y[3][3] = {
                {rs->ray[idx[0]][0], rs->ray[idx[0]][1], rs->ray[idx[0]][2]},
                {rs->ray[idx[1]][0], rs->ray[idx[1]][1], rs->ray[idx[1]][2]},
                {rs->ray[idx[2]][0], rs->ray[idx[2]][1], rs->ray[idx[2]][2]}};
            const rp_real X[3][3] = {{obs[idx[0]].M[0], obs[idx[0]].M[1], obs[idx[0]].M[2]},
                                     {obs[idx[1]].M[0], obs[idx[1]].M[1], obs[idx[1]].M[2]},
                                     {obs[idx[2]].M[0], obs[idx[2]].M[1], obs[idx[2]].M[2]}};
            if (rp_p3p_solve(y, X, sol, &ns) != RP_OK) {
                ns = 0;
            }
        }
        const rp_rig_cam_t *ck = &rig->cam[obs[idx[0]].cam];
        for (uint8_t s = 0; s < ns; ++s) {
            rp_real p[6];
            if (!rig_pose_from_cam(ck, &sol[s], p)) {
                continue;
            }
            res->n_hyp++;
            score_t sc;
            if (!score_pose(rs, rig, obs, n, n_usable, p, thr2, have ? best.inl : 0, NULL, &sc)) {
                continue;
            }
            if (!have || better(&sc, &best)) {
                best = sc;
                memcpy(best_p, p, sizeof best_p);
                have = 1;
                if (prm.local_opt && best.inl >= prm.min_inliers) {
                    local_opt(rs, rig, obs, n, n_usable, &prm, thr2, best_p, &best);
                }
                need = needed_iters(rs, rig, &best, n_samp, &prm);
            }
        }
    }
    res->iters = it;
    if (!have) {
        return RP_E_TOO_FEW;
    }

    /* ---- refine on the consensus, re-score, repeat ---- */
    score_pose(rs, rig, obs, n, n_usable, best_p, thr2, 0, mask, &best);
    for (uint8_t round = 0; round < prm.refine_rounds && best.inl >= 4; ++round) {
        uint32_t m = 0;
        for (uint32_t i = 0; i < n; ++i) {
            if (mask[i]) {
                rs->sel[m++] = obs[i];
            }
        }
        rp_real p[6];
        memcpy(p, best_p, sizeof p);
        st = rp_lowe_solve(rig, rs->sel, m, &prm.lowe, p, NULL, NULL);
        if (st != RP_OK && st != RP_E_NO_CONVERGE) {
            break; /* keep the hypothesis: the consensus does not fix the pose better */
        }
        score_t sc;
        score_pose(rs, rig, obs, n, n_usable, p, thr2, 0, rs->cand, &sc);
        if (sc.inl < best.inl) {
            break; /* refinement lost inliers: keep the previous pose and mask */
        }
        int same = 1;
        for (uint32_t i = 0; i < n; ++i) {
            if (rs->cand[i] != mask[i]) {
                same = 0;
            }
        }
        memcpy(mask, rs->cand, n);
        best = sc;
        memcpy(best_p, p, sizeof best_p);
        if (same) {
            break;
        }
    }
    memcpy(res->p, best_p, sizeof res->p);
    res->n_inliers = best.inl;
    res->rms_px = inlier_rms(rig, obs, n, mask, best_p);
    return best.inl >= prm.min_inliers ? RP_OK : RP_E_TOO_FEW;
}
