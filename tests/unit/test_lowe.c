/*
 * test_lowe.c - Lowe's method (rp_lowe_solve): the rig pose from 2-D/3-D correspondences.
 *
 * Rig (the paper's non-overlapping layout, 640x480, fx = fy = 800 px, centred principal point):
 *   0: cam1 at the origin looking +z (R = I)
 *   1: cam2 at (0.0866, 0, -0.05) looking +x (R = Ry(+pi/2))
 *   2: cam3 at (0, 0, -0.1) looking -z (R = Ry(pi))
 *   3: cam4 at (-0.0866, 0, -0.05) looking -x (R = Ry(-pi/2))
 * Points: uniform in the spherical shell of radii 0.667..1 m around the rig (Table 1 protocol),
 * kept when at least 0.05 m in front of a camera and inside its image.
 */
#include "rp_test.h"

#include <string.h>

#include "rigpose/rp_camera.h"
#include "rigpose/rp_lowe.h"
#include "rigpose/rp_obs.h"
#include "rigpose/rp_rig.h"
#include "rigpose/rp_rot.h"

#define MAX_OBS 512

/* ---- fixtures ------------------------------------------------------------------------------ */

static uint64_t rng_state;

static double urand(void) /* uniform in [0, 1) */
{
    rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static double gauss(void) /* standard normal (Box-Muller) */
{
    double u = urand();
    while (u <= 0.0) {
        u = urand();
    }
    return sqrt(-2.0 * log(u)) * cos(2.0 * 3.14159265358979323846 * urand());
}

/* R = Ry(th), computed in double then rounded once; exact 0/1 where they are. */
static void set_ry(rp_real R[9], double th)
{
    const double c = cos(th), s = sin(th);
    const double M[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
    for (int i = 0; i < 9; ++i) {
        R[i] = (rp_real)(fabs(M[i]) < 1e-15 ? 0.0 : M[i]);
    }
}

static void set_D(rp_real D[3], double x, double y, double z)
{
    D[0] = (rp_real)x;
    D[1] = (rp_real)y;
    D[2] = (rp_real)z;
}

static void make_rig(rp_rig_t *rig)
{
    memset(rig, 0, sizeof *rig);
    rig->n_cams = 4;
    for (int k = 0; k < 4; ++k) {
        rig->cam[k].cam = rp_cam_pinhole(640, 480, RP_C(800.0), RP_C(800.0), RP_C(319.5),
                                         RP_C(239.5));
    }
    set_ry(rig->cam[0].R, 0.0);
    set_D(rig->cam[0].D, 0, 0, 0);
    set_ry(rig->cam[1].R, 3.14159265358979323846 / 2);
    set_D(rig->cam[1].D, 0.0866, 0, -0.05);
    set_ry(rig->cam[2].R, 3.14159265358979323846);
    set_D(rig->cam[2].D, 0, 0, -0.1);
    set_ry(rig->cam[3].R, -3.14159265358979323846 / 2);
    set_D(rig->cam[3].D, -0.0866, 0, -0.05);
}

static const rp_real p_true[6] = {RP_C(0.05), RP_C(-0.02), RP_C(0.03),
                                  RP_C(0.10), RP_C(-0.05), RP_C(0.20)};

/* Up to per_cam noise-free observations in each camera listed in cams (n_c of them) at pose p;
 * pixel noise sigma_px (0 for none). Returns the count. */
static uint32_t make_obs(const rp_rig_t *rig, const rp_real p[6], const uint8_t *cams, int n_c,
                         int per_cam, double sigma_px, rp_obs_t *obs)
{
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p));
    uint32_t n = 0;
    for (int c = 0; c < n_c; ++c) {
        int got = 0;
        for (int tries = 0; tries < 200000 && got < per_cam; ++tries) {
            /* Uniform in the shell: direction uniform on the sphere, r^3 uniform. */
            const double z = 2.0 * urand() - 1.0, phi = 2.0 * 3.14159265358979323846 * urand();
            const double r0 = 0.667, r1 = 1.0;
            const double r = cbrt(r0 * r0 * r0 + urand() * (r1 * r1 * r1 - r0 * r0 * r0));
            const double s = sqrt(1.0 - z * z);
            rp_obs_t o;
            o.M[0] = p[0] + (rp_real)(r * s * cos(phi));
            o.M[1] = p[1] + (rp_real)(r * s * sin(phi));
            o.M[2] = p[2] + (rp_real)(r * z);
            o.cam = cams[c];
            o.w = RP_C(1.0);
            rp_real P[3];
            assert_ok(rp_rig_cam_point(rig, o.cam, &pl, o.M, P));
            if (P[2] < RP_C(0.05) ||
                rp_rig_project(rig, o.cam, &pl, o.M, o.uv, NULL, NULL) != RP_OK ||
                !rp_cam_in_image(&rig->cam[o.cam].cam, o.uv)) {
                continue;
            }
            o.uv[0] += (rp_real)(sigma_px * gauss());
            o.uv[1] += (rp_real)(sigma_px * gauss());
            obs[n++] = o;
            ++got;
        }
        assert_int_equal(got, per_cam);
    }
    return n;
}

/* A start rot_deg degrees (rotation about a skew axis) and trans_m metres off the truth. */
static void make_start(const rp_real truth[6], double rot_deg, double trans_m, rp_real p[6])
{
    const double ax[3] = {1.0, 2.0, -1.5}, tx[3] = {-1.0, 0.5, 2.0};
    const double na = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    const double nt = sqrt(tx[0] * tx[0] + tx[1] * tx[1] + tx[2] * tx[2]);
    rp_real w[3], dR[9], R[9], Rs[9];
    for (int i = 0; i < 3; ++i) {
        w[i] = (rp_real)(ax[i] / na * rot_deg * 3.14159265358979323846 / 180.0);
        p[i] = truth[i] + (rp_real)(tx[i] / nt * trans_m);
    }
    rp_rot_exp(w, dR);
    rp_rot_from_angles(&truth[3], R);
    rp_rot_mul(R, dR, Rs);
    assert_ok(rp_rot_to_angles(Rs, &p[3]));
    assert_near(rp_rot_distance(R, Rs), rot_deg * 3.14159265358979323846 / 180.0,
                RP_TOL(1e-12, 1e-4));
}

static void assert_pose_near(const rp_real p[6], const rp_real q[6], double tol)
{
    for (int i = 0; i < 6; ++i) {
        assert_near(p[i], q[i], tol);
    }
}

/* ---- noise-free ---------------------------------------------------------------------------- */

static void test_four_cameras_recover_pose(void **state)
{
    (void)state;
    rng_state = 21;
    rp_rig_t rig;
    make_rig(&rig);
    static rp_obs_t obs[MAX_OBS];
    const uint8_t cams[4] = {0, 1, 2, 3};
    const uint32_t n = make_obs(&rig, p_true, cams, 4, 15, 0.0, obs);

    /* Given a start 10 degrees and 5 cm off, then the pose comes back to rounding. */
    rp_real p[6], rms, cov[36];
    make_start(p_true, 10.0, 0.05, p);
    const rp_lowe_params_t prm = rp_lowe_default_params();
    assert_ok(rp_lowe_solve(&rig, obs, n, &prm, p, &rms, cov));
    assert_pose_near(p, p_true, RP_TOL(1e-9, 1e-5));
    assert_near(rms, 0.0, RP_TOL(1e-7, 1e-4));

    /* The covariance: symmetric with a positive diagonal. */
    for (int i = 0; i < 6; ++i) {
        assert_true(cov[7 * i] > RP_C(0.0));
        for (int j = 0; j < 6; ++j) {
            assert_near(cov[6 * i + j], cov[6 * j + i], 1e-12 + 1e-6 * fabs((double)cov[7 * i]));
        }
    }

    /* NULL parameters mean the defaults; rms and cov may be NULL. */
    make_start(p_true, 10.0, 0.05, p);
    assert_ok(rp_lowe_solve(&rig, obs, n, NULL, p, NULL, NULL));
    assert_pose_near(p, p_true, RP_TOL(1e-9, 1e-5));
}

static void test_defaults(void **state)
{
    (void)state;
    const rp_lowe_params_t prm = rp_lowe_default_params();
    assert_int_equal(prm.max_iter, 30);
    assert_near(prm.tol_step, RP_TOL(1e-10, 1e-6), RP_TOL(1e-20, 1e-12));
}

static void test_single_camera(void **state)
{
    (void)state;
    rng_state = 22;
    rp_rig_t rig;
    make_rig(&rig);
    static rp_obs_t obs[MAX_OBS];
    rp_real p[6];

    /* Each camera of the rig alone, including the side cameras (off cam1's centre). */
    for (uint8_t k = 0; k < 4; ++k) {
        const uint32_t n = make_obs(&rig, p_true, &k, 1, 20, 0.0, obs);
        make_start(p_true, 10.0, 0.05, p);
        assert_ok(rp_lowe_solve(&rig, obs, n, NULL, p, NULL, NULL));
        assert_pose_near(p, p_true, RP_TOL(1e-9, 2e-5));
    }

    /* A one-camera rig. */
    rig.n_cams = 1;
    const uint8_t k0 = 0;
    const uint32_t n = make_obs(&rig, p_true, &k0, 1, 20, 0.0, obs);
    make_start(p_true, 10.0, 0.05, p);
    assert_ok(rp_lowe_solve(&rig, obs, n, NULL, p, NULL, NULL));
    assert_pose_near(p, p_true, RP_TOL(1e-9, 2e-5));
}

/* ---- failures ------------------------------------------------------------------------------ */

static void test_too_few(void **state)
{
    (void)state;
    rng_state = 23;
    rp_rig_t rig;
    make_rig(&rig);
    static rp_obs_t obs[MAX_OBS];
    const uint8_t k = 0;
    make_obs(&rig, p_true, &k, 1, 3, 0.0, obs);
    rp_real p[6];
    memcpy(p, p_true, sizeof p);
    assert_status(rp_lowe_solve(&rig, obs, 2, NULL, p, NULL, NULL), RP_E_TOO_FEW);
    assert_status(rp_lowe_solve(&rig, NULL, 0, NULL, p, NULL, NULL), RP_E_TOO_FEW);
    /* Three observations, one with zero weight: only two count. */
    obs[2].w = RP_C(0.0);
    assert_status(rp_lowe_solve(&rig, obs, 3, NULL, p, NULL, NULL), RP_E_TOO_FEW);
}

/* Points on one line do not fix the pose (rotation about that line): an error, not a pose. */
static void test_collinear_points_are_singular(void **state)
{
    (void)state;
    rp_rig_t rig;
    make_rig(&rig);
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p_true));
    static rp_obs_t obs[MAX_OBS];
    /* Points along a line in cam1's view, about 0.8 m away (built in cam1's frame). */
    for (int npts = 3; npts <= 12; npts += 9) {
        for (int i = 0; i < npts; ++i) {
            const rp_real P[3] = {RP_C(-0.2) + RP_C(0.04) * (rp_real)i,
                                  RP_C(0.1) - RP_C(0.015) * (rp_real)i,
                                  RP_C(0.8) + RP_C(0.01) * (rp_real)i};
            assert_ok(rp_rig_world_point(&rig, 0, &pl, P, obs[i].M));
            assert_ok(rp_rig_project(&rig, 0, &pl, obs[i].M, obs[i].uv, NULL, NULL));
            obs[i].w = RP_C(1.0);
            obs[i].cam = 0;
        }
        rp_real p[6];
        make_start(p_true, 3.0, 0.01, p);
        const rp_status_t st = rp_lowe_solve(&rig, obs, (uint32_t)npts, NULL, p, NULL, NULL);
        assert_status(st, RP_E_SINGULAR);
        for (int i = 0; i < 6; ++i) {
            assert_true(isfinite((double)p[i]));
        }
    }
}

static void test_nan_and_args(void **state)
{
    (void)state;
    rng_state = 24;
    rp_rig_t rig;
    make_rig(&rig);
    static rp_obs_t obs[MAX_OBS];
    const uint8_t k = 0;
    const uint32_t n = make_obs(&rig, p_true, &k, 1, 10, 0.0, obs);
    rp_real p[6];
    memcpy(p, p_true, sizeof p);

    obs[4].uv[1] = (rp_real)NAN;
    assert_status(rp_lowe_solve(&rig, obs, n, NULL, p, NULL, NULL), RP_E_NAN);
    obs[4].uv[1] = RP_C(100.0);
    obs[5].M[2] = (rp_real)INFINITY;
    assert_status(rp_lowe_solve(&rig, obs, n, NULL, p, NULL, NULL), RP_E_NAN);
    obs[5].M[2] = RP_C(1.0);
    p[3] = (rp_real)NAN;
    assert_status(rp_lowe_solve(&rig, obs, n, NULL, p, NULL, NULL), RP_E_NAN);
    memcpy(p, p_true, sizeof p);

    assert_status(rp_lowe_solve(NULL, obs, n, NULL, p, NULL, NULL), RP_E_ARG);
    assert_status(rp_lowe_solve(&rig, obs, n, NULL, NULL, NULL, NULL), RP_E_ARG);
    obs[1].cam = 7; /* no such camera */
    assert_status(rp_lowe_solve(&rig, obs, n, NULL, p, NULL, NULL), RP_E_ARG);
    obs[1].cam = 0;
    obs[1].w = RP_C(-1.0);
    assert_status(rp_lowe_solve(&rig, obs, n, NULL, p, NULL, NULL), RP_E_ARG);
    obs[1].w = RP_C(1.0);
    rp_lowe_params_t prm = rp_lowe_default_params();
    prm.max_iter = 0;
    assert_status(rp_lowe_solve(&rig, obs, n, &prm, p, NULL, NULL), RP_E_ARG);
}

/* The iteration limit: RP_E_NO_CONVERGE, with p the best pose found (better than the start). */
static void test_iteration_limit(void **state)
{
    (void)state;
    rng_state = 25;
    rp_rig_t rig;
    make_rig(&rig);
    static rp_obs_t obs[MAX_OBS];
    const uint8_t cams[4] = {0, 1, 2, 3};
    const uint32_t n = make_obs(&rig, p_true, cams, 4, 10, 0.0, obs);
    rp_real p[6], p0[6];
    make_start(p_true, 10.0, 0.05, p);
    memcpy(p0, p, sizeof p);
    rp_lowe_params_t prm = rp_lowe_default_params();
    prm.max_iter = 1;
    assert_status(rp_lowe_solve(&rig, obs, n, &prm, p, NULL, NULL), RP_E_NO_CONVERGE);
    double e0 = 0, e1 = 0;
    for (int i = 0; i < 6; ++i) {
        e0 += fabs((double)(p0[i] - p_true[i]));
        e1 += fabs((double)(p[i] - p_true[i]));
    }
    assert_true(e1 < 0.5 * e0);
}

/* ---- robustness of the bookkeeping -------------------------------------------------------- */

/* Zero-weight observations are ignored, and observations behind their camera are skipped. */
static void test_zero_weight_and_behind_are_skipped(void **state)
{
    (void)state;
    rng_state = 26;
    rp_rig_t rig;
    make_rig(&rig);
    static rp_obs_t obs[MAX_OBS];
    const uint8_t cams[2] = {0, 2};
    uint32_t n = make_obs(&rig, p_true, cams, 2, 12, 0.0, obs);

    /* A gross outlier with zero weight. */
    obs[n] = obs[0];
    obs[n].uv[0] += RP_C(150.0);
    obs[n].w = RP_C(0.0);
    ++n;
    /* A point behind cam1 (it is in front of cam3, but attributed to cam1). */
    obs[n] = obs[n - 1];
    obs[n].w = RP_C(1.0);
    obs[n].cam = 0;
    {
        rp_pose_lin_t pl;
        const rp_real P[3] = {RP_C(0.1), RP_C(0.0), RP_C(-0.7)};
        assert_ok(rp_pose_lin_set(&pl, p_true));
        assert_ok(rp_rig_world_point(&rig, 0, &pl, P, obs[n].M));
    }
    ++n;

    rp_real p[6], rms;
    make_start(p_true, 10.0, 0.05, p);
    assert_ok(rp_lowe_solve(&rig, obs, n, NULL, p, &rms, NULL));
    assert_pose_near(p, p_true, RP_TOL(1e-9, 1e-5));
    assert_near(rms, 0.0, RP_TOL(1e-7, 1e-4));
}

/* ---- noise ----------------------------------------------------------------------------------- */

/* Given 0.5 px Gaussian noise, then the RMS residual is about the noise and the pose error is
 * within a few standard deviations of the returned covariance. */
static void test_noisy_rms_and_covariance(void **state)
{
    (void)state;
    rng_state = 27;
    rp_rig_t rig;
    make_rig(&rig);
    static rp_obs_t obs[MAX_OBS];
    const uint8_t cams[4] = {0, 1, 2, 3};
    const double sigma = 0.5;
    for (int run = 0; run < 5; ++run) {
        const uint32_t n = make_obs(&rig, p_true, cams, 4, 50, sigma, obs);
        rp_real p[6], rms, cov[36];
        make_start(p_true, 10.0, 0.05, p);
        assert_ok(rp_lowe_solve(&rig, obs, n, NULL, p, &rms, cov));
        /* 400 residuals, 6 parameters: E[rms^2] = sigma^2 (394 / 400). */
        assert_true(rms > RP_C(0.43) && rms < RP_C(0.57));
        for (int i = 0; i < 6; ++i) {
            const double sd = sigma * sqrt((double)cov[7 * i]);
            assert_true(sd > 0.0 && sd < 0.01);
            if (!(fabs((double)(p[i] - p_true[i])) < 5.0 * sd)) {
                fail_msg("run %d: p[%d] off by %g, sd %g", run, i,
                         (double)(p[i] - p_true[i]), sd);
            }
        }
    }

    /* Weights: doubling every weight changes nothing but cov (halved). */
    const uint32_t n = make_obs(&rig, p_true, cams, 4, 30, sigma, obs);
    rp_real p1[6], p2[6], c1[36], c2[36], r1, r2;
    make_start(p_true, 5.0, 0.02, p1);
    memcpy(p2, p1, sizeof p1);
    assert_ok(rp_lowe_solve(&rig, obs, n, NULL, p1, &r1, c1));
    for (uint32_t i = 0; i < n; ++i) {
        obs[i].w = RP_C(2.0);
    }
    assert_ok(rp_lowe_solve(&rig, obs, n, NULL, p2, &r2, c2));
    assert_pose_near(p1, p2, RP_TOL(1e-9, 1e-4));
    assert_near(r1, r2, RP_TOL(1e-9, 1e-4));
    for (int i = 0; i < 6; ++i) {
        assert_near(c2[7 * i], 0.5 * (double)c1[7 * i], 1e-3 * (double)c1[7 * i]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_four_cameras_recover_pose),
        cmocka_unit_test(test_single_camera),
        cmocka_unit_test(test_too_few),
        cmocka_unit_test(test_collinear_points_are_singular),
        cmocka_unit_test(test_nan_and_args),
        cmocka_unit_test(test_iteration_limit),
        cmocka_unit_test(test_zero_weight_and_behind_are_skipped),
        cmocka_unit_test(test_noisy_rms_and_covariance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
