/*
 * test_vo.c - what every layout does around its filter (rp_vo.h): frame-set checks, the frame
 * interval, the three start priors, filling the estimate (with gc's map-unit scale) and the
 * status mapping.
 */
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_vo.h"
#include "rigpose/rp_rot.h"
#include "priv/rp_math.h"

static rp_frameset_t fs;

static void test_frameset_check(void **state)
{
    (void)state;
    memset(&fs, 0, sizeof(fs));
    fs.n[0] = RP_MAX_FEATS_PER_CAM;
    fs.n[1] = 3;
    assert_ok(rp_vo_check_frameset(&fs, 2));
    assert_status(rp_vo_check_frameset(&fs, 1), RP_E_ARG); /* features in camera 1, not in rig */
    fs.n[0] = RP_MAX_FEATS_PER_CAM + 1;
    assert_status(rp_vo_check_frameset(&fs, 2), RP_E_ARG);
    assert_status(rp_vo_check_frameset(NULL, 2), RP_E_ARG);
}

static void test_frame_interval(void **state)
{
    (void)state;
    memset(&fs, 0, sizeof(fs));
    rp_real dt = 0;
    fs.utime = 1050000;
    assert_ok(rp_vo_frame_dt(&fs, 1000000, RP_C(0.1), &dt));
    assert_near(dt, 0.05, RP_TOL_TIGHT);
    assert_ok(rp_vo_frame_dt(&fs, 1050000, RP_C(0.1), &dt)); /* repeated timestamp */
    assert_true(dt == RP_C(0.1));
    assert_ok(rp_vo_frame_dt(&fs, 2000000, RP_C(0.1), &dt)); /* going back */
    assert_true(dt == RP_C(0.1));
    assert_status(rp_vo_frame_dt(&fs, 0, RP_C(0.1), NULL), RP_E_ARG);
}

static void test_start_priors(void **state)
{
    (void)state;
    const rp_ekf_params_t prm = rp_ekf_default_params();
    rp_ekf_t ekf;
    assert_ok(rp_vo_ekf_idle(&ekf, &prm));
    assert_true(ekf.P[0] == RP_C(1.0) && ekf.P[RP_EKF_N * RP_EKF_N - 1] == RP_C(1.0));
    assert_ok(rp_vo_ekf_at_origin(&ekf, &prm));
    for (int i = 0; i < 6; ++i) {
        assert_true(ekf.x[i] == RP_C(0.0) && ekf.x[6 + i] == RP_C(0.0));
        assert_true(ekf.P[i * RP_EKF_N + i] == RP_VO_ORIGIN_VAR);
        const rp_real s = i < 3 ? RP_VO_START_SIGMA_V : RP_VO_START_SIGMA_W;
        assert_true(ekf.P[(6 + i) * RP_EKF_N + 6 + i] == s * s);
    }
    /* from a pose: velocity from the displacement, Lowe's full covariance times sigma^2 */
    const rp_real p[6] = {RP_C(0.01), RP_C(-0.02), RP_C(0.03), RP_C(0.001), RP_C(0.002),
                          RP_C(-0.003)};
    const rp_real prev[6] = {0};
    rp_real cov[36] = {0};
    for (int i = 0; i < 6; ++i) {
        cov[i * 6 + i] = RP_C(1e-4) * (rp_real)(i + 1);
    }
    cov[1] = cov[6] = RP_C(2e-5);
    const rp_real dt = RP_C(0.04), s2 = prm.sigma_px * prm.sigma_px;
    assert_ok(rp_vo_ekf_from_pose(&ekf, &prm, p, cov, prev, dt));
    /* rates in the chart (rp_ekf.h): translation / dt, Log(R(p) R(prev)^T) / dt */
    rp_real R[9], w[3];
    rp_rot_from_angles(&p[3], R);
    rp_rot_log(R, w);
    for (int i = 0; i < 6; ++i) {
        assert_near(ekf.x[i], p[i], RP_TOL_TIGHT);
        assert_near(ekf.x[6 + i], (i < 3 ? p[i] : w[i - 3]) / dt, RP_TOL_TIGHT);
        const rp_real s = i < 3 ? RP_VO_START_SIGMA_V : RP_VO_START_SIGMA_W;
        assert_near(ekf.P[(6 + i) * RP_EKF_N + 6 + i], cov[i * 6 + i] * s2 / (dt * dt) + s * s,
                    RP_TOL_TIGHT);
    }
    assert_near(ekf.P[1], cov[1] * s2, RP_TOL_TIGHT); /* off-diagonal kept */
    assert_status(rp_vo_ekf_from_pose(&ekf, &prm, p, cov, prev, RP_C(0.0)), RP_E_ARG);
    rp_ekf_params_t bad = prm;
    bad.sigma_px = RP_C(0.0);
    assert_status(rp_vo_ekf_at_origin(&ekf, &bad), RP_E_ARG);
}

static void test_fill_estimate_scales_translations(void **state)
{
    (void)state;
    const rp_ekf_params_t prm = rp_ekf_default_params();
    rp_ekf_t ekf;
    assert_ok(rp_vo_ekf_idle(&ekf, &prm));
    for (int i = 0; i < RP_EKF_N; ++i) {
        ekf.x[i] = RP_C(1.0) + (rp_real)i;
    }
    ekf.P[0 * RP_EKF_N + 3] = RP_C(0.5); /* translation x angle */
    rp_estimate_t est;
    memset(&est, 0, sizeof(est));
    est.n_gated = 7; /* left alone */
    assert_ok(rp_vo_fill_estimate(&ekf, RP_C(0.5), 123, 4, RP_EST_TRACKING, 9, &est));
    assert_true(est.utime == 123 && est.frame == 4 && est.flags == RP_EST_TRACKING);
    assert_int_equal(est.n_landmarks, 9);
    assert_int_equal(est.n_gated, 7);
    assert_true(est.p[0] == RP_C(0.5)); /* angles not scaled, but wrapped: */
    /* (4, 5, 6) rad is outside alpha, gamma in [-pi, pi], beta in [-pi/2, pi/2]: the same
     * rotation's canonical triple is published */
    rp_real Ra[9], Rb[9];
    rp_rot_from_angles(ekf.x + 3, Ra);
    rp_rot_from_angles(est.p + 3, Rb);
    for (int i = 0; i < 9; ++i) {
        assert_true(rp_fabs(Ra[i] - Rb[i]) < RP_C(1e-5));
    }
    assert_true(rp_fabs(est.p[3]) <= RP_PI && rp_fabs(est.p[4]) <= RP_PI / RP_C(2.0) &&
                rp_fabs(est.p[5]) <= RP_PI);
    ekf.x[3] = RP_C(0.25);
    ekf.x[4] = RP_C(-1.5);
    ekf.x[5] = RP_C(3.0);
    assert_ok(rp_vo_fill_estimate(&ekf, RP_C(0.5), 123, 4, RP_EST_TRACKING, 9, &est));
    assert_memory_equal(est.p + 3, ekf.x + 3, 3 * sizeof(rp_real)); /* in range: untouched */
    assert_true(est.v[0] == RP_C(3.5) && est.v[5] == RP_C(12.0));
    assert_true(est.cov[0] == RP_C(0.25));                       /* t t: scale^2 */
    assert_true(est.cov[3] == RP_C(0.25));                       /* t angle: scale */
    assert_true(est.cov[5 * 6 + 5] == RP_C(1.0));
    assert_status(rp_vo_fill_estimate(NULL, RP_C(1.0), 0, 0, 0, 0, &est), RP_E_ARG);
}

static void test_step_status(void **state)
{
    (void)state;
    assert_ok(rp_vo_step_status(RP_OK));
    assert_status(rp_vo_step_status(RP_E_DIVERGED), RP_E_DIVERGED);
    assert_status(rp_vo_step_status(RP_E_TOO_FEW), RP_E_TOO_FEW);
    assert_status(rp_vo_step_status(RP_E_ARG), RP_E_TOO_FEW); /* ARG: a malformed frame set */
    /* every other failure keeps its code: the caller can tell why the update failed */
    assert_status(rp_vo_step_status(RP_E_NAN), RP_E_NAN);
    assert_status(rp_vo_step_status(RP_E_NO_CONVERGE), RP_E_NO_CONVERGE);
    assert_status(rp_vo_step_status(RP_E_SINGULAR), RP_E_SINGULAR);
    assert_status(rp_vo_step_status(RP_E_DEGENERATE), RP_E_SINGULAR); /* pipe's: no image */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frameset_check),
        cmocka_unit_test(test_frame_interval),
        cmocka_unit_test(test_start_priors),
        cmocka_unit_test(test_fill_estimate_scales_translations),
        cmocka_unit_test(test_step_status),
    };
    return cmocka_run_group_tests_name("vo", tests, NULL, NULL);
}
