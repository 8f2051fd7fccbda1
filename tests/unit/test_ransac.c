/*
 * test_ransac.c - rig RANSAC (rp_ransac_solve) on the paper's simulated rig (rp_sim: six
 * cameras, 640x480, fx = fy = 800 px, points in the 0.667-1 m shell, 0.5 px noise): the pose
 * recovered with 0, 30 and 60 % gross outliers (uniform pixels) in every camera and the outliers
 * flagged; the pose found when only one camera has inliers; no prior needed where Lowe's method
 * from a wrong constant-velocity start fails; determinism per seed; bad input refused.
 *
 * Yardstick: the pose error of Lowe's method started at the truth on the true inliers only (the
 * oracle that knows which observations are outliers). RANSAC must come within a small factor of
 * it, and within an absolute bound.
 */
#include "rp_test.h"

#include <stdlib.h>
#include <string.h>

#include "rigpose/rp_lowe.h"
#include "rigpose/rp_ransac.h"
#include "rigpose/rp_rot.h"
#include "rp_sim.h"

#define SIGMA_PX 0.5

/* Pose error bounds. Measured worst over the 0/30/60 % cases here: 5.9e-5 m, 8.3e-5 rad, in
 * double and float alike (the 0.5 px noise dominates; float's rounding at 1 m is 6e-8). The
 * double bound is 4x that; float's is twice double's because its Lowe's method stops at a
 * 1e-6 step (double: 1e-10) and its P3P hypotheses are coarser (test_p3p), so a run can end a
 * little further from the optimum. The factor over the oracle allows for RANSAC's slightly
 * different inlier set. */
#define POS_TOL RP_TOL(3e-4, 6e-4)   /* m */
#define ANG_TOL RP_TOL(3e-4, 6e-4)   /* rad */
#define ORACLE_FACTOR 2.0
#define ORACLE_SLACK RP_TOL(5e-5, 1e-4)

static rp_ransac_t rs;          /* ~260 KB: static, as a caller would */
static rp_frameset_t fs;
static rp_obs_t obs[RP_RANSAC_MAX_OBS];
static uint8_t truth_in[RP_RANSAC_MAX_OBS];
static uint8_t mask[RP_RANSAC_MAX_OBS];

typedef struct {
    rp_sim_run_t sr;
} fixture_t;

static int setup(void **state)
{
    fixture_t *fx = calloc(1, sizeof *fx);
    assert_non_null(fx);
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.noise_px = SIGMA_PX;
    cfg.n_frames = 60;
    assert_int_equal(rp_sim_run_init(&fx->sr, &cfg, 21, 0), 0);
    *state = fx;
    return 0;
}

static int teardown(void **state)
{
    fixture_t *fx = *state;
    rp_sim_run_free(&fx->sr);
    free(fx);
    return 0;
}

static rp_ransac_params_t sim_params(void)
{
    rp_ransac_params_t prm = rp_ransac_default_params();
    prm.sigma_px = (rp_real)SIGMA_PX;
    return prm;
}

/* Observations of frame j in every camera; in camera c a fraction out_frac[c] of them get a
 * uniform pixel in the image (truth_in 0). Returns the count. */
static uint32_t frame_obs(const rp_sim_run_t *sr, uint32_t j, const double out_frac[RP_SIM_NCAMS],
                          uint64_t seed)
{
    rp_rng_t rng;
    rp_rng_seed(&rng, seed);
    rp_sim_frame(sr, j, &fs);
    uint32_t n = 0;
    for (int c = 0; c < RP_SIM_NCAMS; ++c) {
        for (uint16_t i = 0; i < fs.n[c]; ++i) {
            rp_obs_t *o = &obs[n];
            const uint32_t id = fs.f[c][i].id;
            for (int k = 0; k < 3; ++k) o->M[k] = (rp_real)sr->points[3 * id + k];
            o->uv[0] = fs.f[c][i].uv[0];
            o->uv[1] = fs.f[c][i].uv[1];
            o->w = RP_C(1.0);
            o->cam = (uint8_t)c;
            truth_in[n] = 1;
            if (rp_rng_uniform(&rng) < out_frac[c]) {
                o->uv[0] = (rp_real)(rp_rng_uniform(&rng) * 640.0 - 0.5);
                o->uv[1] = (rp_real)(rp_rng_uniform(&rng) * 480.0 - 0.5);
                truth_in[n] = 0;
            }
            ++n;
        }
    }
    return n;
}

/* max |position error| (m) and max |angle error| (rad, wrapped) of p against frame j's truth. */
static void pose_err(const rp_sim_run_t *sr, uint32_t j, const rp_real p[6], double *ep,
                     double *ea)
{
    *ep = 0.0;
    *ea = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double d = fabs((double)p[i] - sr->truth[6 * j + i]);
        *ep = d > *ep ? d : *ep;
    }
    for (int i = 3; i < 6; ++i) {
        const double d = fabs((double)rp_angle_wrap((rp_real)((double)p[i] - sr->truth[6 * j + i])));
        *ea = d > *ea ? d : *ea;
    }
}

/* The oracle: Lowe's method from the truth on the true inliers. */
static void oracle_err(const rp_sim_run_t *sr, uint32_t j, uint32_t n, double *ep, double *ea)
{
    static rp_obs_t clean[RP_RANSAC_MAX_OBS];
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (truth_in[i]) clean[m++] = obs[i];
    }
    rp_real p[6];
    for (int i = 0; i < 6; ++i) p[i] = (rp_real)sr->truth[6 * j + i];
    assert_ok(rp_lowe_solve(&sr->rig, clean, m, NULL, p, NULL, NULL));
    pose_err(sr, j, p, ep, ea);
}

typedef struct {
    uint32_t tp, fp, fn;
} conf_t;

static void confusion(uint32_t n, conf_t *c)
{
    for (uint32_t i = 0; i < n; ++i) {
        c->tp += mask[i] && truth_in[i];
        c->fp += mask[i] && !truth_in[i];
        c->fn += !mask[i] && truth_in[i];
    }
}

/* Given frames 10, 25, 40, 55 with the outlier fraction `frac` in every camera, then the pose is
 * within the bounds and near the oracle, and the outliers are flagged. */
static void check_outliers(fixture_t *fx, double frac)
{
    const rp_ransac_params_t prm = sim_params();
    double of[RP_SIM_NCAMS];
    for (int c = 0; c < RP_SIM_NCAMS; ++c) of[c] = frac;
    conf_t cf = {0, 0, 0};
    double wp = 0.0, wa = 0.0, wop = 0.0, woa = 0.0;
    uint32_t iters = 0;
    const uint32_t frames[4] = {10, 25, 40, 55};
    for (int f = 0; f < 4; ++f) {
        const uint32_t j = frames[f];
        const uint32_t n = frame_obs(&fx->sr, j, of, 100 + j);
        assert_ok(rp_ransac_seed(&rs, 7));
        rp_ransac_result_t res;
        assert_ok(rp_ransac_solve(&rs, &fx->sr.rig, obs, n, &prm, mask, &res));
        confusion(n, &cf);
        double ep, ea, oep, oea;
        pose_err(&fx->sr, j, res.p, &ep, &ea);
        oracle_err(&fx->sr, j, n, &oep, &oea);
        print_message("  %2.0f %% outliers, frame %2u: %4u obs, %4u inliers, %3u draws, %4u "
                      "poses, rms %.3f px; error %.2e m %.2e rad (oracle %.2e m %.2e rad)\n",
                      100.0 * frac, j, n, res.n_inliers, res.iters, res.n_hyp,
                      (double)res.rms_px, ep, ea, oep, oea);
        assert_true(ep <= POS_TOL);
        assert_true(ea <= ANG_TOL);
        assert_true(ep <= ORACLE_FACTOR * oep + ORACLE_SLACK);
        assert_true(ea <= ORACLE_FACTOR * oea + ORACLE_SLACK);
        /* the inliers' residual is the pixel noise (a little under it: the gate trims tails) */
        assert_true((double)res.rms_px > 0.8 * SIGMA_PX && (double)res.rms_px < 1.1 * SIGMA_PX);
        assert_true(res.iters < prm.max_iter); /* the adaptive count ended the draws */
        iters += res.iters;
        wp = ep > wp ? ep : wp;
        wa = ea > wa ? ea : wa;
        wop = oep > wop ? oep : wop;
        woa = oea > woa ? oea : woa;
    }
    const double precision = cf.tp + cf.fp ? (double)cf.tp / (double)(cf.tp + cf.fp) : 1.0;
    const double recall = (double)cf.tp / (double)(cf.tp + cf.fn);
    print_message("%2.0f %% outliers: precision %.4f recall %.4f (fp %u, fn %u), worst error "
                  "%.2e m %.2e rad (oracle %.2e m %.2e rad), %u draws in 4 frames\n",
                  100.0 * frac, precision, recall, cf.fp, cf.fn, wp, wa, wop, woa, iters);
    /* the 99 % gate keeps ~99 % of the inliers; a uniform outlier falls inside a 1.5 px gate
     * with probability ~7e-6 */
    assert_true(recall >= 0.97);
    assert_true(precision >= 0.995);
}

static void test_no_outliers(void **state)
{
    check_outliers(*state, 0.0);
}

static void test_30pc_outliers(void **state)
{
    check_outliers(*state, 0.3);
}

static void test_60pc_outliers(void **state)
{
    check_outliers(*state, 0.6);
}

/* Given 60 % outliers, then local optimisation (Lowe on each new best) ends the draws sooner
 * (the inlier ratio is counted from a better pose) at the same accuracy. Measured over frames
 * 10, 25, 40, 55: 1260 draws without, 641 with. */
static void test_local_opt_fewer_draws(void **state)
{
    fixture_t *fx = *state;
    double of[RP_SIM_NCAMS];
    for (int c = 0; c < RP_SIM_NCAMS; ++c) of[c] = 0.6;
    uint32_t draws[2] = {0, 0};
    const uint32_t frames[4] = {10, 25, 40, 55};
    for (int lo = 0; lo < 2; ++lo) {
        rp_ransac_params_t prm = sim_params();
        prm.local_opt = (uint8_t)lo;
        for (int f = 0; f < 4; ++f) {
            const uint32_t n = frame_obs(&fx->sr, frames[f], of, 100 + frames[f]);
            assert_ok(rp_ransac_seed(&rs, 7));
            rp_ransac_result_t res;
            assert_ok(rp_ransac_solve(&rs, &fx->sr.rig, obs, n, &prm, mask, &res));
            double ep, ea;
            pose_err(&fx->sr, frames[f], res.p, &ep, &ea);
            assert_true(ep <= POS_TOL && ea <= ANG_TOL);
            draws[lo] += res.iters;
        }
    }
    print_message("60 %% outliers, 4 frames: %u draws without local optimisation, %u with\n",
                  draws[0], draws[1]);
    assert_true(draws[1] < draws[0] * 3 / 4);
}

/* Given only the back camera (cam3) with inliers (30 % outliers) and every other camera all
 * outliers, then the pose is found from that camera, and the other cameras' observations are
 * all flagged out. One camera with a 44 x 33 degree view fixes the pose far less well than
 * six: bounds 10x looser (measured 4.0e-4 m, 5.3e-4 rad; the oracle 4.8e-4 m, 6.2e-4 rad). */
static void test_one_camera_has_inliers(void **state)
{
    fixture_t *fx = *state;
    const rp_ransac_params_t prm = sim_params();
    double of[RP_SIM_NCAMS];
    for (int c = 0; c < RP_SIM_NCAMS; ++c) of[c] = 1.0;
    of[RP_SIM_CAM3] = 0.3;
    const uint32_t j = 30;
    const uint32_t n = frame_obs(&fx->sr, j, of, 5);
    assert_ok(rp_ransac_seed(&rs, 3));
    rp_ransac_result_t res;
    assert_ok(rp_ransac_solve(&rs, &fx->sr.rig, obs, n, &prm, mask, &res));
    conf_t cf = {0, 0, 0};
    confusion(n, &cf);
    uint32_t other = 0;
    for (uint32_t i = 0; i < n; ++i) other += mask[i] && obs[i].cam != RP_SIM_CAM3;
    double ep, ea, oep, oea;
    pose_err(&fx->sr, j, res.p, &ep, &ea);
    oracle_err(&fx->sr, j, n, &oep, &oea);
    print_message("cam3 only: %u obs, %u inliers (tp %u fp %u fn %u, %u in other cameras), %u "
                  "draws; error %.2e m %.2e rad (oracle %.2e m %.2e rad)\n",
                  n, res.n_inliers, cf.tp, cf.fp, cf.fn, other, res.iters, ep, ea, oep, oea);
    assert_true(ep <= 10.0 * POS_TOL);
    assert_true(ea <= 10.0 * ANG_TOL);
    assert_true(ep <= ORACLE_FACTOR * oep + ORACLE_SLACK);
    assert_true(ea <= ORACLE_FACTOR * oea + ORACLE_SLACK);
    assert_true(other <= 2);
    assert_true(res.iters < prm.max_iter);
    assert_true((double)cf.tp >= 0.97 * (double)(cf.tp + cf.fn));
}

/* Given a turn's onset: the constant-velocity prediction from frames j-2, j-1 off by a 0.5 rad
 * yaw, and 30 % outliers. Lowe's method from that start on every observation is pulled off by
 * the outliers (measured 7e-3 m, 2e-3 rad); RANSAC, which takes no start at all, finds the pose
 * within the bounds, at least 20 times closer. */
static void test_no_prior_needed(void **state)
{
    fixture_t *fx = *state;
    const rp_ransac_params_t prm = sim_params();
    double of[RP_SIM_NCAMS];
    for (int c = 0; c < RP_SIM_NCAMS; ++c) of[c] = 0.3;
    const uint32_t j = 20;
    const uint32_t n = frame_obs(&fx->sr, j, of, 9);
    rp_real start[6];
    for (int i = 0; i < 6; ++i) {
        start[i] = (rp_real)(2.0 * fx->sr.truth[6 * (j - 1) + i] - fx->sr.truth[6 * (j - 2) + i]);
    }
    start[4] += RP_C(0.5); /* beta: a yaw of the forward camera (y down) */
    rp_real pl[6];
    memcpy(pl, start, sizeof pl);
    (void)rp_lowe_solve(&fx->sr.rig, obs, n, NULL, pl, NULL, NULL);
    double lep, lea;
    pose_err(&fx->sr, j, pl, &lep, &lea);
    assert_ok(rp_ransac_seed(&rs, 11));
    rp_ransac_result_t res;
    assert_ok(rp_ransac_solve(&rs, &fx->sr.rig, obs, n, &prm, mask, &res));
    double ep, ea;
    pose_err(&fx->sr, j, res.p, &ep, &ea);
    print_message("wrong CV start (0.5 rad): Lowe on all observations %.2e m %.2e rad; RANSAC "
                  "%.2e m %.2e rad\n", lep, lea, ep, ea);
    assert_true(ep <= POS_TOL);
    assert_true(ea <= ANG_TOL);
    assert_true(lep > 20.0 * ep && lea > 20.0 * ea);
    assert_true(lep > 5.0 * POS_TOL);
}

/* Given cameras with strong barrel distortion (k1 = -0.3, k2 = 0.1, p1 = 1e-3, p2 = -1e-3,
 * k3 = 0: up to ~28 px at the corners) and 30 % outliers, then the pixels are undistorted
 * before P3P and the pose is as good as with pinhole cameras. The inliers keep the simulator's
 * noise (its pixel minus the pinhole projection), moved to the distorted projection. */
static void test_distorted_cameras(void **state)
{
    fixture_t *fx = *state;
    const rp_ransac_params_t prm = sim_params();
    double of[RP_SIM_NCAMS];
    for (int c = 0; c < RP_SIM_NCAMS; ++c) of[c] = 0.3;
    const uint32_t j = 45;
    const uint32_t n = frame_obs(&fx->sr, j, of, 13);
    rp_rig_t drig = fx->sr.rig;
    for (int c = 0; c < drig.n_cams; ++c) {
        drig.cam[c].cam.k1 = RP_C(-0.3);
        drig.cam[c].cam.k2 = RP_C(0.1);
        drig.cam[c].cam.p1 = RP_C(1e-3);
        drig.cam[c].cam.p2 = RP_C(-1e-3);
    }
    rp_real pt[6];
    for (int i = 0; i < 6; ++i) pt[i] = (rp_real)fx->sr.truth[6 * j + i];
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, pt));
    double moved = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
        if (!truth_in[i]) continue;
        rp_real u0[2], u1[2];
        assert_ok(rp_rig_project(&fx->sr.rig, obs[i].cam, &pl, obs[i].M, u0, NULL, NULL));
        assert_ok(rp_rig_project(&drig, obs[i].cam, &pl, obs[i].M, u1, NULL, NULL));
        for (int k = 0; k < 2; ++k) {
            moved = fmax(moved, fabs((double)(u1[k] - u0[k])));
            obs[i].uv[k] += u1[k] - u0[k];
        }
    }
    assert_ok(rp_ransac_seed(&rs, 5));
    rp_ransac_result_t res;
    assert_ok(rp_ransac_solve(&rs, &drig, obs, n, &prm, mask, &res));
    conf_t cf = {0, 0, 0};
    confusion(n, &cf);
    double ep, ea;
    pose_err(&fx->sr, j, res.p, &ep, &ea);
    print_message("distorted (pixels moved up to %.1f px): %u of %u usable, %u inliers (tp %u fp "
                  "%u fn %u), error %.2e m %.2e rad\n", moved, res.n_usable, n, res.n_inliers,
                  cf.tp, cf.fp, cf.fn, ep, ea);
    assert_true(moved > 10.0); /* the distortion matters (measured 21.5 px) */
    assert_true(ep <= POS_TOL && ea <= ANG_TOL);
    assert_true((double)cf.tp >= 0.97 * (double)(cf.tp + cf.fn));
    assert_true(cf.fp <= 2);
}

/* Given the same input and seed, then the same output bit for bit; with another seed, the same
 * pose within the noise. */
static void test_deterministic(void **state)
{
    fixture_t *fx = *state;
    const rp_ransac_params_t prm = sim_params();
    double of[RP_SIM_NCAMS];
    for (int c = 0; c < RP_SIM_NCAMS; ++c) of[c] = 0.4;
    const uint32_t j = 33;
    const uint32_t n = frame_obs(&fx->sr, j, of, 77);
    static uint8_t mask2[RP_RANSAC_MAX_OBS];
    rp_ransac_result_t a, b, c;
    assert_ok(rp_ransac_seed(&rs, 42));
    assert_ok(rp_ransac_solve(&rs, &fx->sr.rig, obs, n, &prm, mask, &a));
    assert_ok(rp_ransac_seed(&rs, 42));
    assert_ok(rp_ransac_solve(&rs, &fx->sr.rig, obs, n, &prm, mask2, &b));
    assert_memory_equal(&a, &b, sizeof a);
    assert_memory_equal(mask, mask2, n);
    assert_ok(rp_ransac_seed(&rs, 43));
    assert_ok(rp_ransac_solve(&rs, &fx->sr.rig, obs, n, &prm, mask2, &c));
    double dp = 0.0, da = 0.0;
    for (int i = 0; i < 3; ++i) dp = fmax(dp, fabs((double)(a.p[i] - c.p[i])));
    for (int i = 3; i < 6; ++i) da = fmax(da, fabs((double)rp_angle_wrap(a.p[i] - c.p[i])));
    uint32_t differ = 0;
    for (uint32_t i = 0; i < n; ++i) differ += mask[i] != mask2[i];
    print_message("seed 42 vs 43: %u vs %u draws, pose differs by %.2e m %.2e rad, %u mask "
                  "entries differ\n", a.iters, c.iters, dp, da, differ);
    assert_true(dp <= RP_TOL(1e-4, 5e-4));
    assert_true(da <= RP_TOL(1e-4, 5e-4));
    assert_true(differ <= n / 100);
}

/* Bad input gives a clear status. */
static void test_bad_input(void **state)
{
    fixture_t *fx = *state;
    const rp_ransac_params_t prm = sim_params();
    double of[RP_SIM_NCAMS] = {0};
    const uint32_t n = frame_obs(&fx->sr, 5, of, 1);
    rp_ransac_result_t res;
    const rp_rig_t *rig = &fx->sr.rig;
    assert_ok(rp_ransac_seed(&rs, 1));
    assert_status(rp_ransac_seed(NULL, 1), RP_E_ARG);
    assert_status(rp_ransac_solve(NULL, rig, obs, n, &prm, mask, &res), RP_E_ARG);
    assert_status(rp_ransac_solve(&rs, NULL, obs, n, &prm, mask, &res), RP_E_ARG);
    assert_status(rp_ransac_solve(&rs, rig, NULL, n, &prm, mask, &res), RP_E_ARG);
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &prm, mask, NULL), RP_E_ARG);
    assert_status(rp_ransac_solve(&rs, rig, obs, RP_RANSAC_MAX_OBS + 1, &prm, mask, &res),
                  RP_E_ARG);
    /* a bad rig */
    rp_rig_t bad_rig = *rig;
    bad_rig.n_cams = 0;
    assert_status(rp_ransac_solve(&rs, &bad_rig, obs, n, &prm, mask, &res), RP_E_ARG);
    /* a camera index outside the rig */
    rp_obs_t keep = obs[7];
    obs[7].cam = rig->n_cams;
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &prm, mask, &res), RP_E_ARG);
    obs[7] = keep;
    /* NaN pixel, infinite point, NaN weight, negative weight */
    obs[7].uv[1] = (rp_real)NAN;
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &prm, mask, &res), RP_E_NAN);
    obs[7] = keep;
    obs[7].M[2] = (rp_real)INFINITY;
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &prm, mask, &res), RP_E_NAN);
    obs[7] = keep;
    obs[7].w = (rp_real)NAN;
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &prm, mask, &res), RP_E_NAN);
    obs[7] = keep;
    obs[7].w = RP_C(-1.0);
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &prm, mask, &res), RP_E_ARG);
    obs[7] = keep;
    /* bad parameters */
    rp_ransac_params_t bad = prm;
    bad.sigma_px = RP_C(0.0);
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &bad, mask, &res), RP_E_ARG);
    bad = prm;
    bad.confidence = RP_C(1.0);
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &bad, mask, &res), RP_E_ARG);
    bad = prm;
    bad.min_inliers = 3;
    assert_status(rp_ransac_solve(&rs, rig, obs, n, &bad, mask, &res), RP_E_ARG);
    /* fewer than 4 observations; all zero weight: nothing usable */
    assert_status(rp_ransac_solve(&rs, rig, obs, 3, &prm, mask, &res), RP_E_TOO_FEW);
    assert_status(rp_ransac_solve(&rs, rig, obs, 0, &prm, mask, &res), RP_E_TOO_FEW);
    static rp_obs_t zw[64];
    memcpy(zw, obs, sizeof zw);
    for (int i = 0; i < 64; ++i) zw[i].w = RP_C(0.0);
    assert_status(rp_ransac_solve(&rs, rig, zw, 64, &prm, mask, &res), RP_E_TOO_FEW);
    assert_int_equal(res.n_usable, 0);
    /* zero-weight observations are left out and flagged 0; the rest still gives the pose */
    for (int i = 0; i < 64; ++i) zw[i].w = (i % 2) ? RP_C(1.0) : RP_C(0.0);
    assert_ok(rp_ransac_solve(&rs, rig, zw, 64, &prm, mask, &res));
    assert_int_equal(res.n_usable, 32);
    for (int i = 0; i < 64; i += 2) assert_int_equal(mask[i], 0);
    /* the 60 points of one camera (same camera: 3-point samples exist) but nothing consistent:
     * every pixel uniform -> no consensus of min_inliers */
    for (int i = 0; i < 64; ++i) {
        zw[i].w = RP_C(1.0);
        zw[i].cam = 0;
        zw[i].uv[0] = (rp_real)rp_test_urand(0.0, 640.0);
        zw[i].uv[1] = (rp_real)rp_test_urand(0.0, 480.0);
    }
    bad = prm;
    bad.min_inliers = 20;
    assert_status(rp_ransac_solve(&rs, rig, zw, 64, &bad, mask, &res), RP_E_TOO_FEW);
    assert_true(res.n_inliers < 20);
    /* inlier may be NULL */
    assert_ok(rp_ransac_solve(&rs, rig, obs, n, &prm, NULL, &res));
    assert_true(res.n_inliers > n / 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_no_outliers, setup, teardown),
        cmocka_unit_test_setup_teardown(test_30pc_outliers, setup, teardown),
        cmocka_unit_test_setup_teardown(test_60pc_outliers, setup, teardown),
        cmocka_unit_test_setup_teardown(test_local_opt_fewer_draws, setup, teardown),
        cmocka_unit_test_setup_teardown(test_one_camera_has_inliers, setup, teardown),
        cmocka_unit_test_setup_teardown(test_no_prior_needed, setup, teardown),
        cmocka_unit_test_setup_teardown(test_distorted_cameras, setup, teardown),
        cmocka_unit_test_setup_teardown(test_deterministic, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bad_input, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
