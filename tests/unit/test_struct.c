/*
 * test_struct.c - the per-feature structure EKF: covariance from the views, convergence from a
 * poor start on noise-free and noisy data, gating, and bad input.
 */
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_struct.h"
#include "rp_sim.h"

static rp_rig_t rig;

static int setup(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    rp_sim_make_rig(&cfg, &rig);
    return 0;
}

/* A pose on a small circle, frame j (the rig translates and turns: the views differ). */
static void pose_at(int j, rp_pose_lin_t *pl)
{
    rp_real p[6] = {RP_C(0.02) * (rp_real)j, RP_C(0.005) * (rp_real)j, RP_C(0.01) * (rp_real)j,
                    RP_C(0.003) * (rp_real)j, RP_C(0.01) * (rp_real)j, RP_C(-0.002) * (rp_real)j};
    assert_ok(rp_pose_lin_set(pl, p));
}

static double gauss(rp_rng_t *r) { return rp_rng_gauss(r); }

static void run_convergence(double noise, double want_err)
{
    const rp_real M_true[3] = {RP_C(0.1), RP_C(-0.05), RP_C(0.8)};
    rp_pose_lin_t pl;
    pose_at(0, &pl);
    /* start from the wrong depth (as an "orthographic" initialisation would), wide covariance */
    rp_point3_t pt;
    const uint8_t cams[2] = {RP_SIM_CAM1, RP_SIM_CAM1B};
    assert_ok(rp_struct_init(&pt, &rig, cams, 2, &pl, M_true, RP_C(0.5)));
    pt.M[0] = RP_C(0.125);
    pt.M[1] = RP_C(-0.0625);
    pt.M[2] = RP_C(1.0);
    memset(pt.C, 0, sizeof(pt.C));
    pt.C[0] = pt.C[3] = RP_C(0.01);
    pt.C[5] = RP_C(0.04);
    rp_rng_t rng;
    rp_rng_seed(&rng, 3);
    for (int j = 0; j < 30; ++j) {
        pose_at(j, &pl);
        rp_real uv[2];
        assert_ok(rp_rig_project(&rig, RP_SIM_CAM1, &pl, M_true, uv, NULL, NULL));
        uv[0] += (rp_real)(noise * gauss(&rng));
        uv[1] += (rp_real)(noise * gauss(&rng));
        assert_ok(rp_struct_update(&pt, &rig, RP_SIM_CAM1, &pl, uv,
                                   RP_C(0.5), RP_C(0.0)));
    }
    double err = 0;
    for (int a = 0; a < 3; ++a) err += pow((double)(pt.M[a] - M_true[a]), 2);
    err = sqrt(err);
    print_message("structure EKF, %.1f px noise, 30 single-camera views: error %.2e m\n", noise, err);
    assert_true(err < want_err);
    assert_true(pt.C[0] > 0 && pt.C[3] > 0 && pt.C[5] > 0);
}

static void test_converges_from_wrong_depth_noise_free(void **state)
{
    (void)state;
    run_convergence(0.0, RP_TOL(1e-4, 1e-3));
}

static void test_converges_from_wrong_depth_with_noise(void **state)
{
    (void)state;
    run_convergence(0.5, 5e-3);
}

static void test_init_covariance_from_stereo_views(void **state)
{
    (void)state;
    rp_pose_lin_t pl;
    pose_at(0, &pl);
    const rp_real M[3] = {0, 0, RP_C(0.8)};
    rp_point3_t pt;
    const uint8_t cams[2] = {RP_SIM_CAM1, RP_SIM_CAM1B};
    assert_ok(rp_struct_init(&pt, &rig, cams, 2, &pl, M, RP_C(0.5)));
    /* depth sigma of stereo: z^2 / (f b) * sigma_d; lateral: z / f * sigma (order of) */
    double sz = sqrt((double)pt.C[5]), sx = sqrt((double)pt.C[0]);
    assert_true(sz > 0.003 && sz < 0.01);
    assert_true(sx > 2e-4 && sx < 1e-3);
    /* one view does not fix a point */
    assert_status(rp_struct_init(&pt, &rig, cams, 1, &pl, M, RP_C(0.5)), RP_E_SINGULAR);
}

static void test_outlier_is_gated_and_point_unchanged(void **state)
{
    (void)state;
    rp_pose_lin_t pl;
    pose_at(0, &pl);
    const rp_real M[3] = {0, 0, RP_C(0.8)};
    rp_point3_t pt, before;
    const uint8_t cams[2] = {RP_SIM_CAM1, RP_SIM_CAM1B};
    assert_ok(rp_struct_init(&pt, &rig, cams, 2, &pl, M, RP_C(0.5)));
    before = pt;
    rp_real uv[2];
    assert_ok(rp_rig_project(&rig, RP_SIM_CAM1, &pl, M, uv, NULL, NULL));
    uv[0] += RP_C(40.0);
    assert_status(rp_struct_update(&pt, &rig, RP_SIM_CAM1, &pl, uv, RP_C(0.5), RP_C(13.8)), RP_E_RANGE);
    assert_memory_equal(&pt, &before, sizeof(pt));
}

static void test_bad_input(void **state)
{
    (void)state;
    rp_pose_lin_t pl;
    pose_at(0, &pl);
    const rp_real M[3] = {0, 0, RP_C(0.8)};
    rp_point3_t pt;
    const uint8_t cams[2] = {RP_SIM_CAM1, RP_SIM_CAM1B};
    assert_ok(rp_struct_init(&pt, &rig, cams, 2, &pl, M, RP_C(0.5)));
    rp_real uv[2] = {(rp_real)NAN, 1};
    assert_status(rp_struct_update(&pt, &rig, RP_SIM_CAM1, &pl, uv, RP_C(0.5), 0), RP_E_NAN);
    uv[0] = 1;
    assert_status(rp_struct_update(&pt, &rig, RP_SIM_CAM1, &pl, uv, RP_C(0.0), 0), RP_E_ARG);
    /* the point is behind cam3 */
    assert_status(rp_struct_update(&pt, &rig, RP_SIM_CAM3, &pl, uv, RP_C(0.5), 0), RP_E_BEHIND);
    const rp_real Mb[3] = {0, 0, RP_C(-0.8)};
    assert_status(rp_struct_init(&pt, &rig, cams, 2, &pl, Mb, RP_C(0.5)), RP_E_BEHIND);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_converges_from_wrong_depth_noise_free),
        cmocka_unit_test(test_converges_from_wrong_depth_with_noise),
        cmocka_unit_test(test_init_covariance_from_stereo_views),
        cmocka_unit_test(test_outlier_is_gated_and_point_unchanged),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests_name("struct", tests, setup, NULL);
}
