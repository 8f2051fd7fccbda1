/* test_rot.c - rotations: the paper's angles, quaternions, exp/log, products (rp_rot.h). */
#include <string.h>

#include "rp_test.h"

#include "rigpose/rp_rot.h"

#define PI 3.14159265358979323846

/* Uniform in [a, b), from one seeded generator per file (deterministic). */
static double urand(double a, double b) { return rp_test_urand(a, b); }

static void rand_unit(rp_real v[3])
{
    double x, y, z, n;
    do {
        x = urand(-1, 1);
        y = urand(-1, 1);
        z = urand(-1, 1);
        n = sqrt(x * x + y * y + z * z);
    } while (n < 0.1 || n > 1.0);
    v[0] = (rp_real)(x / n);
    v[1] = (rp_real)(y / n);
    v[2] = (rp_real)(z / n);
}

static void rand_rot(rp_real R[9])
{
    rp_real w[3];
    rand_unit(w);
    const rp_real t = (rp_real)urand(0, PI);
    for (int i = 0; i < 3; ++i) {
        w[i] *= t;
    }
    rp_rot_exp(w, R);
}

static void assert_mat_near(const rp_real *A, const rp_real *B, int n, double tol)
{
    for (int i = 0; i < n; ++i) {
        assert_near(A[i], B[i], tol);
    }
}

static void assert_rotation(const rp_real R[9], double tol)
{
    rp_real RtR[9];
    rp_rot_mul_at_b(R, R, RtR);
    const rp_real I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    assert_mat_near(RtR, I, 9, tol);
    const double det = (double)R[0] * ((double)R[4] * R[8] - (double)R[5] * R[7]) -
                       (double)R[1] * ((double)R[3] * R[8] - (double)R[5] * R[6]) +
                       (double)R[2] * ((double)R[3] * R[7] - (double)R[4] * R[6]);
    assert_near(det, 1.0, tol);
}

/* Angle difference wrapped to [-pi, pi]. */
static double adiff(double a, double b)
{
    double d = fmod(a - b, 2 * PI);
    if (d > PI) {
        d -= 2 * PI;
    } else if (d < -PI) {
        d += 2 * PI;
    }
    return d;
}

static void test_from_angles_is_rz_ry_rx_about_fixed_axes(void **state)
{
    (void)state;
    const double a = 0.3, b = -0.7, g = 1.9;
    const rp_real Rx[9] = {1, 0, 0, 0, (rp_real)cos(a), (rp_real)-sin(a),
                           0, (rp_real)sin(a), (rp_real)cos(a)};
    const rp_real Ry[9] = {(rp_real)cos(b), 0, (rp_real)sin(b), 0, 1, 0,
                           (rp_real)-sin(b), 0, (rp_real)cos(b)};
    const rp_real Rz[9] = {(rp_real)cos(g), (rp_real)-sin(g), 0,
                           (rp_real)sin(g), (rp_real)cos(g), 0, 0, 0, 1};
    rp_real want[9], R[9];
    rp_rot_mul(Ry, Rx, want);
    rp_rot_mul(Rz, want, want);
    const rp_real abg[3] = {(rp_real)a, (rp_real)b, (rp_real)g};
    rp_rot_from_angles(abg, R);
    assert_mat_near(R, want, 9, RP_TOL(1e-14, 1e-6));
}

static void test_to_angles_round_trips_on_a_grid(void **state)
{
    (void)state;
    for (int i = -6; i <= 6; ++i) {
        for (int j = -7; j <= 7; ++j) {
            for (int l = -6; l <= 6; ++l) {
                const rp_real abg[3] = {(rp_real)(i * PI / 6.5), (rp_real)(j * 1.5 / 7.0),
                                        (rp_real)(l * PI / 6.5)};
                rp_real R[9], out[3];
                rp_rot_from_angles(abg, R);
                assert_ok(rp_rot_to_angles(R, out));
                for (int k = 0; k < 3; ++k) {
                    assert_near(adiff(out[k], abg[k]), 0.0, RP_TOL(1e-12, 2e-5));
                }
                assert_true(out[0] > -PI && out[0] <= PI);
                assert_true(out[2] > -PI && out[2] <= PI);
            }
        }
    }
}

static void test_to_angles_near_gimbal_lock_reproduces_the_rotation(void **state)
{
    (void)state;
    /* Offsets from +-pi/2: inside the lock threshold, just outside it, and well outside. */
    const double offs[] = {0.0, RP_TOL(1e-12, 1e-7), RP_TOL(-1e-12, -1e-7), RP_TOL(1e-8, 1e-4),
                           RP_TOL(-1e-8, -1e-4), 1e-3, -1e-3};
    for (int s = -1; s <= 1; s += 2) {
        for (unsigned o = 0; o < sizeof offs / sizeof offs[0]; ++o) {
            for (int i = -3; i <= 3; ++i) {
                for (int l = -3; l <= 3; ++l) {
                    const rp_real abg[3] = {(rp_real)(i * 0.9), (rp_real)(s * PI / 2 + offs[o]),
                                            (rp_real)(l * 0.85)};
                    rp_real R[9], out[3], R2[9];
                    rp_rot_from_angles(abg, R);
                    assert_ok(rp_rot_to_angles(R, out));
                    assert_true(out[1] >= -PI / 2 && out[1] <= PI / 2);
                    rp_rot_from_angles(out, R2);
                    assert_mat_near(R2, R, 9, RP_TOL(1e-9, 2e-5));
                }
            }
        }
    }
}

static void test_to_angles_at_gimbal_lock_sets_alpha_zero_and_keeps_alpha_minus_gamma(void **state)
{
    (void)state;
    const rp_real abg[3] = {RP_C(0.4), (rp_real)(PI / 2), RP_C(-1.1)};
    rp_real R[9], out[3];
    rp_rot_from_angles(abg, R);
    assert_ok(rp_rot_to_angles(R, out));
    assert_true(out[0] == RP_C(0.0));
    assert_near(out[1], PI / 2, RP_TOL(1e-12, 1e-6));
    /* beta = +pi/2: only alpha - gamma is determined. */
    assert_near(adiff(out[0] - out[2], abg[0] - abg[2]), 0.0, RP_TOL(1e-12, 1e-6));

    const rp_real abg2[3] = {RP_C(0.4), (rp_real)(-PI / 2), RP_C(-1.1)};
    rp_rot_from_angles(abg2, R);
    assert_ok(rp_rot_to_angles(R, out));
    assert_true(out[0] == RP_C(0.0));
    /* beta = -pi/2: only alpha + gamma is determined. */
    assert_near(adiff(out[0] + out[2], abg2[0] + abg2[2]), 0.0, RP_TOL(1e-12, 1e-6));
}

static void test_to_angles_rejects_non_finite(void **state)
{
    (void)state;
    rp_real R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, out[3];
    R[4] = (rp_real)NAN;
    assert_status(rp_rot_to_angles(R, out), RP_E_NAN);
    R[4] = (rp_real)INFINITY;
    assert_status(rp_rot_to_angles(R, out), RP_E_NAN);
}

static void test_angle_derivs_match_central_differences(void **state)
{
    (void)state;
    const double h = RP_TOL(1e-5, 2e-3);
    for (int n = 0; n < 50; ++n) {
        rp_real abg[3] = {(rp_real)urand(-PI, PI), (rp_real)urand(-1.5, 1.5),
                          (rp_real)urand(-PI, PI)};
        if (n == 0) {
            abg[1] = (rp_real)(PI / 2); /* the derivative has no singularity at gimbal lock */
        }
        rp_real dR[3][9];
        rp_rot_angle_derivs(abg, dR);
        for (int i = 0; i < 3; ++i) {
            rp_real ap[3] = {abg[0], abg[1], abg[2]}, am[3] = {abg[0], abg[1], abg[2]};
            ap[i] = (rp_real)(abg[i] + h);
            am[i] = (rp_real)(abg[i] - h);
            rp_real Rp[9], Rm[9];
            rp_rot_from_angles(ap, Rp);
            rp_rot_from_angles(am, Rm);
            const double step = (double)ap[i] - (double)am[i];
            for (int e = 0; e < 9; ++e) {
                assert_near(dR[i][e], ((double)Rp[e] - (double)Rm[e]) / step,
                            RP_TOL(1e-8, 1e-4));
            }
        }
    }
}

static void test_quat_of_rotation_about_z(void **state)
{
    (void)state;
    const double t = 0.8;
    const rp_real abg[3] = {0, 0, (rp_real)t};
    rp_real R[9], q[4];
    rp_rot_from_angles(abg, R);
    rp_rot_to_quat(R, q);
    assert_near(q[0], cos(t / 2), RP_TOL(1e-14, 1e-6));
    assert_near(q[1], 0.0, RP_TOL(1e-14, 1e-6));
    assert_near(q[2], 0.0, RP_TOL(1e-14, 1e-6));
    assert_near(q[3], sin(t / 2), RP_TOL(1e-14, 1e-6));
}

static void test_quat_round_trips_including_angles_near_pi(void **state)
{
    (void)state;
    const double angles[] = {0.0, 1e-7, 0.5, 2.0, 3.0, PI - 1e-3, PI - 1e-6, PI};
    for (int n = 0; n < 200; ++n) {
        rp_real w[3], R[9], q[4], R2[9], q2[4];
        rand_unit(w);
        const double t = n < 8 * 10 ? angles[n % 8] : urand(0, PI);
        for (int i = 0; i < 3; ++i) {
            w[i] = (rp_real)(w[i] * t);
        }
        rp_rot_exp(w, R);
        rp_rot_to_quat(R, q);
        assert_true(q[0] >= 0);
        assert_near(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0,
                    RP_TOL(1e-14, 1e-6));
        assert_ok(rp_rot_from_quat(q, R2));
        assert_mat_near(R2, R, 9, RP_TOL(1e-14, 1e-6));
        /* q and -q are the same rotation. */
        const rp_real qn[4] = {-q[0], -q[1], -q[2], -q[3]};
        assert_ok(rp_rot_from_quat(qn, R2));
        rp_rot_to_quat(R2, q2);
        if (q[0] > RP_TOL(1e-9, 1e-3)) {
            assert_mat_near(q2, q, 4, RP_TOL(1e-14, 1e-6));
        }
    }
}

static void test_from_quat_normalises_and_rejects_zero_and_nan(void **state)
{
    (void)state;
    const rp_real q[4] = {RP_C(0.5), RP_C(-0.5), RP_C(0.5), RP_C(0.5)};
    const rp_real q3[4] = {RP_C(1.5), RP_C(-1.5), RP_C(1.5), RP_C(1.5)};
    rp_real R[9], R3[9];
    assert_ok(rp_rot_from_quat(q, R));
    assert_ok(rp_rot_from_quat(q3, R3));
    assert_mat_near(R3, R, 9, RP_TOL(1e-15, 1e-7));
    assert_rotation(R, RP_TOL(1e-14, 1e-6));
    const rp_real z[4] = {0, 0, 0, 0};
    assert_status(rp_rot_from_quat(z, R), RP_E_ARG);
    const rp_real tiny[4] = {RP_TOL(1e-13, 1e-7), 0, 0, 0};
    assert_status(rp_rot_from_quat(tiny, R), RP_E_ARG);
    const rp_real bad[4] = {1, (rp_real)NAN, 0, 0};
    assert_status(rp_rot_from_quat(bad, R), RP_E_NAN);
}

static void test_exp_about_x_is_rx(void **state)
{
    (void)state;
    const rp_real w[3] = {RP_C(0.7), 0, 0};
    const rp_real abg[3] = {RP_C(0.7), 0, 0};
    rp_real R[9], want[9];
    rp_rot_exp(w, R);
    rp_rot_from_angles(abg, want);
    assert_mat_near(R, want, 9, RP_TOL(1e-15, 1e-7));
}

static void test_exp_log_round_trip_from_zero_to_near_pi(void **state)
{
    (void)state;
    const double angles[] = {0.0, 1e-12, 1e-6, 1e-3, 0.1, 1.0, 2.5, 3.1, PI - 1e-3,
                             RP_TOL(PI - 1e-6, PI - 1e-4)};
    const int na = (int)(sizeof angles / sizeof angles[0]);
    for (int n = 0; n < 300; ++n) {
        rp_real u[3], w[3], R[9], w2[3];
        rand_unit(u);
        const double t = n < na * 10 ? angles[n % na] : urand(0, PI);
        for (int i = 0; i < 3; ++i) {
            w[i] = (rp_real)(u[i] * t);
        }
        rp_rot_exp(w, R);
        assert_rotation(R, RP_TOL(1e-14, 1e-6));
        rp_rot_log(R, w2);
        for (int i = 0; i < 3; ++i) {
            assert_near(w2[i], w[i], RP_TOL(1e-12, 2e-5));
        }
    }
}

static void test_log_at_pi_returns_an_axis_that_exp_maps_back(void **state)
{
    (void)state;
    for (int n = 0; n < 20; ++n) {
        rp_real u[3], w[3], R[9], w2[3], R2[9];
        rand_unit(u);
        for (int i = 0; i < 3; ++i) {
            w[i] = (rp_real)(u[i] * PI);
        }
        rp_rot_exp(w, R);
        rp_rot_log(R, w2);
        assert_near(sqrt((double)w2[0] * w2[0] + (double)w2[1] * w2[1] + (double)w2[2] * w2[2]),
                    PI, RP_TOL(1e-12, 1e-5));
        rp_rot_exp(w2, R2);
        assert_mat_near(R2, R, 9, RP_TOL(1e-14, 1e-6));
    }
}

static void test_exp_of_tiny_vector_is_identity_plus_skew(void **state)
{
    (void)state;
    const rp_real w[3] = {RP_C(1e-9), RP_C(-2e-9), RP_C(3e-9)};
    rp_real R[9];
    rp_rot_exp(w, R);
    const rp_real want[9] = {1, -w[2], w[1], w[2], 1, -w[0], -w[1], w[0], 1};
    assert_mat_near(R, want, 9, RP_TOL(1e-17, 1e-12));
}

static void test_orthonormalize_returns_the_nearest_rotation(void **state)
{
    (void)state;
    for (int n = 0; n < 50; ++n) {
        rp_real Rt[9], S[9], A[9];
        rand_rot(Rt);
        /* A = Rt (I + S), S symmetric and small: the polar factor of A is Rt exactly. */
        for (int i = 0; i < 3; ++i) {
            for (int j = i; j < 3; ++j) {
                const rp_real s = (rp_real)urand(-1e-2, 1e-2);
                S[3 * i + j] = S[3 * j + i] = s + (i == j ? RP_C(1.0) : RP_C(0.0));
            }
        }
        rp_rot_mul(Rt, S, A);
        rp_rot_orthonormalize(A);
        assert_rotation(A, RP_TOL(1e-14, 1e-6));
        assert_mat_near(A, Rt, 9, RP_TOL(1e-13, 2e-6));
    }
}

static void test_orthonormalize_repairs_accumulated_products(void **state)
{
    (void)state;
    rp_real R[9], step[9];
    const rp_real w[3] = {RP_C(0.01), RP_C(-0.02), RP_C(0.015)};
    rp_rot_exp(w, step);
    rp_rot_exp(w, R);
    for (int n = 0; n < 1000; ++n) {
        rp_rot_mul(R, step, R);
        R[0] = (rp_real)(R[0] * (1.0 + 1e-7)); /* drift */
    }
    rp_rot_orthonormalize(R);
    assert_rotation(R, RP_TOL(1e-14, 1e-6));
    /* Far from a rotation (a reflection): still comes back as a rotation. */
    rp_real F[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1};
    rp_rot_orthonormalize(F);
    assert_rotation(F, RP_TOL(1e-14, 1e-6));
}

static void test_distance_is_the_rotation_angle_between(void **state)
{
    (void)state;
    const double angles[] = {0.0, 1e-6, 0.3, 2.0, PI - 1e-3};
    for (int n = 0; n < 50; ++n) {
        rp_real A[9], B[9], u[3], w[3], E[9];
        rand_rot(A);
        rand_unit(u);
        const double t = angles[n % 5];
        for (int i = 0; i < 3; ++i) {
            w[i] = (rp_real)(u[i] * t);
        }
        rp_rot_exp(w, E);
        rp_rot_mul(A, E, B);
        assert_near(rp_rot_distance(A, B), t, RP_TOL(1e-12, 1e-5));
        assert_near(rp_rot_distance(B, A), t, RP_TOL(1e-12, 1e-5));
    }
}

static void test_products_agree_and_allow_aliasing(void **state)
{
    (void)state;
    rp_real A[9], B[9], At[9], Bt[9], C[9], want[9], T[9];
    rand_rot(A);
    rand_rot(B);
    rp_rot_transpose(A, At);
    rp_rot_transpose(B, Bt);
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            assert_true(At[3 * i + j] == A[3 * j + i]);
            double s = 0;
            for (int k = 0; k < 3; ++k) {
                s += (double)A[3 * i + k] * B[3 * k + j];
            }
            want[3 * i + j] = (rp_real)s;
        }
    }
    rp_rot_mul(A, B, C);
    assert_mat_near(C, want, 9, RP_TOL(1e-15, 1e-6));
    rp_rot_mul_at_b(At, B, C);
    assert_mat_near(C, want, 9, RP_TOL(1e-15, 1e-6));
    rp_rot_mul_a_bt(A, Bt, C);
    assert_mat_near(C, want, 9, RP_TOL(1e-15, 1e-6));

    memcpy(T, A, sizeof T);
    rp_rot_mul(T, B, T);
    assert_mat_near(T, want, 9, RP_TOL(1e-15, 1e-6));
    memcpy(T, B, sizeof T);
    rp_rot_mul(A, T, T);
    assert_mat_near(T, want, 9, RP_TOL(1e-15, 1e-6));
    memcpy(T, At, sizeof T);
    rp_rot_mul_at_b(T, B, T);
    assert_mat_near(T, want, 9, RP_TOL(1e-15, 1e-6));
    memcpy(T, Bt, sizeof T);
    rp_rot_mul_a_bt(A, T, T);
    assert_mat_near(T, want, 9, RP_TOL(1e-15, 1e-6));
    memcpy(T, A, sizeof T);
    rp_rot_transpose(T, T);
    assert_mat_near(T, At, 9, 0.0);

    rp_real v[3] = {RP_C(0.3), RP_C(-1.2), RP_C(2.0)}, Av[3], back[3];
    rp_rot_apply(A, v, Av);
    for (int i = 0; i < 3; ++i) {
        assert_near(Av[i], A[3 * i] * v[0] + A[3 * i + 1] * v[1] + A[3 * i + 2] * v[2],
                    RP_TOL(1e-15, 1e-6));
    }
    rp_rot_apply_t(A, Av, back);
    assert_mat_near(back, v, 3, RP_TOL(1e-14, 1e-6));
    rp_rot_apply(A, v, v);
    assert_mat_near(v, Av, 3, 0.0);
    rp_rot_apply_t(A, v, v);
    assert_mat_near(v, back, 3, 0.0);
}

static void test_angle_wrap_maps_to_minus_pi_pi(void **state)
{
    (void)state;
    assert_near(rp_angle_wrap(RP_C(0.5)), 0.5, RP_TOL(1e-15, 1e-7));
    assert_near(rp_angle_wrap((rp_real)(0.5 + 2 * PI)), 0.5, RP_TOL(1e-14, 1e-6));
    assert_near(rp_angle_wrap((rp_real)(-0.5 - 4 * PI)), -0.5, RP_TOL(1e-14, 1e-6));
    assert_near(rp_angle_wrap((rp_real)(PI - 0.1)), PI - 0.1, RP_TOL(1e-14, 1e-6));
    assert_near(rp_angle_wrap((rp_real)(-PI + 0.1)), -PI + 0.1, RP_TOL(1e-14, 1e-6));
    const rp_real pi = (rp_real)PI;
    assert_true(rp_angle_wrap(pi) == -pi);
    assert_true(rp_angle_wrap(-pi) == -pi);
    for (int n = 0; n < 1000; ++n) {
        const rp_real x = (rp_real)urand(-100, 100);
        const rp_real r = rp_angle_wrap(x);
        assert_true(r >= -pi && r < pi);
        assert_near(adiff(r, x), 0.0, RP_TOL(1e-12, 2e-5));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_from_angles_is_rz_ry_rx_about_fixed_axes),
        cmocka_unit_test(test_to_angles_round_trips_on_a_grid),
        cmocka_unit_test(test_to_angles_near_gimbal_lock_reproduces_the_rotation),
        cmocka_unit_test(test_to_angles_at_gimbal_lock_sets_alpha_zero_and_keeps_alpha_minus_gamma),
        cmocka_unit_test(test_to_angles_rejects_non_finite),
        cmocka_unit_test(test_angle_derivs_match_central_differences),
        cmocka_unit_test(test_quat_of_rotation_about_z),
        cmocka_unit_test(test_quat_round_trips_including_angles_near_pi),
        cmocka_unit_test(test_from_quat_normalises_and_rejects_zero_and_nan),
        cmocka_unit_test(test_exp_about_x_is_rx),
        cmocka_unit_test(test_exp_log_round_trip_from_zero_to_near_pi),
        cmocka_unit_test(test_log_at_pi_returns_an_axis_that_exp_maps_back),
        cmocka_unit_test(test_exp_of_tiny_vector_is_identity_plus_skew),
        cmocka_unit_test(test_orthonormalize_returns_the_nearest_rotation),
        cmocka_unit_test(test_orthonormalize_repairs_accumulated_products),
        cmocka_unit_test(test_distance_is_the_rotation_angle_between),
        cmocka_unit_test(test_products_agree_and_allow_aliasing),
        cmocka_unit_test(test_angle_wrap_maps_to_minus_pi_pi),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
