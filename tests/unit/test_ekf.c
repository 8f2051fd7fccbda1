/*
 * test_ekf.c - the pose EKF: prediction, the iterated update, consistency (NEES) on the paper's
 * simulation with known structure, gating, and bad input that must leave the filter usable.
 */
#include <stdlib.h>
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_ekf.h"
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
    };
    return cmocka_run_group_tests_name("ekf", tests, NULL, NULL);
}
