/* test_rig.c - the rig and the measurement model of eqs. (1)-(2) (rp_rig.h). */
#include <string.h>

#include "rp_test.h"

#include "rigpose/rp_rig.h"
#include "rigpose/rp_rot.h"

#define PI 3.14159265358979323846

/* Uniform in [a, b), from one seeded generator per file (deterministic). */
static double urand(double a, double b) { return rp_test_urand(a, b); }

static void ry(double b, rp_real R[9])
{
    const rp_real abg[3] = {0, (rp_real)b, 0};
    rp_rot_from_angles(abg, R);
}

/* The paper's six cameras (docs/design.md): cam1, cam2 (+x side), cam3 (back), cam4 (-x side),
 * cam1's and cam3's stereo partners. 640x480, f = 800 px; cam2 and cam1b carry EuRoC's
 * distortion so that the distortion Jacobian is part of the chain. */
static void make_rig(rp_rig_t *rig)
{
    memset(rig, 0, sizeof *rig);
    rig->n_cams = 6;
    const double D[6][3] = {{0, 0, 0},       {0.0866, 0, -0.05}, {0, 0, -0.1},
                            {-0.0866, 0, -0.05}, {0.1, 0, 0},    {0.1, 0, -0.1}};
    const double yaw[6] = {0, PI / 2, PI, -PI / 2, 0, PI};
    for (int k = 0; k < 6; ++k) {
        rp_rig_cam_t *c = &rig->cam[k];
        ry(yaw[k], c->R);
        for (int i = 0; i < 3; ++i) {
            c->D[i] = (rp_real)D[k][i];
        }
        c->cam = rp_cam_pinhole(640, 480, RP_C(800), RP_C(800), RP_C(319.5), RP_C(239.5));
        if (k == 1 || k == 4) {
            c->cam.k1 = RP_C(-0.28340811);
            c->cam.k2 = RP_C(0.07395907);
            c->cam.p1 = RP_C(0.00019359);
            c->cam.p2 = RP_C(1.76187114e-05);
        }
    }
}

static void rand_pose(rp_real p[6])
{
    for (int i = 0; i < 3; ++i) {
        p[i] = (rp_real)urand(-1, 1);
    }
    p[3] = (rp_real)urand(-PI, PI);
    p[4] = (rp_real)urand(-1.4, 1.4);
    p[5] = (rp_real)urand(-PI, PI);
}

/* A world point seen by camera k at pose pl, between 0.3 m and 3 m in front of it. */
static void rand_point(const rp_rig_t *rig, uint8_t k, const rp_pose_lin_t *pl, rp_real M[3])
{
    const double z = urand(0.3, 3.0);
    const rp_real P[3] = {(rp_real)(urand(-0.35, 0.35) * z), (rp_real)(urand(-0.25, 0.25) * z),
                          (rp_real)z};
    assert_ok(rp_rig_world_point(rig, k, pl, P, M));
}

static void test_rig_check_accepts_the_six_camera_rig(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    assert_ok(rp_rig_check(&rig));
    rig.n_cams = 1;
    assert_ok(rp_rig_check(&rig));
}

static void test_rig_check_rejects_bad_rotations_cameras_and_counts(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    rig.cam[2].R[0] = (rp_real)(rig.cam[2].R[0] * 1.01); /* not orthonormal */
    assert_status(rp_rig_check(&rig), RP_E_ARG);
    make_rig(&rig);
    rig.cam[1].R[4] += RP_C(1e-4);
    assert_status(rp_rig_check(&rig), RP_E_ARG);
    make_rig(&rig);
    for (int i = 0; i < 3; ++i) {
        rig.cam[3].R[i] = -rig.cam[3].R[i]; /* a reflection: det -1 */
    }
    assert_status(rp_rig_check(&rig), RP_E_ARG);
    make_rig(&rig);
    rig.cam[4].cam.fx = 0;
    assert_status(rp_rig_check(&rig), RP_E_ARG);
    make_rig(&rig);
    rig.cam[5].cam.width = 0;
    assert_status(rp_rig_check(&rig), RP_E_ARG);
    make_rig(&rig);
    rig.n_cams = 0;
    assert_status(rp_rig_check(&rig), RP_E_ARG);
    rig.n_cams = RP_MAX_CAMS + 1;
    assert_status(rp_rig_check(&rig), RP_E_ARG);
    make_rig(&rig);
    rig.cam[1].D[2] = (rp_real)NAN;
    assert_status(rp_rig_check(&rig), RP_E_NAN);
    make_rig(&rig);
    rig.cam[0].R[8] = (rp_real)INFINITY;
    assert_status(rp_rig_check(&rig), RP_E_NAN);
    assert_status(rp_rig_check(NULL), RP_E_ARG);
}

static void test_pose_lin_set_holds_the_pose_and_its_rotation(void **state)
{
    (void)state;
    for (int n = 0; n < 20; ++n) {
        rp_real p[6], R[9];
        rand_pose(p);
        rp_pose_lin_t pl;
        assert_ok(rp_pose_lin_set(&pl, p));
        rp_rot_from_angles(p + 3, R);
        for (int i = 0; i < 6; ++i) {
            assert_true(pl.p[i] == p[i]);
        }
        for (int e = 0; e < 9; ++e) {
            assert_true(pl.R[e] == R[e]);
        }
    }
}

/* The pose chart: p [+] d has translation p + d and rotation Exp(w) R(p); p [-] q inverts it;
 * at gimbal lock (beta = +-pi/2) the angles it returns still give that rotation exactly. */
static void test_pose_plus_and_minus_are_the_chart_also_at_gimbal_lock(void **state)
{
    (void)state;
    for (int n = 0; n < 40; ++n) {
        rp_real p[6], d[6], q[6], back[6], R[9], E[9], Rq[9];
        rand_pose(p);
        if (n % 4 == 1) {
            p[4] = (rp_real)(1.5707963267948966); /* exactly locked */
        } else if (n % 4 == 2) {
            p[4] = (rp_real)(-1.5707963267948966 + 1e-3);
        }
        for (int i = 0; i < 6; ++i) {
            d[i] = (rp_real)urand(-0.3, 0.3);
        }
        if (n % 4 == 3) {
            /* a step that lands on beta = +pi/2 from beta = 0 with alpha = gamma = 0 */
            p[3] = p[4] = p[5] = 0;
            d[3] = d[5] = 0;
            d[4] = (rp_real)(1.5707963267948966);
        }
        assert_ok(rp_pose_plus(p, d, q));
        rp_rot_from_angles(p + 3, R);
        rp_rot_exp(d + 3, E);
        rp_rot_mul(E, R, R);
        rp_rot_from_angles(q + 3, Rq);
        for (int e = 0; e < 9; ++e) {
            assert_near(Rq[e], R[e], RP_TOL(1e-12, 2e-6));
        }
        for (int i = 0; i < 3; ++i) {
            assert_near(q[i], p[i] + d[i], RP_TOL(1e-15, 1e-6));
        }
        rp_pose_minus(q, p, back);
        for (int i = 0; i < 6; ++i) {
            assert_near(back[i], d[i], RP_TOL(1e-9, 2e-4));
        }
    }
    const rp_real p[6] = {0, 0, 0, 0, 0, 0};
    rp_real d[6] = {0, 0, 0, 0, 0, 0}, q[6];
    d[4] = (rp_real)NAN;
    assert_status(rp_pose_plus(p, d, q), RP_E_NAN);
    assert_status(rp_pose_plus(NULL, d, q), RP_E_ARG);
}

static void test_pose_lin_set_rejects_nan(void **state)
{
    (void)state;
    rp_pose_lin_t pl;
    rp_real p[6] = {0, 0, 0, 0, 0, 0};
    p[4] = (rp_real)NAN;
    assert_status(rp_pose_lin_set(&pl, p), RP_E_NAN);
    assert_status(rp_pose_lin_set(NULL, p), RP_E_ARG);
}

static void test_cam_point_follows_eq2(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    for (int n = 0; n < 20; ++n) {
        rp_real p[6], M[3];
        rand_pose(p);
        rp_pose_lin_t pl;
        assert_ok(rp_pose_lin_set(&pl, p));
        for (int i = 0; i < 3; ++i) {
            M[i] = (rp_real)urand(-3, 3);
        }
        for (uint8_t k = 0; k < rig.n_cams; ++k) {
            /* P = R_k^T R_j^T (M - d_j - R_j D_k), term by term. */
            rp_real RjDk[3], q[3], RjRk[9], want[3], P[3];
            rp_rot_apply(pl.R, rig.cam[k].D, RjDk);
            for (int i = 0; i < 3; ++i) {
                q[i] = M[i] - p[i] - RjDk[i];
            }
            rp_rot_mul(pl.R, rig.cam[k].R, RjRk);
            rp_rot_apply_t(RjRk, q, want);
            assert_ok(rp_rig_cam_point(&rig, k, &pl, M, P));
            for (int i = 0; i < 3; ++i) {
                assert_near(P[i], want[i], RP_TOL(1e-13, 1e-5));
            }
        }
    }
}

static void test_at_the_start_cam1_sees_world_coordinates_and_cam3_looks_back(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    const rp_real p0[6] = {0, 0, 0, 0, 0, 0};
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p0));
    const rp_real M[3] = {RP_C(0.2), RP_C(-0.1), RP_C(-2.0)};
    rp_real P[3];
    assert_ok(rp_rig_cam_point(&rig, 0, &pl, M, P));
    assert_near(P[0], 0.2, RP_TOL(1e-15, 1e-7));
    assert_near(P[1], -0.1, RP_TOL(1e-15, 1e-7));
    assert_near(P[2], -2.0, RP_TOL(1e-15, 1e-7));
    /* cam3: at z = -0.1, rotated by pi about y: x and z flip. */
    assert_ok(rp_rig_cam_point(&rig, 2, &pl, M, P));
    assert_near(P[0], -0.2, RP_TOL(1e-15, 1e-6));
    assert_near(P[1], -0.1, RP_TOL(1e-15, 1e-6));
    assert_near(P[2], 1.9, RP_TOL(1e-15, 1e-6));
    /* cam2 looks along +x: a point on the +x axis is straight ahead. */
    const rp_real Mx[3] = {RP_C(1.0866), 0, RP_C(-0.05)};
    assert_ok(rp_rig_cam_point(&rig, 1, &pl, Mx, P));
    assert_near(P[0], 0.0, RP_TOL(1e-15, 1e-6));
    assert_near(P[1], 0.0, RP_TOL(1e-15, 1e-6));
    assert_near(P[2], 1.0, RP_TOL(1e-15, 1e-6));
}

static void test_world_point_inverts_cam_point(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    for (int n = 0; n < 20; ++n) {
        rp_real p[6];
        rand_pose(p);
        rp_pose_lin_t pl;
        assert_ok(rp_pose_lin_set(&pl, p));
        for (uint8_t k = 0; k < rig.n_cams; ++k) {
            const rp_real P[3] = {(rp_real)urand(-1, 1), (rp_real)urand(-1, 1),
                                  (rp_real)urand(0.1, 4)};
            rp_real M[3], P2[3];
            assert_ok(rp_rig_world_point(&rig, k, &pl, P, M));
            assert_ok(rp_rig_cam_point(&rig, k, &pl, M, P2));
            for (int i = 0; i < 3; ++i) {
                assert_near(P2[i], P[i], RP_TOL(1e-13, 2e-6));
            }
        }
    }
}

static void test_project_jacobians_match_central_differences(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    const double h = RP_TOL(1e-6, 1e-3);
    const double tol = RP_TOL(1e-6, 3e-3); /* relative to the largest entry of the row */
    for (int n = 0; n < 30; ++n) {
        rp_real p[6];
        rand_pose(p);
        rp_pose_lin_t pl;
        assert_ok(rp_pose_lin_set(&pl, p));
        for (uint8_t k = 0; k < rig.n_cams; ++k) {
            for (int f = 0; f < 4; ++f) {
                rp_real M[3], uv[2], Jp[12], JM[6];
                rand_point(&rig, k, &pl, M);
                assert_ok(rp_rig_project(&rig, k, &pl, M, uv, Jp, JM));
                double scale[2] = {0, 0};
                for (int r = 0; r < 2; ++r) {
                    for (int c = 0; c < 6; ++c) {
                        scale[r] = fmax(scale[r], fabs((double)Jp[6 * r + c]));
                    }
                }
                for (int c = 0; c < 6; ++c) {
                    /* column c: d uv / d d_c in the pose chart, p [+] (+-h e_c) */
                    rp_real pp[6], pm[6], up[2], um[2], dp[6] = {0}, dm[6] = {0};
                    dp[c] = (rp_real)h;
                    dm[c] = (rp_real)-h;
                    assert_ok(rp_pose_plus(p, dp, pp));
                    assert_ok(rp_pose_plus(p, dm, pm));
                    rp_pose_lin_t lp, lm;
                    assert_ok(rp_pose_lin_set(&lp, pp));
                    assert_ok(rp_pose_lin_set(&lm, pm));
                    assert_ok(rp_rig_project(&rig, k, &lp, M, up, NULL, NULL));
                    assert_ok(rp_rig_project(&rig, k, &lm, M, um, NULL, NULL));
                    const double step = (double)dp[c] - (double)dm[c];
                    for (int r = 0; r < 2; ++r) {
                        assert_near(Jp[6 * r + c], ((double)up[r] - (double)um[r]) / step,
                                    tol * scale[r]);
                    }
                }
                for (int c = 0; c < 3; ++c) {
                    rp_real Mp[3], Mm[3], up[2], um[2];
                    memcpy(Mp, M, sizeof Mp);
                    memcpy(Mm, M, sizeof Mm);
                    Mp[c] = (rp_real)(M[c] + h);
                    Mm[c] = (rp_real)(M[c] - h);
                    assert_ok(rp_rig_project(&rig, k, &pl, Mp, up, NULL, NULL));
                    assert_ok(rp_rig_project(&rig, k, &pl, Mm, um, NULL, NULL));
                    const double step = (double)Mp[c] - (double)Mm[c];
                    for (int r = 0; r < 2; ++r) {
                        assert_near(JM[3 * r + c], ((double)up[r] - (double)um[r]) / step,
                                    tol * scale[r]);
                        /* d uv / d t = -d uv / d M. */
                        assert_true(Jp[6 * r + c] == -JM[3 * r + c]);
                    }
                }
            }
        }
    }
}

static void test_project_pixel_does_not_depend_on_the_jacobians_asked(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    rp_real p[6];
    rand_pose(p);
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p));
    for (uint8_t k = 0; k < rig.n_cams; ++k) {
        rp_real M[3], uv[2], uv1[2], uv2[2], uv3[2], Jp[12], JM[6], P[3], want[2];
        rand_point(&rig, k, &pl, M);
        assert_ok(rp_rig_project(&rig, k, &pl, M, uv, NULL, NULL));
        assert_ok(rp_rig_project(&rig, k, &pl, M, uv1, Jp, NULL));
        assert_ok(rp_rig_project(&rig, k, &pl, M, uv2, NULL, JM));
        assert_ok(rp_rig_project(&rig, k, &pl, M, uv3, Jp, JM));
        assert_ok(rp_rig_cam_point(&rig, k, &pl, M, P));
        assert_ok(rp_cam_project(&rig.cam[k].cam, P, want, NULL));
        for (int r = 0; r < 2; ++r) {
            assert_true(uv1[r] == uv[r] && uv2[r] == uv[r] && uv3[r] == uv[r]);
            assert_near(uv[r], want[r], RP_TOL(1e-12, 1e-4));
        }
    }
}

static void test_project_reports_a_point_behind_the_camera(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    const rp_real p0[6] = {0, 0, 0, 0, 0, 0};
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p0));
    const rp_real M[3] = {RP_C(0.1), RP_C(0.05), RP_C(1.0)}; /* ahead of cam1, behind cam3 */
    rp_real uv[2], Jp[12], JM[6];
    assert_ok(rp_rig_project(&rig, 0, &pl, M, uv, Jp, JM));
    assert_status(rp_rig_project(&rig, 2, &pl, M, uv, Jp, JM), RP_E_BEHIND);
    assert_status(rp_rig_project(&rig, 5, &pl, M, uv, NULL, NULL), RP_E_BEHIND);
    /* Rig moved to z = 0.5 and rolled by pi about z: cam1 (still looking +z) has the point at
     * z = 0.2 behind it, cam3 (at z = 0.4, looking -z) has it 0.2 m ahead. */
    const rp_real p2[6] = {0, 0, RP_C(0.5), 0, 0, (rp_real)PI};
    rp_pose_lin_t pl2;
    assert_ok(rp_pose_lin_set(&pl2, p2));
    const rp_real M2[3] = {RP_C(0.01), RP_C(0.02), RP_C(0.2)};
    assert_status(rp_rig_project(&rig, 0, &pl2, M2, uv, Jp, NULL), RP_E_BEHIND);
    assert_ok(rp_rig_project(&rig, 2, &pl2, M2, uv, Jp, NULL));
}

static void test_measurement_model_rejects_nan_and_bad_camera_index(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    const rp_real p0[6] = {0, 0, 0, 0, 0, 0};
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p0));
    const rp_real nan[3] = {RP_C(0.1), (rp_real)NAN, RP_C(1.0)};
    const rp_real M[3] = {RP_C(0.1), RP_C(0.05), RP_C(1.0)};
    rp_real uv[2], Jp[12], JM[6], P[3];
    assert_status(rp_rig_project(&rig, 0, &pl, nan, uv, Jp, JM), RP_E_NAN);
    assert_status(rp_rig_cam_point(&rig, 0, &pl, nan, P), RP_E_NAN);
    assert_status(rp_rig_world_point(&rig, 0, &pl, nan, P), RP_E_NAN);
    assert_status(rp_rig_project(&rig, 6, &pl, M, uv, Jp, JM), RP_E_ARG);
    rig.n_cams = 4;
    assert_status(rp_rig_project(&rig, 4, &pl, M, uv, NULL, NULL), RP_E_ARG);
    assert_status(rp_rig_cam_point(&rig, 4, &pl, M, P), RP_E_ARG);
    assert_status(rp_rig_world_point(&rig, 255, &pl, M, P), RP_E_ARG);
    assert_status(rp_rig_project(NULL, 0, &pl, M, uv, NULL, NULL), RP_E_ARG);
    assert_status(rp_rig_project(&rig, 0, NULL, M, uv, NULL, NULL), RP_E_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rig_check_accepts_the_six_camera_rig),
        cmocka_unit_test(test_rig_check_rejects_bad_rotations_cameras_and_counts),
        cmocka_unit_test(test_pose_lin_set_holds_the_pose_and_its_rotation),
        cmocka_unit_test(test_pose_plus_and_minus_are_the_chart_also_at_gimbal_lock),
        cmocka_unit_test(test_pose_lin_set_rejects_nan),
        cmocka_unit_test(test_cam_point_follows_eq2),
        cmocka_unit_test(test_at_the_start_cam1_sees_world_coordinates_and_cam3_looks_back),
        cmocka_unit_test(test_world_point_inverts_cam_point),
        cmocka_unit_test(test_project_jacobians_match_central_differences),
        cmocka_unit_test(test_project_pixel_does_not_depend_on_the_jacobians_asked),
        cmocka_unit_test(test_project_reports_a_point_behind_the_camera),
        cmocka_unit_test(test_measurement_model_rejects_nan_and_bad_camera_index),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
