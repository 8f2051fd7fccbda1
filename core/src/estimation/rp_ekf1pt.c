/*
 * rp_ekf1pt.c - 1-point RANSAC around the pose EKF's update (Civera et al. 2010, algorithm 1).
 * See rp_ekf1pt.h for the method; the steps below are its numbers.
 */
#include <string.h>

#include "priv/rp_rng.h"
#include "priv/rp_math.h"
#include "rigpose/rp_ekf1pt.h"

#define NP 6
#define RESCUE_ROUNDS 3 /* updates from the prior at most (rescue rounds) */
#define LO_ROUNDS 3     /* refinements of one new best at most */
#define RESCUE_VAR RP_C(2.0) /* the rescue's pixel variance, in s2 / w */
#define LO_MAX_OBS 64   /* observations a refinement uses at most */
#define LO_ITERATIONS 2 /* linearisations of a refinement: the prior can be off by the motion
                         * of a frame (tens of px), where one linearisation leaves more than
                         * the gate */

rp_ekf1pt_params_t rp_ekf1pt_default_params(void)
{
    rp_ekf1pt_params_t p;
    p.confidence = RP_C(0.99);
    p.min_hyp = 2;
    p.max_hyp = 200;
    p.plain_without_majority = 0;
    p.regroup = 1;
    p.hyp_cams = 3;
    return p;
}

/* ---- generator (priv/rp_rng.h) ------------------------------------------------------------ */

rp_status_t rp_ekf1pt_seed(rp_ekf1pt_t *s, uint64_t seed)
{
    if (s == NULL) {
        return RP_E_ARG;
    }
    s->rng = rp_rng_state(seed);
    return RP_OK;
}

/* ---- helpers ------------------------------------------------------------------------------ */

/* S = J C J^T + s2w I (J 2x6, C 6x6 row-major) and CJt = C J^T (6x2). */
static void innov_cov(const rp_real J[12], const rp_real C[36], rp_real s2w, rp_real S[4],
                      rp_real CJt[12])
{
    for (int i = 0; i < NP; ++i) {
        for (int a = 0; a < 2; ++a) {
            rp_real acc = RP_C(0.0);
            for (int k = 0; k < NP; ++k) {
                acc += C[i * NP + k] * J[a * NP + k];
            }
            CJt[i * 2 + a] = acc;
        }
    }
    for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
            rp_real acc = RP_C(0.0);
            for (int k = 0; k < NP; ++k) {
                acc += J[a * NP + k] * CJt[k * 2 + b];
            }
            S[a * 2 + b] = acc + (a == b ? s2w : RP_C(0.0));
        }
    }
}

/* S^-1 of a 2x2; 0 if S is not positive definite. */
static int inv2(const rp_real S[4], rp_real Si[4])
{
    const rp_real det = S[0] * S[3] - S[1] * S[2];
    if (!(det > RP_C(0.0)) || !(S[0] > RP_C(0.0))) {
        return 0;
    }
    Si[0] = S[3] / det;
    Si[1] = -S[1] / det;
    Si[2] = -S[2] / det;
    Si[3] = S[0] / det;
    return 1;
}

static void pose_cov(const rp_ekf_t *ekf, rp_real C[36])
{
    for (int i = 0; i < NP; ++i) {
        for (int j = 0; j < NP; ++j) {
            C[i * NP + j] = ekf->P[i * RP_EKF_N + j];
        }
    }
}

static int obs_ok(const rp_rig_t *rig, const rp_obs_t *o)
{
    return rp_finite(o->w) && o->w > RP_C(0.0) && rp_all_finite(o->uv, 2) &&
           rp_all_finite(o->M, 3) && o->cam < rig->n_cams;
}

/* The pose at observation o's capture time from pose p, at e's rate and clock offsets
 * (rp_ekf.h, rp_pose_lin_at), into *pl; *pl is kept while the time does not change (*have: pl
 * holds the pose *delta after p). 0 if it cannot be formed. */
typedef struct {
    rp_pose_lin_t pl;
    rp_real delta;
    int have;
} campose_t;

static int obs_pose(const rp_ekf_t *e, const rp_real p[6], const rp_obs_t *o, campose_t *cp)
{
    const rp_real d = o->dt + (o->cam < RP_MAX_CAMS ? e->toff[o->cam] : RP_C(0.0));
    if (!cp->have || d != cp->delta) {
        cp->have = rp_pose_lin_at(&cp->pl, p, e->x + NP, d) == RP_OK;
        cp->delta = d;
    }
    return cp->have;
}

/* Pose p scored over the observations k with ok[k] (ok NULL: every one with obs_ok), each at
 * its camera's time at e's rate and offsets: cand[k] = 1 (cand may be NULL) for those with
 * w |z - h(p)|^2 <= thr2; returns their count, or 0 as soon as it cannot exceed `beat` (n_ok
 * of them in all). *cost (may be NULL): the MSAC cost, the sum of min(w |z - h(p)|^2, thr2),
 * thr2 for one that does not project (rp_ekf1pt_cost; only when the count ran to the end). */
static uint32_t score(const rp_rig_t *rig, const rp_ekf_t *e, const rp_obs_t *obs, uint32_t n,
                      const uint8_t *ok, const rp_real p[6], rp_real thr2, uint32_t n_ok,
                      uint32_t beat, uint8_t *cand, rp_real *cost)
{
    campose_t cp = {0};
    if (cand) {
        memset(cand, 0, n);
    }
    uint32_t c = 0, left = n_ok;
    rp_real sum = RP_C(0.0);
    for (uint32_t k = 0; k < n; ++k) {
        rp_real uv[2];
        if (ok ? !ok[k] : !obs_ok(rig, &obs[k])) {
            continue;
        }
        if (c + left <= beat) {
            return 0;
        }
        left--;
        if (!obs_pose(e, p, &obs[k], &cp) ||
            rp_rig_project(rig, obs[k].cam, &cp.pl, obs[k].M, uv, NULL, NULL) != RP_OK) {
            sum += thr2;
            continue;
        }
        const rp_real du = obs[k].uv[0] - uv[0], dv = obs[k].uv[1] - uv[1];
        const rp_real e2 = obs[k].w * (du * du + dv * dv);
        if (e2 <= thr2) {
            if (cand) {
                cand[k] = 1;
            }
            c++;
            sum += e2;
        } else {
            sum += thr2;
        }
    }
    if (cost) {
        *cost = sum;
    }
    return c;
}

/* Support of pose p among the usable observations (s->ok, n_ok of them) into s->cand: score() */
static uint32_t support(rp_ekf1pt_t *s, const rp_rig_t *rig, const rp_ekf_t *e,
                        const rp_obs_t *obs, uint32_t n, const rp_real p[6], rp_real thr2,
                        uint32_t n_ok, uint32_t beat)
{
    return score(rig, e, obs, n, s->ok, p, thr2, n_ok, beat, s->cand, NULL);
}

/* The gate's threshold on w |z - h|^2 in units of s2: gate_chi2, or 13.8 when the filter does
 * not gate */
static rp_real gate_of(const rp_ekf_t *ekf)
{
    return ekf->prm.gate_chi2 > RP_C(0.0) ? ekf->prm.gate_chi2 : RP_C(13.8);
}

rp_status_t rp_ekf1pt_cost(const rp_ekf_t *ekf, const rp_rig_t *rig, const rp_obs_t *obs,
                           uint32_t n, const rp_real p[6], rp_real *cost, uint32_t *inliers)
{
    if (!ekf || !rig || (n > 0 && !obs) || !p || !cost || !rp_all_finite(p, NP)) {
        return RP_E_ARG;
    }
    const rp_real thr2 = gate_of(ekf) * ekf->prm.sigma_px * ekf->prm.sigma_px;
    /* n_ok = n, beat 0: never stops early */
    const uint32_t c = score(rig, ekf, obs, n, NULL, p, thr2, n, 0, NULL, cost);
    if (inliers) {
        *inliers = c;
    }
    return RP_OK;
}

/* Draws needed for confidence when a fraction eps of the observations are inliers and a
 * hypothesis takes m of them. */
static uint32_t draws_needed(const rp_ekf1pt_params_t *prm, rp_real eps, uint32_t m)
{
    if (!(eps > RP_C(0.0))) {
        return prm->max_hyp;
    }
    if (!(eps < RP_C(1.0))) {
        return prm->min_hyp;
    }
    rp_real all_in = eps; /* eps^m: every observation of a hypothesis an inlier */
    for (uint32_t k = 1; k < m; ++k) {
        all_in *= eps;
    }
    const rp_real nf =
        rp_log(RP_C(1.0) - prm->confidence) / rp_log(RP_C(1.0) - all_in) + RP_C(1.0);
    if (!(nf < (rp_real)prm->max_hyp)) {
        return prm->max_hyp;
    }
    const uint32_t ni = (uint32_t)nf;
    return ni > prm->min_hyp ? ni : prm->min_hyp;
}

/* The support of a hypothesis that beat the best so far, from base (the prior, or in the
 * rescue's consensus the low-innovation posterior), refined (local optimisation, as
 * LO-RANSAC does for minimal solvers: O. Chum, J. Matas, J. Kittler, DAGM 2003): s->post =
 * base updated (LO_ITERATIONS linearisations) by at most LO_MAX_OBS of the c
 * observations in s->cand, every ceil(c / LO_MAX_OBS)-th of them (the observations come
 * grouped by camera, so the stride spreads them over the cameras), then that posterior's
 * support at threshold thr2 into s->cand. Returns its size, or 0 (s->cand cleared) if the
 * update failed. Why: a one-observation hypothesis fixes two of the six pose directions, the
 * other four stay at the prior's error, so under a wide prior its support is a small part of
 * the inliers and the adaptive count (eps = support / usable) would draw for a far worse
 * inlier ratio than the data's. Why a subset: the refined pose only has to score the others
 * within the pixel gate; LO_MAX_OBS inliers of 0.5 px pin it to about a tenth of a pixel, at
 * a fixed cost whatever the number of observations. */
static uint32_t local_opt(rp_ekf1pt_t *s, const rp_ekf_t *base, const rp_rig_t *rig,
                          const rp_obs_t *obs, uint32_t n, uint32_t c, rp_real thr2,
                          uint32_t n_ok)
{
    const uint32_t stride = (c + LO_MAX_OBS - 1) / LO_MAX_OBS;
    uint32_t m = 0, seen = 0;
    for (uint32_t k = 0; k < n && m < LO_MAX_OBS; ++k) {
        if (s->cand[k] && seen++ % stride == 0) {
            s->sel[m++] = obs[k];
        }
    }
    s->post = *base;
    s->post.prm.iterations = LO_ITERATIONS;
    s->post.prm.min_features = 1;
    if (rp_ekf_update(&s->post, rig, s->sel, m, NULL, NULL) != RP_OK) {
        s->post = *base;
        memset(s->cand, 0, n);
        return 0;
    }
    return support(s, rig, &s->post, obs, n, s->post.x, thr2, n_ok, 0);
}

/* Hypothesis from the single observation i: base's pose updated by it (one linearisation at
 * base's pose p0, pose covariance C) into p. 0 if it cannot be formed. */
static int hyp_one(const rp_ekf_t *base, const rp_rig_t *rig, const rp_obs_t *o,
                   const rp_real C[36], rp_real s2, campose_t *cp0, rp_real p[NP])
{
    rp_real uv[2], J[12], S[4], Si[4], CJt[12];
    if (!obs_pose(base, base->x, o, cp0) ||
        rp_rig_project(rig, o->cam, &cp0->pl, o->M, uv, J, NULL) != RP_OK) {
        return 0;
    }
    innov_cov(J, C, s2 / o->w, S, CJt);
    if (!inv2(S, Si)) {
        return 0;
    }
    const rp_real r[2] = {o->uv[0] - uv[0], o->uv[1] - uv[1]};
    const rp_real g[2] = {Si[0] * r[0] + Si[1] * r[1], Si[2] * r[0] + Si[3] * r[1]};
    rp_real d[NP]; /* p = p0 [+] d, the chart of rp_rig.h */
    for (int a = 0; a < NP; ++a) {
        d[a] = CJt[a * 2] * g[0] + CJt[a * 2 + 1] * g[1];
    }
    return rp_pose_plus(base->x, d, p) == RP_OK;
}

/* Step 1 from base (the prior; in the rescue's consensus, the low-innovation posterior): up to
 * the adaptive count of hypotheses, each drawn from usable observations (s->ok, n_ok of them)
 * uniformly: one, then one of each further camera up to prm->hyp_cams (rp_ekf1pt.h), base's
 * pose updated by them; its support at pixel threshold thr2 and, for each new best, its local
 * optimisation. On return s->best is the largest support, s->post its refined posterior (base
 * if none was refined), *n_hyp the hypotheses drawn; returns the support's size. */
static uint32_t draw_consensus(rp_ekf1pt_t *s, const rp_ekf_t *base, const rp_rig_t *rig,
                               const rp_obs_t *obs, uint32_t n, uint32_t n_ok,
                               const rp_ekf1pt_params_t *prm, rp_real s2, rp_real thr2,
                               uint32_t *n_hyp)
{
    rp_real C[36];
    campose_t cp0 = {0};
    pose_cov(base, C);
    s->post = *base;
    uint32_t best = 0, need = prm->max_hyp, h = 0, m_pool = 0, cams = 0;
    for (uint32_t k = 0; k < n; ++k) { /* s->pool[j]: the j-th usable observation */
        if (s->ok[k]) {
            s->pool[m_pool++] = (uint16_t)k;
            cams |= 1u << obs[k].cam;
        }
    }
    uint32_t m_hyp = 0; /* observations of a hypothesis: hyp_cams, or the cameras there are */
    for (; cams != 0u; cams &= cams - 1u) {
        m_hyp++;
    }
    m_hyp = m_hyp < prm->hyp_cams ? m_hyp : prm->hyp_cams;
    memset(s->best, 0, n);
    for (; h < need && m_pool > 0; ++h) {
        const uint32_t i = s->pool[rp_rng_below(&s->rng, m_pool)];
        uint32_t m = 1, in_cams = 1u << obs[i].cam;
        s->sel[0] = obs[i];
        for (int t = 0; t < RP_EKF1PT_HYP_TRIES && m < m_hyp; ++t) {
            const uint32_t j = s->pool[rp_rng_below(&s->rng, m_pool)];
            if (!(in_cams & (1u << obs[j].cam))) {
                in_cams |= 1u << obs[j].cam;
                s->sel[m++] = obs[j];
            }
        }
        rp_real p[NP];
        if (m == 1) {
            if (!hyp_one(base, rig, &obs[i], C, s2, &cp0, p)) {
                continue;
            }
        } else {
            s->hyp = *base;
            s->hyp.prm.iterations = LO_ITERATIONS;
            s->hyp.prm.min_features = 1;
            if (rp_ekf_update(&s->hyp, rig, s->sel, m, NULL, NULL) != RP_OK) {
                continue;
            }
            memcpy(p, s->hyp.x, sizeof(p));
        }
        const uint32_t c = support(s, rig, base, obs, n, p, thr2, n_ok, best);
        if (c > best) {
            /* the hypothesis's own support, then its refinement's if that is larger */
            best = c;
            memcpy(s->best, s->cand, n);
            /* refined while its support grows (LO_ROUNDS at most): each round's posterior
             * sees more of the pose directions, so its support reaches further */
            for (int lo = 0; lo < LO_ROUNDS; ++lo) {
                const rp_ekf_t post_before = s->post;
                const uint32_t c_lo = local_opt(s, base, rig, obs, n, best, thr2, n_ok);
                if (c_lo <= best) {
                    if (c_lo == 0) {
                        s->post = post_before; /* the update failed */
                    }
                    break;
                }
                best = c_lo;
                memcpy(s->best, s->cand, n);
            }
            need = draws_needed(prm, (rp_real)best / (rp_real)n_ok, m_hyp);
        }
    }
    *n_hyp = h;
    return best;
}

/* Observations usable, not in s->best and inside the filter's gate at ekf's state with its
 * pose covariance, r^T (J C J^T + s2 / w I)^-1 r <= gate, are added to s->best. Returns how
 * many. */
static uint32_t rescue(rp_ekf1pt_t *s, const rp_ekf_t *ekf, const rp_rig_t *rig,
                       const rp_obs_t *obs, uint32_t n, rp_real s2, rp_real gate)
{
    rp_real C[36];
    campose_t cp = {0};
    pose_cov(ekf, C);
    uint32_t added = 0;
    for (uint32_t k = 0; k < n; ++k) {
        rp_real uv[2], J[12], S[4], Si[4], CJt[12];
        if (!s->ok[k] || s->best[k] || !obs_pose(ekf, ekf->x, &obs[k], &cp) ||
            rp_rig_project(rig, obs[k].cam, &cp.pl, obs[k].M, uv, J, NULL) != RP_OK) {
            continue;
        }
        innov_cov(J, C, RESCUE_VAR * s2 / obs[k].w, S, CJt);
        if (!inv2(S, Si)) {
            continue;
        }
        const rp_real r[2] = {obs[k].uv[0] - uv[0], obs[k].uv[1] - uv[1]};
        const rp_real d2 =
            r[0] * (Si[0] * r[0] + Si[1] * r[1]) + r[1] * (Si[2] * r[0] + Si[3] * r[1]);
        if (d2 <= gate) {
            s->best[k] = 1;
            added++;
        }
    }
    return added;
}

/* Step 3: `rounds` at most of one update from the prior on s->best (the others weighted 0;
 * used flags into s->cand), each but the last followed by a rescue against its posterior
 * that, if it adds any, makes the next round. The last update's status. */
static rp_status_t update_rounds(rp_ekf1pt_t *s, rp_ekf_t *ekf, const rp_rig_t *rig,
                                 const rp_obs_t *obs, uint32_t n, rp_real s2, rp_real gate,
                                 int rounds, rp_ekf_info_t *info)
{
    rp_status_t st = RP_OK;
    for (int round = 0; round < rounds; ++round) {
        for (uint32_t k = 0; k < n; ++k) {
            s->sel[k] = obs[k];
            if (!s->best[k]) {
                s->sel[k].w = RP_C(0.0);
            }
        }
        *ekf = s->prior;
        st = rp_ekf_update(ekf, rig, s->sel, n, s->cand, info);
        if (st != RP_OK || round + 1 == rounds) {
            break;
        }
        if (rescue(s, ekf, rig, obs, n, s2, gate) == 0) {
            break;
        }
    }
    return st;
}

/* The variance per pixel coordinate that the low-innovation consensus (s->low) shows at its
 * own posterior (s->post), mean w |z - h|^2 / 2, or s2 if that is larger: the scale of what
 * the model leaves of its inliers (the pixel noise, and errors of the map that the pose update
 * does not model, e.g. gc's and mono's depths before they converge). */
static rp_real spread(const rp_ekf1pt_t *s, const rp_rig_t *rig, const rp_obs_t *obs,
                      uint32_t n, rp_real s2)
{
    campose_t cp = {0};
    rp_real acc = RP_C(0.0);
    uint32_t m = 0;
    for (uint32_t k = 0; k < n; ++k) {
        rp_real uv[2];
        if (!s->low[k] || !obs_pose(&s->post, s->post.x, &obs[k], &cp) ||
            rp_rig_project(rig, obs[k].cam, &cp.pl, obs[k].M, uv, NULL, NULL) != RP_OK) {
            continue;
        }
        const rp_real du = obs[k].uv[0] - uv[0], dv = obs[k].uv[1] - uv[1];
        acc += obs[k].w * (du * du + dv * dv);
        m++;
    }
    const rp_real v = m > 0 ? acc / (RP_C(2.0) * (rp_real)m) : s2;
    return v > s2 ? v : s2;
}

/* 1 if every observation the update used (s->cand) and the low-innovation consensus did not
 * hold (s->low) is within thr2 of the posterior ekf: w |z - h(x+)|^2 <= thr2, thr2 the gate
 * on the consensus's own spread. (An observation inside an update has a posterior residual of
 * variance under that of the data, so only a rescued group that the update could not fit
 * together with the rest fails it.) */
static int consistent(const rp_ekf1pt_t *s, const rp_ekf_t *ekf, const rp_rig_t *rig,
                      const rp_obs_t *obs, uint32_t n, rp_real thr2)
{
    campose_t cp = {0};
    for (uint32_t k = 0; k < n; ++k) {
        rp_real uv[2];
        if (!s->cand[k] || s->low[k]) {
            continue;
        }
        if (!obs_pose(ekf, ekf->x, &obs[k], &cp) ||
            rp_rig_project(rig, obs[k].cam, &cp.pl, obs[k].M, uv, NULL, NULL) != RP_OK) {
            return 0;
        }
        const rp_real du = obs[k].uv[0] - uv[0], dv = obs[k].uv[1] - uv[1];
        if (obs[k].w * (du * du + dv * dv) > thr2) {
            return 0;
        }
    }
    return 1;
}

rp_status_t rp_ekf1pt_update(rp_ekf1pt_t *s, rp_ekf_t *ekf, const rp_rig_t *rig,
                             const rp_obs_t *obs, uint32_t n, const rp_ekf1pt_params_t *prm,
                             uint8_t *used, rp_ekf1pt_info_t *info)
{
    rp_ekf1pt_info_t dummy;
    if (!info) {
        info = &dummy;
    }
    memset(info, 0, sizeof(*info));
    const rp_ekf1pt_params_t def = rp_ekf1pt_default_params();
    if (!prm) {
        prm = &def;
    }
    if (!s || !ekf || !rig || (n > 0 && !obs) || n > RP_EKF1PT_MAX_OBS ||
        !(prm->confidence > RP_C(0.0) && prm->confidence < RP_C(1.0)) || prm->max_hyp < 1 ||
        prm->min_hyp > prm->max_hyp || prm->plain_without_majority > 1 || prm->regroup > 1 ||
        prm->hyp_cams < 1 || prm->hyp_cams > RP_MAX_CAMS) {
        return RP_E_ARG;
    }
    if (used) {
        memset(used, 0, n);
    }
    const rp_real s2 = ekf->prm.sigma_px * ekf->prm.sigma_px;
    const rp_real gate = gate_of(ekf);
    const rp_real thr2 = gate * s2;
    rp_real C[36], p0[NP];
    pose_cov(ekf, C);
    memcpy(p0, ekf->x, sizeof(p0));
    rp_pose_lin_t pl0;
    if (!rp_all_finite(p0, NP) || !rp_all_finite(C, 36) || rp_pose_lin_set(&pl0, p0) != RP_OK) {
        return rp_ekf_update(ekf, rig, obs, n, used, &info->ekf); /* its fault handling */
    }

    /* Step 1: usable observations, then hypotheses from single ones (each observation at its
     * camera's time: the prior's pose there). */
    uint32_t n_ok = 0;
    campose_t cp0 = {0};
    for (uint32_t k = 0; k < n; ++k) {
        rp_real uv[2];
        s->ok[k] = (uint8_t)(obs_ok(rig, &obs[k]) && obs_pose(ekf, p0, &obs[k], &cp0) &&
                             rp_rig_project(rig, obs[k].cam, &cp0.pl, obs[k].M, uv, NULL,
                                            NULL) == RP_OK);
        n_ok += s->ok[k];
    }
    info->n_usable = (uint16_t)n_ok;
    if (n_ok < ekf->prm.min_features) {
        return rp_ekf_update(ekf, rig, obs, n, used, &info->ekf);
    }
    s->prior = *ekf;
    uint32_t h = 0;
    const uint32_t best = draw_consensus(s, &s->prior, rig, obs, n, n_ok, prm, s2, thr2, &h);
    info->n_hyp = (uint16_t)h;
    info->n_low = (uint16_t)best;

    /* Steps 2-3: the high-innovation inliers are rescued against the low-innovation
     * consensus's posterior (s->post, one linearisation), then ONE update from the prior on
     * consensus + rescued: the filter's own iterated, gated update on the inlier set. (Two
     * partial updates in a row, the paper's order, relinearise the second at the first's
     * posterior and gate it against that posterior's covariance; on outlier-free data they
     * then differ from the plain update, measured as up to 1.14x the error of Table 1.) A
     * further round tests what is still left out against the final posterior and repeats the
     * update if it adds any (RESCUE_ROUNDS in all). */
    memcpy(s->low, s->best, n);
    const uint32_t n_in = best + rescue(s, &s->post, rig, obs, n, s2, gate);
    if (prm->plain_without_majority && 2u * n_in < n_ok) {
        /* No majority: the consensus judges the model (e.g. a map whose errors exceed a tiny
         * sigma_px), not the observations: the filter's plain update, as rp_ekf_update itself
         * uses every feature when its gate would reject more than it keeps. */
        *ekf = s->prior;
        const rp_status_t st0 = rp_ekf_update(ekf, rig, obs, n, used, &info->ekf);
        info->n_no_majority = 1;
        return st0;
    }
    rp_status_t st = update_rounds(s, ekf, rig, obs, n, s2, gate, RESCUE_ROUNDS, &info->ekf);
    /* A camera whose clock jumped (rp_ekf_clock_jumps on the consensus): its features are all
     * outliers of a prior that puts them at the old offset. Its offset restarts, and the
     * filter's plain gated update runs from the prior on every observation. */
    if (st == RP_OK && s->prior.toff_mask) {
        uint16_t in_cam[RP_MAX_CAMS] = {0}, out_cam[RP_MAX_CAMS] = {0};
        for (uint32_t k = 0; k < n; ++k) {
            if (s->ok[k] && obs[k].cam < RP_MAX_CAMS) {
                in_cam[obs[k].cam] = (uint16_t)(in_cam[obs[k].cam] + (s->cand[k] != 0));
                out_cam[obs[k].cam] = (uint16_t)(out_cam[obs[k].cam] + (s->cand[k] == 0));
            }
        }
        const uint8_t jumped = rp_ekf_clock_jumps(&s->prior, in_cam, out_cam);
        if (jumped) {
            *ekf = s->prior;
            rp_ekf_toff_restart(ekf, jumped);
            const rp_status_t st1 = rp_ekf_update(ekf, rig, obs, n, used, &info->ekf);
            info->ekf.toff_reset = (uint8_t)(info->ekf.toff_reset | jumped);
            return st1;
        }
    }
    /* (after the clock-jump test: a jumped camera's features are a consistent group, which the
     * redrawn rescue could take in) */
    const rp_real thr2c = st == RP_OK && prm->regroup ? gate * spread(s, rig, obs, n, s2) : thr2;
    if (st == RP_OK && prm->regroup && !consistent(s, ekf, rig, obs, n, thr2c)) {
        /* Step 2b (rp_ekf1pt.h): the rescued ones did not fit together; their own consensus
         * from the low-innovation posterior (s->post, still the one the rescue used) */
        uint32_t m = 0, h2 = 0;
        for (uint32_t k = 0; k < n; ++k) {
            s->ok_all[k] = s->ok[k];
            s->ok[k] = (uint8_t)(s->ok[k] && s->best[k] && !s->low[k]);
            m += s->ok[k];
        }
        s->base = s->post;
        (void)draw_consensus(s, &s->base, rig, obs, n, m, prm, s2, thr2, &h2);
        for (uint32_t k = 0; k < n; ++k) {
            s->ok[k] = s->ok_all[k];
            s->best[k] = (uint8_t)(s->best[k] || s->low[k]);
        }
        info->n_hyp_regroup = (uint16_t)h2;
        info->n_reconsensus = 1;
        st = update_rounds(s, ekf, rig, obs, n, s2, gate, RESCUE_ROUNDS, &info->ekf);
        if (st == RP_OK && !consistent(s, ekf, rig, obs, n, thr2c)) {
            /* the redrawn group does not fit the consensus either (the rescue's largest
             * group was the one the consensus had left out, a moving object against a
             * consensus that holds the scene): the consensus alone */
            memcpy(s->best, s->low, n);
            info->n_reconsensus = 2;
            st = update_rounds(s, ekf, rig, obs, n, s2, gate, 1, &info->ekf);
        }
    }
    if (used) {
        memcpy(used, s->cand, n);
    }
    if (st != RP_OK) {
        return st;
    }
    uint32_t n_used = 0, n_res_used = 0;
    for (uint32_t k = 0; k < n; ++k) {
        n_used += s->cand[k];
        n_res_used += s->cand[k] && !s->low[k];
    }
    info->n_rescued = (uint16_t)n_res_used;
    info->ekf.n_used = (uint16_t)n_used;
    info->ekf.n_bad = (uint16_t)(n - n_ok);
    info->ekf.n_gated = (uint16_t)(n_ok - n_used);
    info->ekf.n_outside = info->ekf.n_gated; /* left out of the consensus */
    return RP_OK;
}
