/*
 * test_ekf.c - the pose EKF: prediction, the iterated update, consistency (NEES) on the paper's
 * simulation with known structure, gating, and bad input that must leave the filter usable.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_ekf.h"
#include "rigpose/rp_ekf1pt.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_rig.h"
#include "rp_sim.h"

#define N RP_EKF_N

/* Observations of frame j of a simulated run in cameras cams[0..ncams-1], with the true 3-D
 * points (structure known exactly, so that the measurement model is exact). */
static uint32_t sim_obs(const rp_sim_run_t *sr, const rp_frameset_t *fs, const uint8_t *cams,
                        int ncams, rp_obs_t *obs, uint32_t cap)
{
    uint32_t n = 0;
    for (int c = 0; c < ncams; ++c) {
        uint8_t k = cams[c];
        for (uint16_t i = 0; i < fs->n[k] && n < cap; ++i) {
            const rp_feat_t *f = &fs->f[k][i];
            rp_obs_t *o = &obs[n++];
            o->uv[0] = f->uv[0];
            o->uv[1] = f->uv[1];
            for (int a = 0; a < 3; ++a) {
                o->M[a] = (rp_real)sr->points[3 * f->id + (uint32_t)a];
            }
            o->w = RP_C(1.0);
            o->dt = RP_C(0.0);
            o->cam = k;
        }
    }
    return n;
}

static rp_ekf_t *make_ekf(const rp_real x0[N], rp_real p_sigma, rp_real v_sigma)
{
    rp_ekf_t *ekf = calloc(1, sizeof(*ekf));
    rp_ekf_params_t prm = rp_ekf_default_params();
    rp_real P0[N];
    for (int i = 0; i < 6; ++i) {
        P0[i] = p_sigma * p_sigma;
        P0[6 + i] = v_sigma * v_sigma;
    }
    assert_ok(rp_ekf_init(ekf, &prm, x0, P0));
    return ekf;
}

static void test_predict_matches_F_P_Ft_plus_Q(void **state)
{
    (void)state;
    rp_real x0[N] = {0.1, 0.2, 0.3, 0.01, 0.02, 0.03, 1, 2, 3, 0.1, 0.2, 0.3};
    rp_ekf_t *ekf = make_ekf(x0, RP_C(0.1), RP_C(0.5));
    /* give P some correlation */
    ekf->P[0 * N + 7] = ekf->P[7 * N + 0] = RP_C(0.001);
    rp_real P[N * N];
    memcpy(P, ekf->P, sizeof(P));
    const rp_real dt = RP_C(0.05);
    assert_ok(rp_ekf_predict(ekf, dt));
    /* reference: F P F^T + Q with explicit matrices; in the chart (rp_ekf.h) the rotation
     * block of F is Phi = Exp(dt omega), the rest is constant velocity */
    const rp_real wdt[3] = {dt * x0[9], dt * x0[10], dt * x0[11]};
    rp_real Phi[9];
    rp_rot_exp(wdt, Phi);
    double F[N * N] = {0}, FP[N * N] = {0}, ref[N * N] = {0};
    for (int i = 0; i < N; ++i) {
        F[i * N + i] = 1.0;
    }
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            F[(3 + a) * N + 3 + b] = (double)Phi[3 * a + b];
        }
    }
    for (int i = 0; i < 6; ++i) {
        F[i * N + 6 + i] = dt;
    }
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j)
            for (int k = 0; k < N; ++k) FP[i * N + j] += F[i * N + k] * (double)P[k * N + j];
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j)
            for (int k = 0; k < N; ++k) ref[i * N + j] += FP[i * N + k] * F[j * N + k];
    const double q = 1.0, t = dt;
    for (int i = 0; i < 6; ++i) {
        ref[i * N + i] += q * t * t * t / 3.0;
        ref[i * N + 6 + i] += q * t * t / 2.0;
        ref[(6 + i) * N + i] += q * t * t / 2.0;
        ref[(6 + i) * N + 6 + i] += q * t;
    }
    for (int i = 0; i < N * N; ++i) {
        assert_near(ekf->P[i], ref[i], RP_TOL(1e-12, 1e-6));
    }
    assert_near(ekf->x[0], 0.1 + 0.05 * 1.0, RP_TOL_TIGHT);
    /* R+ = Exp(dt omega) R */
    rp_real R0[9], R1[9], Rw[9];
    rp_rot_from_angles(&x0[3], R0);
    rp_rot_mul(Phi, R0, Rw);
    rp_rot_from_angles(&ekf->x[3], R1);
    for (int e = 0; e < 9; ++e) {
        assert_near(R1[e], Rw[e], RP_TOL_TIGHT);
    }
    for (int i = 6; i < N; ++i) {
        assert_true(ekf->x[i] == x0[i]);
    }
    assert_status(rp_ekf_predict(ekf, RP_C(0.0)), RP_E_ARG);
    assert_status(rp_ekf_predict(ekf, (rp_real)NAN), RP_E_ARG);
    free(ekf);
}

static void test_init_rejects_bad_params(void **state)
{
    (void)state;
    rp_ekf_t ekf;
    rp_real x0[N] = {0}, P0[N];
    for (int i = 0; i < N; ++i) P0[i] = 1;
    rp_ekf_params_t prm = rp_ekf_default_params();
    prm.sigma_px = 0;
    assert_status(rp_ekf_init(&ekf, &prm, x0, P0), RP_E_ARG);
    prm = rp_ekf_default_params();
    prm.iterations = 0;
    assert_status(rp_ekf_init(&ekf, &prm, x0, P0), RP_E_ARG);
    prm = rp_ekf_default_params();
    P0[3] = -1;
    assert_status(rp_ekf_init(&ekf, &prm, x0, P0), RP_E_ARG);
    P0[3] = (rp_real)NAN;
    assert_status(rp_ekf_init(&ekf, &prm, x0, P0), RP_E_NAN);
}

/* Shared fixture: one simulated run and one of its frames. */
typedef struct {
    rp_sim_run_t sr;
    rp_frameset_t fs;
    rp_obs_t obs[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM];
    uint8_t used[RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM];
} fixture_t;

static fixture_t *fixture(double noise_px, uint32_t frames)
{
    fixture_t *fx = calloc(1, sizeof(*fx));
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.noise_px = noise_px;
    cfg.n_frames = frames;
    assert_int_equal(rp_sim_run_init(&fx->sr, &cfg, 7, 0), 0);
    return fx;
}

static void free_fixture(fixture_t *fx)
{
    rp_sim_run_free(&fx->sr);
    free(fx);
}

static const uint8_t stereo4_cams[4] = {RP_SIM_CAM1, RP_SIM_CAM1B, RP_SIM_CAM3, RP_SIM_CAM3B};

static void test_update_noise_free_recovers_truth_from_offset_prior(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.0, 10);
    rp_sim_frame(&fx->sr, 5, &fx->fs);
    uint32_t n = sim_obs(&fx->sr, &fx->fs, stereo4_cams, 4, fx->obs, RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM);
    assert_true(n > 200);
    rp_real x0[N] = {0};
    for (int i = 0; i < 6; ++i) {
        /* 2 cm and ~1.1 degrees off */
        x0[i] = (rp_real)fx->sr.truth[5 * 6 + i] + (i < 3 ? RP_C(0.02) : RP_C(0.02));
    }
    rp_ekf_t *ekf = make_ekf(x0, RP_C(0.05), RP_C(1.0));
    ekf->prm.iterations = 5;
    ekf->prm.sigma_px = RP_C(0.01);
    rp_ekf_info_t info;
    assert_ok(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, n, fx->used, &info));
    assert_int_equal(info.n_used, n);
    assert_int_equal(info.n_gated, 0);
    for (int i = 0; i < 6; ++i) {
        assert_near(ekf->x[i], fx->sr.truth[5 * 6 + i], RP_TOL(1e-8, 2e-4));
    }
    free(ekf);
    free_fixture(fx);
}

/* Consistency: run the EKF over a noisy simulation with exact structure; the error of every
 * pose component is within 3 sigma in at least 95% of frames, and the mean NEES (6 dof) is
 * near 6. */
static void test_nees_consistent_on_simulation(void **state)
{
    (void)state;
    const uint32_t frames = 60;
    fixture_t *fx = fixture(0.5, frames);
    rp_real x0[N] = {0};
    rp_ekf_t *ekf = make_ekf(x0, RP_C(1e-6), RP_C(1.0));
    ekf->prm.q_trans = RP_C(1.0);
    ekf->prm.q_rot = RP_C(1.0);
    const rp_real dt = RP_C(1.0) / RP_C(30.0);
    uint32_t inside = 0;
    double nees_sum = 0;
    for (uint32_t j = 1; j < frames; ++j) {
        rp_sim_frame(&fx->sr, j, &fx->fs);
        uint32_t n = sim_obs(&fx->sr, &fx->fs, stereo4_cams, 4, fx->obs, RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM);
        assert_ok(rp_ekf_predict(ekf, dt));
        assert_ok(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, n, NULL, NULL));
        int ok = 1;
        double e[6];
        for (int i = 0; i < 6; ++i) {
            e[i] = (double)ekf->x[i] - fx->sr.truth[j * 6 + i];
            double sd = sqrt((double)ekf->P[i * N + i]);
            if (fabs(e[i]) > 3.0 * sd) ok = 0;
        }
        inside += (uint32_t)ok;
        /* NEES = e^T Ppp^-1 e, by Cholesky in double */
        double C[36], L[36] = {0}, y[6];
        for (int a = 0; a < 6; ++a)
            for (int b = 0; b < 6; ++b) C[a * 6 + b] = (double)ekf->P[a * N + b];
        for (int a = 0; a < 6; ++a) {
            for (int b = 0; b <= a; ++b) {
                double s = C[a * 6 + b];
                for (int k = 0; k < b; ++k) s -= L[a * 6 + k] * L[b * 6 + k];
                L[a * 6 + b] = a == b ? sqrt(s) : s / L[b * 6 + b];
            }
        }
        double nees = 0;
        for (int a = 0; a < 6; ++a) {
            double s = e[a];
            for (int k = 0; k < a; ++k) s -= L[a * 6 + k] * y[k];
            y[a] = s / L[a * 6 + a];
            nees += y[a] * y[a];
        }
        nees_sum += nees;
    }
    double frac = (double)inside / (double)(frames - 1);
    double mean_nees = nees_sum / (double)(frames - 1);
    print_message("EKF consistency: %.1f%% of frames within 3 sigma, mean NEES %.2f (6 expected)\n",
                  100.0 * frac, mean_nees);
    assert_true(frac >= 0.95);
    assert_true(mean_nees < 12.0 && mean_nees > 2.0);
    free(ekf);
    free_fixture(fx);
}

static void test_outlier_feature_is_gated(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 10);
    rp_sim_frame(&fx->sr, 3, &fx->fs);
    uint32_t n = sim_obs(&fx->sr, &fx->fs, stereo4_cams, 4, fx->obs, RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM);
    fx->obs[10].uv[0] += RP_C(30.0); /* a mis-tracked feature */
    rp_real x0[N] = {0};
    for (int i = 0; i < 6; ++i) x0[i] = (rp_real)fx->sr.truth[3 * 6 + i] + RP_C(0.003);
    rp_ekf_t *ekf = make_ekf(x0, RP_C(0.01), RP_C(1.0));
    rp_ekf_info_t info;
    assert_ok(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, n, fx->used, &info));
    assert_int_equal(fx->used[10], 0);
    assert_true(info.n_gated >= 1);
    assert_true(info.n_gated < 10);
    for (int i = 0; i < 3; ++i) {
        assert_near(ekf->x[i], fx->sr.truth[3 * 6 + i], 1e-3);
    }
    free(ekf);
    free_fixture(fx);
}

static void test_bad_measurements_are_skipped_and_filter_stays_usable(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 10);
    rp_sim_frame(&fx->sr, 2, &fx->fs);
    uint32_t n = sim_obs(&fx->sr, &fx->fs, stereo4_cams, 4, fx->obs, RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM);
    fx->obs[0].uv[1] = (rp_real)NAN;      /* NaN pixel */
    fx->obs[1].M[2] = RP_C(-5.0);         /* a point behind cam1 */
    fx->obs[1].cam = RP_SIM_CAM1;
    fx->obs[2].cam = 200;                 /* no such camera */
    rp_real x0[N] = {0};
    for (int i = 0; i < 6; ++i) x0[i] = (rp_real)fx->sr.truth[2 * 6 + i];
    rp_ekf_t *ekf = make_ekf(x0, RP_C(0.01), RP_C(1.0));
    rp_ekf_info_t info;
    assert_ok(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, n, fx->used, &info));
    assert_int_equal(info.n_bad, 3);
    assert_int_equal(fx->used[0] + fx->used[1] + fx->used[2], 0);
    for (int i = 0; i < 6; ++i) assert_true(isfinite((double)ekf->x[i]));
    free(ekf);
    free_fixture(fx);
}

static void test_too_few_features_leaves_prediction(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 10);
    rp_sim_frame(&fx->sr, 2, &fx->fs);
    uint32_t n = sim_obs(&fx->sr, &fx->fs, stereo4_cams, 4, fx->obs, 4);
    assert_int_equal(n, 4);
    rp_real x0[N] = {0.01, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    rp_ekf_t *ekf = make_ekf(x0, RP_C(0.01), RP_C(1.0));
    rp_real P_before[N * N];
    memcpy(P_before, ekf->P, sizeof(P_before));
    rp_ekf_info_t info;
    assert_status(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, n, NULL, &info), RP_E_TOO_FEW);
    assert_memory_equal(ekf->P, P_before, sizeof(P_before));
    assert_near(ekf->x[0], 0.01, RP_TOL_TIGHT);
    assert_status(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, 0, NULL, &info), RP_E_TOO_FEW);
    free(ekf);
    free_fixture(fx);
}

static void test_broken_covariance_is_reset_and_filter_recovers(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 10);
    rp_sim_frame(&fx->sr, 2, &fx->fs);
    uint32_t n = sim_obs(&fx->sr, &fx->fs, stereo4_cams, 4, fx->obs, RP_MAX_CAMS * RP_MAX_FEATS_PER_CAM);
    rp_real x0[N] = {0};
    for (int i = 0; i < 6; ++i) x0[i] = (rp_real)fx->sr.truth[2 * 6 + i];
    rp_ekf_t *ekf = make_ekf(x0, RP_C(0.01), RP_C(1.0));
    ekf->P[0] = RP_C(-1.0); /* not positive definite */
    rp_ekf_info_t info;
    assert_status(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, n, NULL, &info), RP_E_DIVERGED);
    assert_int_equal(info.cov_reset, 1);
    /* the caller re-initialises the covariance; the filter then works again */
    rp_real P0[N];
    for (int i = 0; i < N; ++i) P0[i] = i < 6 ? RP_C(1e-4) : RP_C(1.0);
    assert_ok(rp_ekf_init(ekf, &ekf->prm, ekf->x, P0));
    assert_ok(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, n, NULL, &info));
    for (int i = 0; i < 3; ++i) assert_near(ekf->x[i], fx->sr.truth[2 * 6 + i], 1e-3);
    free(ekf);
    free_fixture(fx);
}

/* ---- per-camera capture times and clock offsets (rp_ekf.h, issue 15) ------------------------ */

/* The rig under the filter's own model: constant velocity V (m/s) and world-frame rate W
 * (rad/s) from the identity, so d(t) = V t and R(t) = Exp(W t). */
static const rp_real cv_V[3] = {0.10, -0.05, 0.08}, cv_W[3] = {0.3, 0.9, -0.2};

static void cv_pose(double t, rp_real p[6])
{
    const rp_real w[3] = {(rp_real)t * cv_W[0], (rp_real)t * cv_W[1], (rp_real)t * cv_W[2]};
    rp_real R[9];
    rp_rot_exp(w, R);
    for (int i = 0; i < 3; ++i) {
        p[i] = (rp_real)t * cv_V[i];
    }
    assert_ok(rp_rot_to_angles(R, p + 3));
}

/* Observations of the sim's points by every camera k, each captured at true time
 * t + toff_true[k] but stamped stamp_dt[k] after t (obs.dt); Gaussian pixel noise from rng. */
static uint32_t cv_obs(const rp_sim_run_t *sr, double t, const double toff_true[RP_SIM_NCAMS],
                       const double stamp_dt[RP_SIM_NCAMS], double noise_px, rp_rng_t *rng,
                       rp_obs_t *obs, uint32_t cap)
{
    uint32_t n = 0;
    for (uint8_t k = 0; k < RP_SIM_NCAMS; ++k) {
        rp_real p[6];
        cv_pose(t + stamp_dt[k] + toff_true[k], p);
        rp_pose_lin_t pl;
        assert_ok(rp_pose_lin_set(&pl, p));
        uint32_t nk = 0;
        for (uint32_t i = 0; i < sr->cfg.n_points && nk < 60 && n < cap; i += 7) {
            rp_real M[3], uv[2];
            for (int a = 0; a < 3; ++a) {
                M[a] = (rp_real)sr->points[3 * i + (uint32_t)a];
            }
            if (rp_rig_project(&sr->rig, k, &pl, M, uv, NULL, NULL) != RP_OK ||
                !rp_cam_in_image(&sr->rig.cam[k].cam, uv)) {
                continue;
            }
            rp_obs_t *o = &obs[n++];
            o->uv[0] = uv[0] + (rp_real)(noise_px * rp_rng_gauss(rng));
            o->uv[1] = uv[1] + (rp_real)(noise_px * rp_rng_gauss(rng));
            memcpy(o->M, M, sizeof(M));
            o->w = RP_C(1.0);
            o->dt = (rp_real)stamp_dt[k];
            o->cam = k;
            nk++;
        }
    }
    return n;
}

/* Runs the filter over `frames` sets at 30 Hz on cv_* with the given true offsets and stamps;
 * returns the largest pose error (translation m + rotation rad) over the last half. */
static double cv_run(rp_ekf_t *ekf, const rp_sim_run_t *sr, const double toff_true[],
                     const double stamp_dt[], double noise_px, int frames, rp_obs_t *obs,
                     uint32_t cap)
{
    rp_rng_t rng;
    rp_rng_seed(&rng, 11);
    const double dt = 1.0 / 30.0;
    double worst = 0.0;
    for (int j = 1; j <= frames; ++j) {
        assert_ok(rp_ekf_predict(ekf, (rp_real)dt));
        const uint32_t n = cv_obs(sr, j * dt, toff_true, stamp_dt, noise_px, &rng, obs, cap);
        assert_ok(rp_ekf_update(ekf, &sr->rig, obs, n, NULL, NULL));
        rp_real truth[6], d[6];
        cv_pose(j * dt, truth);
        rp_pose_minus(ekf->x, truth, d);
        const double e = sqrt((double)(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])) +
                         sqrt((double)(d[3] * d[3] + d[4] * d[4] + d[5] * d[5]));
        if (j > frames / 2 && e > worst) {
            worst = e;
        }
    }
    return worst;
}

static rp_ekf_t *cv_ekf(void)
{
    /* started 4 mm / 4 mrad off the truth (about one sigma), at the true rates */
    rp_real x0[N];
    const rp_real off[6] = {0.004, -0.003, 0.002, 0.003, -0.002, 0.004};
    cv_pose(0.0, x0);
    assert_ok(rp_pose_plus(x0, off, x0));
    for (int i = 0; i < 3; ++i) {
        x0[6 + i] = cv_V[i];
        x0[9 + i] = cv_W[i];
    }
    return make_ekf(x0, RP_C(0.005), RP_C(0.05));
}

static void test_features_apply_at_their_cameras_times(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.0, 2);
    /* camera k captured 0, 12, -25, 40, 20, -10 ms after the set's time, and stamped so */
    const double stamp[RP_SIM_NCAMS] = {0.0, 0.012, -0.025, 0.040, 0.020, -0.010};
    const double none[RP_SIM_NCAMS] = {0};
    rp_ekf_t *timed = cv_ekf();
    const double e_timed = cv_run(timed, &fx->sr, none, stamp, 0.0, 30, fx->obs, 2000);
    /* the same images with the stamps lost: every camera taken as at the set's time */
    rp_ekf_t *flat = cv_ekf();
    rp_real off[RP_MAX_CAMS] = {0};
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        off[k] = (rp_real)stamp[k]; /* true capture = stamp (dt 0) + the offset: the same */
    }
    assert_ok(rp_ekf_toff_set(flat, 0, off, NULL, RP_C(0.0)));
    const double e_known = cv_run(flat, &fx->sr, stamp, none, 0.0, 30, fx->obs, 2000);
    rp_ekf_t *blind = cv_ekf();
    const double e_blind = cv_run(blind, &fx->sr, stamp, none, 0.0, 30, fx->obs, 2000);
    print_message("noise-free, cameras 0..+40 ms apart: worst pose error with their times %.2e, "
                  "as known offsets %.2e, as simultaneous %.2e\n", e_timed, e_known, e_blind);
    /* the filter's model is exact here: only the first-order chart composition is left */
    assert_true(e_timed < RP_TOL(1e-5, 1e-3));
    assert_true(e_known < RP_TOL(1e-5, 1e-3));
    assert_true(e_blind > 100.0 * e_timed);
    free(timed);
    free(flat);
    free(blind);
    free_fixture(fx);
}

static void test_clock_offsets_are_estimated(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.0, 2);
    const double truth[RP_SIM_NCAMS] = {0.0, 0.012, -0.025, 0.040, 0.005, -0.008};
    const double none[RP_SIM_NCAMS] = {0};
    rp_ekf_t *ekf = cv_ekf();
    const rp_real sig0[RP_MAX_CAMS] = {0, 0.05, 0.05, 0.05, 0.05, 0.05};
    assert_ok(rp_ekf_toff_set(ekf, 0x3e, NULL, sig0, RP_C(1e-8)));
    const double worst = cv_run(ekf, &fx->sr, truth, none, 0.5, 50, fx->obs, 2000);
    for (int k = 1; k < RP_SIM_NCAMS; ++k) {
        const double est = (double)ekf->toff[k], sig = sqrt((double)ekf->Poo[k * RP_MAX_CAMS + k]);
        print_message("camera %d: offset %+.3f ms, estimated %+.3f ms, sigma %.3f ms\n", k,
                      1e3 * truth[k], 1e3 * est, 1e3 * sig);
        assert_true(fabs(est - truth[k]) < 0.5e-3);           /* the 0.5 ms */
        assert_true(fabs(est - truth[k]) < 4.0 * sig + 1e-6); /* and consistent */
    }
    print_message("worst pose error over the last 25 frames: %.2e\n", worst);
    assert_true(worst < 0.005);
    /* an offset state survives a restart at a new pose, without its cross-covariance */
    rp_ekf_t *fresh = cv_ekf();
    assert_ok(rp_ekf_toff_carry(fresh, ekf));
    assert_int_equal(fresh->toff_mask, 0x3e);
    assert_true(fresh->toff[3] == ekf->toff[3] && fresh->Poo[7] == ekf->Poo[7]);
    for (int i = 0; i < N * RP_MAX_CAMS; ++i) {
        assert_true(fresh->Pxo[i] == RP_C(0.0));
    }
    free(fresh);
    free(ekf);
    free_fixture(fx);
}

/* The rate from a filter started at rest (velocity prior 1 m/s, 1 rad/s): cameras 2 or 20 ms
 * off the set's time, their offsets given, must not make it worse than synchronised cameras
 * give it (the rate is a considered parameter of the camera-time pose: rp_ekf.c). Largest
 * velocity error over frames 10..30, 0.5 px noise. */
static double rate_error(const rp_sim_run_t *sr, double off1, rp_obs_t *obs, uint32_t cap)
{
    const double none[RP_SIM_NCAMS] = {0};
    double truth[RP_SIM_NCAMS] = {0};
    truth[1] = off1;
    rp_real x0[N] = {0}, P0[N];
    for (int i = 0; i < 6; ++i) {
        P0[i] = RP_C(1e-6);
        P0[6 + i] = RP_C(1.0);
    }
    rp_ekf_t *ekf = make_ekf(x0, RP_C(0.001), RP_C(1.0));
    assert_ok(rp_ekf_init(ekf, &ekf->prm, x0, P0));
    rp_real off[RP_MAX_CAMS] = {0};
    off[1] = (rp_real)off1;
    assert_ok(rp_ekf_toff_set(ekf, 0, off, NULL, RP_C(0.0)));
    rp_rng_t rng;
    rp_rng_seed(&rng, 5);
    double worst = 0.0;
    for (int j = 1; j <= 30; ++j) {
        assert_ok(rp_ekf_predict(ekf, RP_C(1.0 / 30.0)));
        const uint32_t n = cv_obs(sr, j / 30.0, truth, none, 0.5, &rng, obs, cap);
        assert_ok(rp_ekf_update(ekf, &sr->rig, obs, n, NULL, NULL));
        double e = 0.0;
        for (int i = 0; i < 3; ++i) {
            e += pow((double)ekf->x[6 + i] - (double)cv_V[i], 2) +
                 pow((double)ekf->x[9 + i] - (double)cv_W[i], 2);
        }
        if (j >= 10 && sqrt(e) > worst) {
            worst = sqrt(e);
        }
    }
    free(ekf);
    return worst;
}

static void test_camera_times_leave_the_rate_alone(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.0, 2);
    const double e0 = rate_error(&fx->sr, 0.0, fx->obs, 2000);
    const double e2 = rate_error(&fx->sr, 0.002, fx->obs, 2000);
    const double e20 = rate_error(&fx->sr, 0.020, fx->obs, 2000);
    print_message("rate error from rest, frames 10-30: synchronised %.4f, a camera at +2 ms "
                  "%.4f, at +20 ms %.4f\n", e0, e2, e20);
    assert_true(e2 < 2.0 * e0);
    assert_true(e20 < 2.0 * e0);
    free_fixture(fx);
}

/* Camera 3's clock jumps from +10 to +30 ms at frame 30 (its offset a converged state): the
 * jump is found at once (toff_reset), the offset re-estimated within 0.5 ms by frame 50, and
 * no other frame claims a jump; through the plain update and through 1-point RANSAC. */
static void clock_jump_run(int one_point)
{
    fixture_t *fx = fixture(0.0, 2);
    rp_ekf1pt_t *op = calloc(1, sizeof(*op));
    assert_non_null(op);
    assert_ok(rp_ekf1pt_seed(op, 1));
    double truth[RP_SIM_NCAMS] = {0.0, 0.0, 0.0, 0.010, 0.0, 0.0};
    const double none[RP_SIM_NCAMS] = {0};
    rp_ekf_t *ekf = cv_ekf();
    const rp_real sig0[RP_MAX_CAMS] = {0, 0.02, 0.02, 0.02, 0.02, 0.02};
    rp_real start[RP_MAX_CAMS] = {0};
    start[3] = RP_C(0.010);
    assert_ok(rp_ekf_toff_set(ekf, 0x08, start, sig0, RP_C(1e-8)));
    rp_rng_t rng;
    rp_rng_seed(&rng, 9);
    int found_at = -1, false_alarms = 0;
    for (int j = 1; j <= 50; ++j) {
        if (j == 30) {
            truth[3] = 0.030;
        }
        assert_ok(rp_ekf_predict(ekf, RP_C(1.0 / 30.0)));
        const uint32_t n = cv_obs(&fx->sr, j / 30.0, truth, none, 0.5, &rng, fx->obs, 2000);
        rp_ekf_info_t info;
        rp_ekf1pt_info_t info1;
        if (one_point) {
            assert_ok(rp_ekf1pt_update(op, ekf, &fx->sr.rig, fx->obs, n, NULL, NULL, &info1));
            info = info1.ekf;
        } else {
            assert_ok(rp_ekf_update(ekf, &fx->sr.rig, fx->obs, n, NULL, &info));
        }
        if (info.toff_reset) {
            if (j >= 30 && found_at < 0 && info.toff_reset == 0x08) {
                found_at = j;
            } else {
                false_alarms++;
            }
        }
    }
    const double est = (double)ekf->toff[3];
    print_message("clock jump +10 -> +30 ms at frame 30, %s: found at frame %d, %d false "
                  "alarms, offset at frame 50 %+.3f ms\n", one_point ? "1-point RANSAC" :
                  "plain update", found_at, false_alarms, 1e3 * est);
    assert_int_equal(found_at, 30);
    assert_int_equal(false_alarms, 0);
    assert_true(fabs(est - 0.030) < 0.5e-3);
    free(ekf);
    free(op);
    free_fixture(fx);
}

static void test_clock_jump_is_found_and_reestimated(void **state)
{
    (void)state;
    clock_jump_run(0);
    clock_jump_run(1);
}

static void test_toff_set_rejects_bad_input(void **state)
{
    (void)state;
    rp_real x0[N] = {0};
    rp_ekf_t *ekf = make_ekf(x0, RP_C(0.1), RP_C(0.1));
    const rp_real sig[RP_MAX_CAMS] = {0.01, 0.01, 0.01, 0.01, 0.01, 0.01};
    rp_real off[RP_MAX_CAMS] = {0};
    assert_status(rp_ekf_toff_set(NULL, 0, NULL, NULL, 0), RP_E_ARG);
    assert_status(rp_ekf_toff_set(ekf, 0x01, NULL, sig, 0), RP_E_ARG); /* the reference */
    assert_status(rp_ekf_toff_set(ekf, 0x02, NULL, NULL, 0), RP_E_ARG); /* no sigma */
    assert_status(rp_ekf_toff_set(ekf, (uint8_t)(1u << RP_MAX_CAMS), NULL, sig, 0), RP_E_ARG);
    assert_status(rp_ekf_toff_set(ekf, 0x02, NULL, sig, RP_C(-1.0)), RP_E_ARG);
    off[2] = (rp_real)NAN;
    assert_status(rp_ekf_toff_set(ekf, 0x02, off, sig, 0), RP_E_NAN);
    assert_int_equal(ekf->toff_mask, 0);
    /* a non-finite stamp skips that observation only */
    fixture_t *fx = fixture(0.0, 2);
    rp_ekf_t *e2 = cv_ekf();
    const double none[RP_SIM_NCAMS] = {0};
    rp_rng_t rng;
    rp_rng_seed(&rng, 3);
    assert_ok(rp_ekf_predict(e2, RP_C(1.0 / 30.0)));
    const uint32_t n = cv_obs(&fx->sr, 1.0 / 30.0, none, none, 0.0, &rng, fx->obs, 2000);
    fx->obs[0].dt = (rp_real)NAN;
    rp_ekf_info_t info;
    assert_ok(rp_ekf_update(e2, &fx->sr.rig, fx->obs, n, fx->used, &info));
    assert_int_equal(info.n_bad, 1);
    assert_int_equal(fx->used[0], 0);
    free(e2);
    free(ekf);
    free_fixture(fx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_predict_matches_F_P_Ft_plus_Q),
        cmocka_unit_test(test_init_rejects_bad_params),
        cmocka_unit_test(test_update_noise_free_recovers_truth_from_offset_prior),
        cmocka_unit_test(test_nees_consistent_on_simulation),
        cmocka_unit_test(test_outlier_feature_is_gated),
        cmocka_unit_test(test_bad_measurements_are_skipped_and_filter_stays_usable),
        cmocka_unit_test(test_too_few_features_leaves_prediction),
        cmocka_unit_test(test_broken_covariance_is_reset_and_filter_recovers),
        cmocka_unit_test(test_features_apply_at_their_cameras_times),
        cmocka_unit_test(test_clock_offsets_are_estimated),
        cmocka_unit_test(test_camera_times_leave_the_rate_alone),
        cmocka_unit_test(test_clock_jump_is_found_and_reestimated),
        cmocka_unit_test(test_toff_set_rejects_bad_input),
    };
    return cmocka_run_group_tests_name("ekf", tests, NULL, NULL);
}
