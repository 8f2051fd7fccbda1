/* test_camera.c - pinhole + OpenCV radial-tangential distortion (rp_camera.h). */
#include "rp_test.h"

#include "rigpose/rp_camera.h"

/* EuRoC MAV cam0 (752x480); k3 = 0.05 added so that the k3 term is exercised. */
static rp_camera_t euroc(void)
{
    rp_camera_t c = rp_cam_pinhole(752, 480, RP_C(458.654), RP_C(457.296), RP_C(367.215),
                                   RP_C(248.375));
    c.k1 = RP_C(-0.28340811);
    c.k2 = RP_C(0.07395907);
    c.p1 = RP_C(0.00019359);
    c.p2 = RP_C(1.76187114e-05);
    c.k3 = RP_C(0.05);
    return c;
}

static void test_pinhole_sets_intrinsics_and_no_distortion(void **state)
{
    (void)state;
    const rp_camera_t c = rp_cam_pinhole(640, 480, RP_C(800), RP_C(810), RP_C(319.5), RP_C(239.5));
    assert_int_equal(c.width, 640);
    assert_int_equal(c.height, 480);
    assert_true(c.fx == RP_C(800) && c.fy == RP_C(810));
    assert_true(c.cx == RP_C(319.5) && c.cy == RP_C(239.5));
    assert_true(c.k1 == 0 && c.k2 == 0 && c.p1 == 0 && c.p2 == 0 && c.k3 == 0);
    assert_ok(rp_cam_check(&c));
}

static void test_check_rejects_zero_focal_zero_size_and_nan(void **state)
{
    (void)state;
    rp_camera_t c = euroc();
    assert_ok(rp_cam_check(&c));
    c.fx = 0;
    assert_status(rp_cam_check(&c), RP_E_ARG);
    c = euroc();
    c.fy = RP_C(-1);
    assert_status(rp_cam_check(&c), RP_E_ARG);
    c = euroc();
    c.width = 0;
    assert_status(rp_cam_check(&c), RP_E_ARG);
    c = euroc();
    c.height = 0;
    assert_status(rp_cam_check(&c), RP_E_ARG);
    c = euroc();
    c.k2 = (rp_real)NAN;
    assert_status(rp_cam_check(&c), RP_E_NAN);
    c = euroc();
    c.cx = (rp_real)INFINITY;
    assert_status(rp_cam_check(&c), RP_E_NAN);
    assert_status(rp_cam_check(NULL), RP_E_ARG);
}

/* Reference pixels from OpenCV 4.6 cv::projectPoints (rvec = tvec = 0) with euroc(). */
static void test_project_matches_opencv_project_points(void **state)
{
    (void)state;
    const rp_camera_t c = euroc();
    const rp_real P[3][3] = {{RP_C(0.3), RP_C(-0.2), RP_C(1.0)},
                             {RP_C(-0.9), RP_C(0.6), RP_C(1.5)},
                             {RP_C(0.05), RP_C(0.4), RP_C(0.8)}};
    const double want[3][2] = {{499.9206834819, 160.1786978970},
                               {125.1075580420, 409.3508950367},
                               {393.9859100495, 461.9142779461}};
    for (int i = 0; i < 3; ++i) {
        rp_real uv[2];
        assert_ok(rp_cam_project(&c, P[i], uv, NULL));
        assert_near(uv[0], want[i][0], RP_TOL(1e-8, 2e-3));
        assert_near(uv[1], want[i][1], RP_TOL(1e-8, 2e-3));
    }
}

static void test_project_pinhole_is_f_xz_plus_c(void **state)
{
    (void)state;
    const rp_camera_t c = rp_cam_pinhole(640, 480, RP_C(800), RP_C(800), RP_C(320), RP_C(240));
    const rp_real P[3] = {RP_C(0.1), RP_C(-0.05), RP_C(2.0)};
    rp_real uv[2];
    assert_ok(rp_cam_project(&c, P, uv, NULL));
    assert_near(uv[0], 360.0, RP_TOL(1e-12, 1e-4));
    assert_near(uv[1], 220.0, RP_TOL(1e-12, 1e-4));
}

static void test_distort_jacobian_matches_central_differences(void **state)
{
    (void)state;
    const rp_camera_t c = euroc();
    const double h = RP_TOL(1e-6, 1e-3);
    for (int i = -4; i <= 4; ++i) {
        for (int j = -4; j <= 4; ++j) {
            const rp_real xn[2] = {(rp_real)(0.2 * i), (rp_real)(0.15 * j)};
            rp_real xd[2], J[4];
            assert_ok(rp_cam_distort(&c, xn, xd, J));
            for (int k = 0; k < 2; ++k) {
                rp_real xp[2] = {xn[0], xn[1]}, xm[2] = {xn[0], xn[1]}, dp[2], dm[2];
                xp[k] = (rp_real)(xn[k] + h);
                xm[k] = (rp_real)(xn[k] - h);
                assert_ok(rp_cam_distort(&c, xp, dp, NULL));
                assert_ok(rp_cam_distort(&c, xm, dm, NULL));
                const double step = (double)xp[k] - (double)xm[k];
                for (int r = 0; r < 2; ++r) {
                    assert_near(J[2 * r + k], ((double)dp[r] - (double)dm[r]) / step,
                                RP_TOL(1e-8, 1e-3));
                }
            }
        }
    }
}

static void test_undistort_inverts_distort(void **state)
{
    (void)state;
    const rp_camera_t c = euroc();
    for (int i = -10; i <= 10; ++i) {
        for (int j = -10; j <= 10; ++j) {
            const rp_real xn[2] = {(rp_real)(0.08 * i), (rp_real)(0.06 * j)};
            rp_real xd[2], back[2];
            assert_ok(rp_cam_distort(&c, xn, xd, NULL));
            assert_ok(rp_cam_undistort(&c, xd, back));
            assert_near(back[0], xn[0], RP_TOL(1e-12, 2e-6));
            assert_near(back[1], xn[1], RP_TOL(1e-12, 2e-6));
        }
    }
}

static void test_unproject_then_project_returns_the_pixel_over_the_image(void **state)
{
    (void)state;
    const rp_camera_t c = euroc();
    for (int v = 0; v < 480; v += 16) {
        for (int u = 0; u < 752; u += 16) {
            const rp_real uv[2] = {(rp_real)u, (rp_real)v};
            rp_real xn[2], uv2[2];
            assert_ok(rp_cam_unproject(&c, uv, xn));
            const rp_real P[3] = {RP_C(2.0) * xn[0], RP_C(2.0) * xn[1], RP_C(2.0)};
            assert_ok(rp_cam_project(&c, P, uv2, NULL));
            assert_near(uv2[0], uv[0], RP_TOL(1e-9, 2e-3));
            assert_near(uv2[1], uv[1], RP_TOL(1e-9, 2e-3));
        }
    }
}

static void test_undistort_reports_no_convergence_outside_the_model_range(void **state)
{
    (void)state;
    /* x (1 - x^2) never exceeds 2 / (3 sqrt 3) = 0.385 on its monotonic branch: xd = 0.6 has
     * only the root x = -1.2 beyond the fold, which is not a ray of the camera. */
    rp_camera_t c = rp_cam_pinhole(640, 480, RP_C(800), RP_C(800), RP_C(320), RP_C(240));
    c.k1 = RP_C(-1.0);
    const rp_real xd[2] = {RP_C(0.6), RP_C(0.0)};
    rp_real xn[2];
    assert_status(rp_cam_undistort(&c, xd, xn), RP_E_NO_CONVERGE);
}

static void test_undistort_and_unproject_reject_nan(void **state)
{
    (void)state;
    const rp_camera_t c = euroc();
    const rp_real bad[2] = {(rp_real)NAN, RP_C(0.0)};
    rp_real xn[2];
    assert_status(rp_cam_undistort(&c, bad, xn), RP_E_NAN);
    assert_status(rp_cam_unproject(&c, bad, xn), RP_E_NAN);
    rp_real xd[2];
    assert_status(rp_cam_distort(&c, bad, xd, NULL), RP_E_NAN);
}

static void test_project_jacobian_matches_central_differences(void **state)
{
    (void)state;
    const rp_camera_t c = euroc();
    const double h = RP_TOL(1e-6, 2e-3);
    for (int i = -3; i <= 3; ++i) {
        for (int j = -3; j <= 3; ++j) {
            for (int l = 0; l < 3; ++l) {
                const double Z = 0.5 + 1.2 * l;
                const rp_real P[3] = {(rp_real)(0.25 * i * Z), (rp_real)(0.2 * j * Z),
                                      (rp_real)Z};
                rp_real uv[2], J[6];
                assert_ok(rp_cam_project(&c, P, uv, J));
                double scale = 0;
                for (int e = 0; e < 6; ++e) {
                    scale = fmax(scale, fabs((double)J[e]));
                }
                for (int k = 0; k < 3; ++k) {
                    rp_real pp[3] = {P[0], P[1], P[2]}, pm[3] = {P[0], P[1], P[2]};
                    pp[k] = (rp_real)(P[k] + h);
                    pm[k] = (rp_real)(P[k] - h);
                    rp_real up[2], um[2];
                    assert_ok(rp_cam_project(&c, pp, up, NULL));
                    assert_ok(rp_cam_project(&c, pm, um, NULL));
                    const double step = (double)pp[k] - (double)pm[k];
                    for (int r = 0; r < 2; ++r) {
                        assert_near(J[3 * r + k], ((double)up[r] - (double)um[r]) / step,
                                    RP_TOL(1e-7, 2e-3) * scale);
                    }
                }
            }
        }
    }
}

static void test_project_rejects_points_behind_and_nan(void **state)
{
    (void)state;
    const rp_camera_t c = euroc();
    rp_real uv[2], J[6];
    const rp_real behind[3] = {RP_C(0.1), RP_C(0.1), RP_C(-1.0)};
    assert_status(rp_cam_project(&c, behind, uv, J), RP_E_BEHIND);
    const rp_real on_plane[3] = {RP_C(0.1), RP_C(0.1), RP_C(0.0)};
    assert_status(rp_cam_project(&c, on_plane, uv, NULL), RP_E_BEHIND);
    const rp_real too_close[3] = {RP_C(0.0), RP_C(0.0), RP_C(0.5e-3)};
    assert_status(rp_cam_project(&c, too_close, uv, NULL), RP_E_BEHIND);
    const rp_real nan[3] = {RP_C(0.1), (rp_real)NAN, RP_C(1.0)};
    assert_status(rp_cam_project(&c, nan, uv, J), RP_E_NAN);
}

static void test_in_image_uses_pixel_centre_bounds(void **state)
{
    (void)state;
    const rp_camera_t c = rp_cam_pinhole(640, 480, RP_C(800), RP_C(800), RP_C(320), RP_C(240));
    const rp_real in[][2] = {{RP_C(-0.5), RP_C(-0.5)}, {RP_C(639.49), RP_C(479.49)},
                             {RP_C(320), RP_C(240)}};
    const rp_real out[][2] = {{RP_C(-0.51), RP_C(0)}, {RP_C(639.5), RP_C(10)},
                              {RP_C(10), RP_C(479.5)}, {RP_C(10), RP_C(-0.6)},
                              {(rp_real)NAN, RP_C(10)}};
    for (int i = 0; i < 3; ++i) {
        assert_int_equal(rp_cam_in_image(&c, in[i]), 1);
    }
    for (int i = 0; i < 5; ++i) {
        assert_int_equal(rp_cam_in_image(&c, out[i]), 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pinhole_sets_intrinsics_and_no_distortion),
        cmocka_unit_test(test_check_rejects_zero_focal_zero_size_and_nan),
        cmocka_unit_test(test_project_matches_opencv_project_points),
        cmocka_unit_test(test_project_pinhole_is_f_xz_plus_c),
        cmocka_unit_test(test_distort_jacobian_matches_central_differences),
        cmocka_unit_test(test_undistort_inverts_distort),
        cmocka_unit_test(test_unproject_then_project_returns_the_pixel_over_the_image),
        cmocka_unit_test(test_undistort_reports_no_convergence_outside_the_model_range),
        cmocka_unit_test(test_undistort_and_unproject_reject_nan),
        cmocka_unit_test(test_project_jacobian_matches_central_differences),
        cmocka_unit_test(test_project_rejects_points_behind_and_nan),
        cmocka_unit_test(test_in_image_uses_pixel_centre_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
