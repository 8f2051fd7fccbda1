/*
 * test_stereo.c - the stereo pair: E/F from the rig extrinsics, the epipolar check, and
 * triangulation, on the paper's rig (640x480, fx = fy = 800 px, centred principal point).
 *
 * Rig of these tests (camera index: role):
 *   0: cam1 at the origin looking +z          1: its partner at (0.1, 0, 0), same orientation
 *   2: cam3 at (0, 0, -0.1) looking -z, Ry(pi)  3: its partner at (0.1, 0, -0.1), same as cam3
 *   4: a verged camera (rotated about y and x, offset in x, y, z) to pair with cam1 in general
 *      position.
 */
#include "rp_test.h"

#include <string.h>

#include "rigpose/rp_camera.h"
#include "rigpose/rp_rig.h"
#include "rigpose/rp_stereo.h"

/* ---- fixtures ------------------------------------------------------------------------------ */

static uint64_t rng_state;

static double urand(void) /* uniform in [0, 1) */
{
    rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static void set_identity(rp_real R[9])
{
    for (int i = 0; i < 9; ++i) {
        R[i] = RP_C(0.0);
    }
    R[0] = R[4] = R[8] = RP_C(1.0);
}

/* R = Ry(th) Rx(ph), computed in double then rounded once. */
static void set_ry_rx(rp_real R[9], double th, double ph)
{
    const double cy = cos(th), sy = sin(th), cx = cos(ph), sx = sin(ph);
    const double Ry[9] = {cy, 0, sy, 0, 1, 0, -sy, 0, cy};
    const double Rx[9] = {1, 0, 0, 0, cx, -sx, 0, sx, cx};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            double s = 0;
            for (int k = 0; k < 3; ++k) {
                s += Ry[3 * i + k] * Rx[3 * k + j];
            }
            R[3 * i + j] = (rp_real)s;
        }
    }
}

static void set_ry_pi(rp_real R[9])
{
    set_identity(R);
    R[0] = RP_C(-1.0);
    R[8] = RP_C(-1.0);
}

static void set_D(rp_real D[3], double x, double y, double z)
{
    D[0] = (rp_real)x;
    D[1] = (rp_real)y;
    D[2] = (rp_real)z;
}

static void make_rig(rp_rig_t *rig, int distorted)
{
    memset(rig, 0, sizeof *rig);
    rig->n_cams = 5;
    for (int k = 0; k < 5; ++k) {
        rig->cam[k].cam = rp_cam_pinhole(640, 480, RP_C(800.0), RP_C(800.0), RP_C(319.5),
                                         RP_C(239.5));
        if (distorted) {
            rig->cam[k].cam.k1 = RP_C(-0.25);
            rig->cam[k].cam.k2 = RP_C(0.08);
            rig->cam[k].cam.p1 = RP_C(1e-3);
            rig->cam[k].cam.p2 = RP_C(-5e-4);
            rig->cam[k].cam.k3 = RP_C(-0.01);
        }
    }
    set_identity(rig->cam[0].R);
    set_D(rig->cam[0].D, 0, 0, 0);
    set_identity(rig->cam[1].R);
    set_D(rig->cam[1].D, 0.1, 0, 0);
    set_ry_pi(rig->cam[2].R);
    set_D(rig->cam[2].D, 0, 0, -0.1);
    set_ry_pi(rig->cam[3].R);
    set_D(rig->cam[3].D, 0.1, 0, -0.1);
    set_ry_rx(rig->cam[4].R, -0.15, 0.05);
    set_D(rig->cam[4].D, 0.12, 0.02, 0.01);
}

/* Camera-k coordinates of a point M of cam1's frame: P = R_k^T (M - D_k). */
static void to_cam(const rp_rig_t *rig, int k, const double M[3], rp_real P[3])
{
    const rp_real *R = rig->cam[k].R, *D = rig->cam[k].D;
    for (int i = 0; i < 3; ++i) {
        double s = 0;
        for (int j = 0; j < 3; ++j) {
            s += (double)R[3 * j + i] * (M[j] - (double)D[j]);
        }
        P[i] = (rp_real)s;
    }
}

/* A random point of cam1's frame seen by both cameras of the pair, at 0.667..1 m from camera
 * a, inside both images; its camera-a coordinates (double) and pixels. */
static void make_match(const rp_rig_t *rig, const rp_stereo_pair_t *sp, double Pa[3],
                       rp_real uv_a[2], rp_real uv_b[2])
{
    for (int tries = 0; tries < 10000; ++tries) {
        const double z = 0.667 + 0.333 * urand();
        const double x = (urand() - 0.5) * 0.7 * z, y = (urand() - 0.5) * 0.5 * z;
        const rp_real *Ra = rig->cam[sp->a].R, *Da = rig->cam[sp->a].D;
        double M[3];
        for (int i = 0; i < 3; ++i) {
            M[i] = (double)Ra[3 * i] * x + (double)Ra[3 * i + 1] * y + (double)Ra[3 * i + 2] * z +
                   (double)Da[i];
        }
        rp_real P_a[3], P_b[3];
        to_cam(rig, sp->a, M, P_a);
        to_cam(rig, sp->b, M, P_b);
        if (rp_cam_project(&rig->cam[sp->a].cam, P_a, uv_a, NULL) != RP_OK ||
            rp_cam_project(&rig->cam[sp->b].cam, P_b, uv_b, NULL) != RP_OK ||
            !rp_cam_in_image(&rig->cam[sp->a].cam, uv_a) ||
            !rp_cam_in_image(&rig->cam[sp->b].cam, uv_b) || P_b[2] < RP_C(0.3)) {
            continue;
        }
        Pa[0] = x;
        Pa[1] = y;
        Pa[2] = z;
        return;
    }
    fail_msg("no common point for pair (%d, %d)", sp->a, sp->b);
}

/* x_b^T A x_a for 3x3 A and homogeneous 2-vectors. */
static double bilinear(const rp_real A[9], const double xa[2], const double xb[2])
{
    const double a[3] = {xa[0], xa[1], 1.0}, b[3] = {xb[0], xb[1], 1.0};
    double s = 0;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            s += b[i] * (double)A[3 * i + j] * a[j];
        }
    }
    return s;
}

/* ---- pair init ----------------------------------------------------------------------------- */

static void test_pair_init_front_and_back(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig, 0);
    rp_stereo_pair_t sp;

    /* Given the front pair, then b sits 0.1 m to the right of a, same orientation. */
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
    assert_int_equal(sp.a, 0);
    assert_int_equal(sp.b, 1);
    assert_near(sp.baseline_m, 0.1, RP_TOL(1e-15, 1e-7));
    assert_near(sp.t_ab[0], 0.1, RP_TOL(1e-15, 1e-7));
    assert_near(sp.t_ab[1], 0.0, RP_TOL(1e-15, 1e-7));
    assert_near(sp.t_ab[2], 0.0, RP_TOL(1e-15, 1e-7));
    for (int i = 0; i < 9; ++i) {
        assert_near(sp.R_ab[i], (i % 4 == 0) ? 1.0 : 0.0, RP_TOL(1e-15, 1e-7));
    }

    /* Given the back pair (cam3 looks -z, its x axis is -x1), then D_b - D_a = +0.1 x1 is
     * 0.1 m along cam3's -x: b sits to the left in a's image. */
    assert_ok(rp_stereo_pair_init(&rig, 2, 3, &sp));
    assert_near(sp.baseline_m, 0.1, RP_TOL(1e-15, 1e-7));
    assert_near(sp.t_ab[0], -0.1, RP_TOL(1e-15, 1e-7));
    assert_near(sp.t_ab[1], 0.0, RP_TOL(1e-15, 1e-7));
    assert_near(sp.t_ab[2], 0.0, RP_TOL(1e-15, 1e-7));
    for (int i = 0; i < 9; ++i) {
        assert_near(sp.R_ab[i], (i % 4 == 0) ? 1.0 : 0.0, RP_TOL(1e-15, 1e-7));
    }
}

static void test_pair_init_rejects_bad_pairs(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig, 0);
    rp_stereo_pair_t sp;
    assert_status(rp_stereo_pair_init(&rig, 0, 0, &sp), RP_E_ARG);
    assert_status(rp_stereo_pair_init(&rig, 0, 5, &sp), RP_E_ARG);
    assert_status(rp_stereo_pair_init(NULL, 0, 1, &sp), RP_E_ARG);
    assert_status(rp_stereo_pair_init(&rig, 0, 1, NULL), RP_E_ARG);

    /* Identical cameras (same place): no baseline, no depth. */
    rig.cam[1] = rig.cam[0];
    assert_status(rp_stereo_pair_init(&rig, 0, 1, &sp), RP_E_DEGENERATE);
    /* Under the 1 mm limit too. */
    rig.cam[1].D[0] = RP_C(5e-4);
    assert_status(rp_stereo_pair_init(&rig, 0, 1, &sp), RP_E_DEGENERATE);
}

/* ---- epipolar geometry ----------------------------------------------------------------------- */

static void check_epipolar_pair(const rp_rig_t *rig, uint8_t a, uint8_t b)
{
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(rig, a, b, &sp));
    const rp_camera_t *ca = &rig->cam[a].cam, *cb = &rig->cam[b].cam;
    for (int n = 0; n < 50; ++n) {
        double Pa[3];
        rp_real uv_a[2], uv_b[2];
        make_match(rig, &sp, Pa, uv_a, uv_b);

        /* E on normalised coordinates, F on undistorted pixels: both ~0 (scaled by norms). */
        rp_real xa[2], xb[2];
        assert_ok(rp_cam_unproject(ca, uv_a, xa));
        assert_ok(rp_cam_unproject(cb, uv_b, xb));
        const double na[2] = {(double)xa[0], (double)xa[1]}, nb[2] = {(double)xb[0], (double)xb[1]};
        assert_near(bilinear(sp.E, na, nb), 0.0, RP_TOL(1e-12, 1e-5));
        const double pa[2] = {(double)ca->fx * na[0] + (double)ca->cx,
                              (double)ca->fy * na[1] + (double)ca->cy};
        const double pb[2] = {(double)cb->fx * nb[0] + (double)cb->cx,
                              (double)cb->fy * nb[1] + (double)cb->cy};
        /* F = K_b^-T E K_a^-1: the same value as E on the normalised points. */
        assert_near(bilinear(sp.F, pa, pb), bilinear(sp.E, na, nb), RP_TOL(1e-12, 1e-5));

        /* Then the symmetric distance is ~0 pixels. */
        rp_real d;
        assert_ok(rp_stereo_epipolar_px(rig, &sp, uv_a, uv_b, &d));
        assert_true(d >= RP_C(0.0));
        assert_near(d, 0.0, RP_TOL(1e-8, 2e-3));
    }
}

static void test_epipolar_zero_on_projected_points(void **state)
{
    (void)state;
    rng_state = 11;
    for (int distorted = 0; distorted < 2; ++distorted) {
        rp_rig_t rig;
        make_rig(&rig, distorted);
        check_epipolar_pair(&rig, 0, 1); /* front */
        check_epipolar_pair(&rig, 2, 3); /* back */
        check_epipolar_pair(&rig, 0, 4); /* general position */
        check_epipolar_pair(&rig, 4, 0); /* and the other way round */
    }
}

/* Move uv_b 3 px across its epipolar line (undistorted pixels, no distortion here). */
static void check_off_line(const rp_rig_t *rig, uint8_t a, uint8_t b)
{
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(rig, a, b, &sp));
    for (int n = 0; n < 20; ++n) {
        double Pa[3];
        rp_real uv_a[2], uv_b[2];
        make_match(rig, &sp, Pa, uv_a, uv_b);
        const rp_real *F = sp.F;
        double l[3];
        for (int i = 0; i < 3; ++i) {
            l[i] = (double)F[3 * i] * (double)uv_a[0] + (double)F[3 * i + 1] * (double)uv_a[1] +
                   (double)F[3 * i + 2];
        }
        const double ln = sqrt(l[0] * l[0] + l[1] * l[1]);
        rp_real moved[2] = {(rp_real)((double)uv_b[0] + 3.0 * l[0] / ln),
                            (rp_real)((double)uv_b[1] + 3.0 * l[1] / ln)};
        rp_real d;
        assert_ok(rp_stereo_epipolar_px(rig, &sp, uv_a, moved, &d));
        /* The distance in image b is 3 px; the symmetric distance is at least that. */
        assert_true((double)d >= 3.0 - RP_TOL(1e-6, 2e-2));
        assert_true((double)d < 4.0);
        /* A 1 px gate rejects it. */
        assert_true(d > RP_C(1.0));
    }
}

static void test_epipolar_rejects_point_moved_3px(void **state)
{
    (void)state;
    rng_state = 12;
    rp_rig_t rig;
    make_rig(&rig, 0);
    check_off_line(&rig, 0, 1);
    check_off_line(&rig, 2, 3);
    check_off_line(&rig, 0, 4);

    /* The rectified front pair: epipolar lines are the image rows, so moving v by 3 px gives
     * exactly 3 px in both images. */
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
    const rp_real uv_a[2] = {RP_C(400.0), RP_C(300.0)}, uv_b[2] = {RP_C(320.0), RP_C(303.0)};
    rp_real d;
    assert_ok(rp_stereo_epipolar_px(&rig, &sp, uv_a, uv_b, &d));
    assert_near(d, 3.0, RP_TOL(1e-9, 1e-3));
}

static void test_epipolar_nan_and_args(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig, 0);
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
    const rp_real good[2] = {RP_C(300.0), RP_C(200.0)};
    const rp_real bad[2] = {(rp_real)NAN, RP_C(200.0)};
    const rp_real inf[2] = {RP_C(300.0), (rp_real)INFINITY};
    rp_real d;
    assert_status(rp_stereo_epipolar_px(&rig, &sp, bad, good, &d), RP_E_NAN);
    assert_status(rp_stereo_epipolar_px(&rig, &sp, good, inf, &d), RP_E_NAN);
    assert_status(rp_stereo_epipolar_px(&rig, &sp, good, good, NULL), RP_E_ARG);
    assert_status(rp_stereo_epipolar_px(NULL, &sp, good, good, &d), RP_E_ARG);
    rp_stereo_pair_t broken = sp;
    broken.b = 9;
    assert_status(rp_stereo_epipolar_px(&rig, &broken, good, good, &d), RP_E_ARG);
}

/* ---- triangulation --------------------------------------------------------------------------- */

static void check_triangulation(const rp_rig_t *rig, uint8_t a, uint8_t b, double tol_m)
{
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(rig, a, b, &sp));
    for (int n = 0; n < 50; ++n) {
        double Pt[3];
        rp_real uv_a[2], uv_b[2], P[3], e;
        make_match(rig, &sp, Pt, uv_a, uv_b);
        assert_ok(rp_stereo_triangulate(rig, &sp, uv_a, uv_b, P, &e));
        for (int i = 0; i < 3; ++i) {
            assert_near(P[i], Pt[i], tol_m);
        }
        assert_near(e, 0.0, RP_TOL(1e-8, 2e-3));
        /* reproj_px may be NULL. */
        assert_ok(rp_stereo_triangulate(rig, &sp, uv_a, uv_b, P, NULL));
    }
}

static void test_triangulate_recovers_truth(void **state)
{
    (void)state;
    rng_state = 13;
    const double tol = RP_TOL(1e-9, 2e-5);
    for (int distorted = 0; distorted < 2; ++distorted) {
        rp_rig_t rig;
        make_rig(&rig, distorted);
        check_triangulation(&rig, 0, 1, tol); /* front pair */
        check_triangulation(&rig, 2, 3, tol); /* back pair */
        check_triangulation(&rig, 0, 4, tol); /* general position */
    }
}

/* With pixel noise, Gauss-Newton lowers the reprojection error of the midpoint start and the
 * point stays close to the truth (0.3 px noise at 1 m with a 0.1 m baseline: mm to cm). */
static void test_triangulate_noisy(void **state)
{
    (void)state;
    rng_state = 14;
    rp_rig_t rig;
    make_rig(&rig, 1);
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
    for (int n = 0; n < 50; ++n) {
        double Pt[3];
        rp_real uv_a[2], uv_b[2], P[3], e;
        make_match(&rig, &sp, Pt, uv_a, uv_b);
        for (int i = 0; i < 2; ++i) {
            uv_a[i] += (rp_real)(0.6 * (urand() - 0.5));
            uv_b[i] += (rp_real)(0.6 * (urand() - 0.5));
        }
        assert_ok(rp_stereo_triangulate(&rig, &sp, uv_a, uv_b, P, &e));
        /* The residual is at most the noise that cannot be explained (|noise| <= 0.42 px). */
        assert_true(e <= RP_C(0.45));
        const double dz = (double)P[2] - Pt[2];
        assert_true(fabs(dz) < 0.05 * Pt[2]);
    }
}

static void test_triangulate_behind(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig, 0);
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
    rp_real P[3];
    /* Given a negative disparity (b sees the feature further right than a, though b sits to
     * the right): the rays meet behind the cameras. */
    const rp_real uv_a[2] = {RP_C(300.0), RP_C(240.0)}, uv_b[2] = {RP_C(340.0), RP_C(240.0)};
    assert_status(rp_stereo_triangulate(&rig, &sp, uv_a, uv_b, P, NULL), RP_E_BEHIND);

    /* The back pair: cam3's partner is at -x in cam3's frame, so there a positive disparity
     * u_a - u_b is impossible. */
    assert_ok(rp_stereo_pair_init(&rig, 2, 3, &sp));
    const rp_real ua[2] = {RP_C(340.0), RP_C(240.0)}, ub[2] = {RP_C(300.0), RP_C(240.0)};
    assert_status(rp_stereo_triangulate(&rig, &sp, ua, ub, P, NULL), RP_E_BEHIND);
    /* ...and the mirrored disparity is in front. */
    assert_ok(rp_stereo_triangulate(&rig, &sp, ub, ua, P, NULL));
    assert_near(P[2], 800.0 * 0.1 / 40.0, RP_TOL(1e-9, 1e-4));
}

static void test_triangulate_degenerate(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig, 0);
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
    rp_real P[3];
    /* Zero disparity in a rectified pair: parallel rays, the point is at infinity. */
    const rp_real uv[2] = {RP_C(250.0), RP_C(100.0)};
    assert_status(rp_stereo_triangulate(&rig, &sp, uv, uv, P, NULL), RP_E_DEGENERATE);

    /* Identical cameras never make a pair; a pair struct forced onto them is degenerate too. */
    rp_rig_t same;
    make_rig(&same, 0);
    same.cam[1] = same.cam[0];
    assert_status(rp_stereo_pair_init(&same, 0, 1, &sp), RP_E_DEGENERATE);
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
    sp.t_ab[0] = RP_C(0.0);
    const rp_real uv_b[2] = {RP_C(200.0), RP_C(100.0)};
    assert_true(rp_stereo_triangulate(&same, &sp, uv, uv_b, P, NULL) != RP_OK);
}

static void test_triangulate_nan_and_args(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig, 0);
    rp_stereo_pair_t sp;
    assert_ok(rp_stereo_pair_init(&rig, 0, 1, &sp));
    const rp_real good_a[2] = {RP_C(400.0), RP_C(240.0)}, good_b[2] = {RP_C(320.0), RP_C(240.0)};
    const rp_real bad[2] = {RP_C(400.0), (rp_real)NAN};
    rp_real P[3];
    assert_status(rp_stereo_triangulate(&rig, &sp, bad, good_b, P, NULL), RP_E_NAN);
    assert_status(rp_stereo_triangulate(&rig, &sp, good_a, bad, P, NULL), RP_E_NAN);
    assert_status(rp_stereo_triangulate(&rig, &sp, good_a, good_b, NULL, NULL), RP_E_ARG);
    assert_status(rp_stereo_triangulate(&rig, NULL, good_a, good_b, P, NULL), RP_E_ARG);
    /* The good match: disparity 80 px at f = 800, B = 0.1 m: depth 1 m. */
    assert_ok(rp_stereo_triangulate(&rig, &sp, good_a, good_b, P, NULL));
    assert_near(P[2], 1.0, RP_TOL(1e-12, 1e-5));
    assert_near(P[0], (400.0 - 319.5) / 800.0, RP_TOL(1e-12, 1e-5));
    assert_near(P[1], (240.0 - 239.5) / 800.0, RP_TOL(1e-12, 1e-5));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pair_init_front_and_back),
        cmocka_unit_test(test_pair_init_rejects_bad_pairs),
        cmocka_unit_test(test_epipolar_zero_on_projected_points),
        cmocka_unit_test(test_epipolar_rejects_point_moved_3px),
        cmocka_unit_test(test_epipolar_nan_and_args),
        cmocka_unit_test(test_triangulate_recovers_truth),
        cmocka_unit_test(test_triangulate_noisy),
        cmocka_unit_test(test_triangulate_behind),
        cmocka_unit_test(test_triangulate_degenerate),
        cmocka_unit_test(test_triangulate_nan_and_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
