/*
 * test_p3p.c - Lambda Twist P3P (rp_p3p_solve): the true pose is among the solutions on random
 * noise-free configurations, every solution explains the three bearings, degenerate input is
 * refused, near-degenerate input gives finite answers.
 *
 * Random configuration: camera rotation uniform (rotation vector, angle up to pi), camera
 * centre in a 10 m box, three points at depths 0.5..20 m inside a 120-degree cone around the
 * optical axis (wide-angle to narrow-baseline triangles, as RANSAC draws them).
 */
#include "rp_test.h"

#include <string.h>

#include "rigpose/rp_p3p.h"
#include "rigpose/rp_rot.h"

#define N_TRIALS 20000

/* Tolerances. Double: every trial's true pose within TOL_LOOSE, 99.9 % within TOL_TIGHT (measured
 * here: 100 % within 1e-9, worst 5.5e-10, over 2 x 20000 trials). Float: 24-bit arithmetic
 * through a cubic, a 3x3 eigenproblem and Gauss-Newton on squared distances; near-double
 * solutions (two points ~0.5 m from the camera, the third 20 m away: the cubic's root nearly
 * triple, known only to eps^(1/3)) are found poorly or not at all. Measured: 99.1-99.7 % within
 * 2e-3, 0.1-0.2 % of trials without a solution, the worst bearing error of an accepted solution
 * 0.05 rad in such cases. RANSAC draws another sample there; the float bounds below are those
 * figures with a margin. */
#define TOL_TIGHT RP_TOL(1e-9, 2e-3)
#define TOL_LOOSE RP_TOL(1e-6, 5e-2)
#define MIN_TIGHT_FRAC RP_TOL(0.999, 0.985)
#define MIN_LOOSE_FRAC RP_TOL(1.0, 0.995)
#define MAX_NOSOL_FRAC RP_TOL(0.0, 0.004)
#define BEARING_TOL RP_TOL(1e-6, 1e-3)       /* rad */
#define MAX_BAD_BEARING_FRAC RP_TOL(0.0, 0.004)

typedef struct {
    double R[9], t[3];       /* world -> camera, true */
    rp_real y[3][3], X[3][3];
    double depth_mean;       /* m */
} config_t;

static void rand_unit(double v[3])
{
    double n;
    do {
        for (int i = 0; i < 3; ++i) v[i] = rp_test_urand(-1.0, 1.0);
        n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    } while (n > 1.0 || n < 1e-3);
    for (int i = 0; i < 3; ++i) v[i] /= n;
}

static void make_config(config_t *c, double cone_half_deg)
{
    double ax[3];
    rand_unit(ax);
    const double ang = rp_test_urand(0.0, 3.14159);
    rp_real w[3], R[9];
    for (int i = 0; i < 3; ++i) w[i] = (rp_real)(ax[i] * ang);
    rp_rot_exp(w, R);
    double C[3]; /* camera centre in the world */
    for (int i = 0; i < 9; ++i) c->R[i] = (double)R[i];
    for (int i = 0; i < 3; ++i) C[i] = rp_test_urand(-5.0, 5.0);
    for (int i = 0; i < 3; ++i) /* t = -R C */
        c->t[i] = -(c->R[3 * i] * C[0] + c->R[3 * i + 1] * C[1] + c->R[3 * i + 2] * C[2]);
    const double cmin = cos(cone_half_deg * 3.14159265358979323846 / 180.0);
    c->depth_mean = 0.0;
    for (int k = 0; k < 3; ++k) {
        double d[3];
        do {
            rand_unit(d);
        } while (d[2] < cmin);
        const double r = rp_test_urand(0.5, 20.0);
        c->depth_mean += r / 3.0;
        double Pc[3] = {r * d[0], r * d[1], r * d[2]};
        for (int i = 0; i < 3; ++i) {
            c->y[k][i] = (rp_real)d[i];
            /* X = R^T (Pc - t) */
            c->X[k][i] = (rp_real)(c->R[i] * (Pc[0] - c->t[0]) + c->R[3 + i] * (Pc[1] - c->t[1]) +
                                   c->R[6 + i] * (Pc[2] - c->t[2]));
        }
    }
}

/* Pose error of one solution: max(rotation Frobenius distance, |t - t_true| / mean depth). */
static double pose_err(const rp_p3p_pose_t *s, const config_t *c)
{
    double er = 0.0, et = 0.0;
    for (int i = 0; i < 9; ++i) er += ((double)s->R[i] - c->R[i]) * ((double)s->R[i] - c->R[i]);
    for (int i = 0; i < 3; ++i) et += ((double)s->t[i] - c->t[i]) * ((double)s->t[i] - c->t[i]);
    er = sqrt(er);
    et = sqrt(et) / c->depth_mean;
    return er > et ? er : et;
}

/* Largest angle (rad) between a bearing and the ray of its point under solution s. */
static double bearing_err(const rp_p3p_pose_t *s, const config_t *c)
{
    double worst = 0.0;
    for (int k = 0; k < 3; ++k) {
        double P[3], n = 0.0, dt = 0.0, ny = 0.0;
        for (int i = 0; i < 3; ++i) {
            P[i] = (double)s->t[i];
            for (int j = 0; j < 3; ++j) P[i] += (double)s->R[3 * i + j] * (double)c->X[k][j];
            n += P[i] * P[i];
            ny += (double)c->y[k][i] * (double)c->y[k][i];
        }
        for (int i = 0; i < 3; ++i) dt += P[i] * (double)c->y[k][i];
        double cs = dt / sqrt(n * ny);
        cs = cs > 1.0 ? 1.0 : cs;
        const double a = acos(cs);
        worst = a > worst ? a : worst;
    }
    return worst;
}

static void check_random(double cone_half_deg, const char *label)
{
    int tight = 0, loose = 0, bad_bearing = 0, n_sols = 0, hist[RP_P3P_MAX_SOLS + 1] = {0};
    double worst = 0.0, worst_bearing = 0.0;
    for (int trial = 0; trial < N_TRIALS; ++trial) {
        config_t c;
        make_config(&c, cone_half_deg);
        rp_p3p_pose_t sol[RP_P3P_MAX_SOLS];
        uint8_t ns = 99;
        assert_ok(rp_p3p_solve((const rp_real(*)[3])c.y, (const rp_real(*)[3])c.X, sol, &ns));
        assert_true(ns <= RP_P3P_MAX_SOLS);
        hist[ns]++;
        double best = 1e300;
        for (int s = 0; s < ns; ++s) {
            /* every solution: a rotation, the bearings explained */
            rp_real I[9];
            rp_rot_mul_a_bt(sol[s].R, sol[s].R, I);
            for (int i = 0; i < 9; ++i)
                assert_near(I[i], (i % 4 == 0) ? 1.0 : 0.0, RP_TOL(1e-12, 1e-5));
            const double be = bearing_err(&sol[s], &c);
            worst_bearing = be > worst_bearing ? be : worst_bearing;
            bad_bearing += be > BEARING_TOL;
            ++n_sols;
            const double e = pose_err(&sol[s], &c);
            best = e < best ? e : best;
        }
        tight += best <= TOL_TIGHT;
        loose += best <= TOL_LOOSE;
        if (ns > 0) worst = best > worst ? best : worst;
    }
    print_message("%s: %d trials, true pose within %.0e in %.3f %%, within %.0e in %.3f %%, "
                  "worst %.2e; worst bearing error of any solution %.2e rad (%d of %d over "
                  "%.0e); solutions 0:%d 1:%d 2:%d 3:%d 4:%d\n",
                  label, N_TRIALS, TOL_TIGHT, 100.0 * tight / N_TRIALS, TOL_LOOSE,
                  100.0 * loose / N_TRIALS, worst, worst_bearing, bad_bearing, n_sols,
                  BEARING_TOL, hist[0], hist[1], hist[2], hist[3], hist[4]);
    assert_true((double)tight >= MIN_TIGHT_FRAC * N_TRIALS);
    assert_true((double)loose >= MIN_LOOSE_FRAC * N_TRIALS);
    assert_true((double)hist[0] <= MAX_NOSOL_FRAC * N_TRIALS); /* the truth always exists */
    assert_true((double)bad_bearing <= MAX_BAD_BEARING_FRAC * n_sols);
}

/* Given random noise-free configurations in a 120-degree cone, then the truth is among the
 * solutions. */
static void test_random_wide(void **state)
{
    (void)state;
    check_random(60.0, "wide (120 deg cone)");
}

/* Given narrow fields of view (a 20-degree cone: the paper's rig sees 44 x 33 degrees), then the
 * same. */
static void test_random_narrow(void **state)
{
    (void)state;
    check_random(10.0, "narrow (20 deg cone)");
}

/* A hand-made configuration with a known answer: identity pose, points on the axes. */
static void test_known_pose(void **state)
{
    (void)state;
    const rp_real X[3][3] = {{1, 0, 5}, {0, 1, 4}, {-1, -1, 6}};
    rp_real y[3][3];
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i) y[k][i] = X[k][i]; /* R = I, t = 0: unnormalised bearings */
    rp_p3p_pose_t sol[RP_P3P_MAX_SOLS];
    uint8_t ns = 0;
    assert_ok(rp_p3p_solve((const rp_real(*)[3])y, X, sol, &ns));
    int found = 0;
    for (int s = 0; s < ns; ++s) {
        double e = 0.0;
        for (int i = 0; i < 9; ++i) e += fabs((double)sol[s].R[i] - ((i % 4 == 0) ? 1.0 : 0.0));
        for (int i = 0; i < 3; ++i) e += fabs((double)sol[s].t[i]);
        if (e < RP_TOL(1e-9, 1e-3)) found = 1;
    }
    assert_true(found);
}

/* Degenerate inputs are refused with RP_E_DEGENERATE; NaN with RP_E_NAN; NULL with RP_E_ARG. */
static void test_degenerate_refused(void **state)
{
    (void)state;
    rp_p3p_pose_t sol[RP_P3P_MAX_SOLS];
    uint8_t ns = 7;
    const rp_real y[3][3] = {{0.1f, 0, 1}, {0, 0.1f, 1}, {-0.1f, 0, 1}};
    const rp_real Xc[3][3] = {{0, 0, 1}, {1, 1, 2}, {2, 2, 3}}; /* collinear */
    assert_status(rp_p3p_solve(y, Xc, sol, &ns), RP_E_DEGENERATE);
    assert_int_equal(ns, 0);
    const rp_real Xs[3][3] = {{0, 0, 1}, {0, 0, 1}, {1, 0, 2}}; /* two coincide */
    assert_status(rp_p3p_solve(y, Xs, sol, &ns), RP_E_DEGENERATE);
    const rp_real X[3][3] = {{0.1f, 0, 1}, {0, 0.1f, 1}, {-0.1f, 0, 1}};
    const rp_real ysame[3][3] = {{0.1f, 0, 1}, {0.2f, 0, 2}, {-0.1f, 0, 1}}; /* one ray */
    assert_status(rp_p3p_solve(ysame, X, sol, &ns), RP_E_DEGENERATE);
    const rp_real yzero[3][3] = {{0, 0, 0}, {0, 0.1f, 1}, {-0.1f, 0, 1}};
    assert_status(rp_p3p_solve(yzero, X, sol, &ns), RP_E_DEGENERATE);
    rp_real ynan[3][3];
    memcpy(ynan, y, sizeof ynan);
    ynan[1][2] = (rp_real)NAN;
    assert_status(rp_p3p_solve((const rp_real(*)[3])ynan, X, sol, &ns), RP_E_NAN);
    rp_real Xinf[3][3];
    memcpy(Xinf, X, sizeof Xinf);
    Xinf[2][0] = (rp_real)INFINITY;
    assert_status(rp_p3p_solve(y, (const rp_real(*)[3])Xinf, sol, &ns), RP_E_NAN);
    assert_status(rp_p3p_solve(NULL, X, sol, &ns), RP_E_ARG);
    assert_status(rp_p3p_solve(y, X, NULL, &ns), RP_E_ARG);
    assert_status(rp_p3p_solve(y, X, sol, NULL), RP_E_ARG);
}

/* Nearly collinear points and nearly parallel rays (just above the refusal limits) give finite
 * solutions that explain the bearings, or none: never NaN, never a crash. */
static void test_near_degenerate_finite(void **state)
{
    (void)state;
    for (int trial = 0; trial < 2000; ++trial) {
        config_t c;
        make_config(&c, trial % 2 ? 1.0 : 60.0);
        /* pull point 3 towards the line through points 1 and 2 (world and bearing alike) */
        const double f = rp_test_urand(0.0, 1.0), eps = pow(10.0, rp_test_urand(-7.0, -2.0));
        double P[3][3];
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 3; ++i) {
                P[k][i] = c.t[i];
                for (int j = 0; j < 3; ++j) P[k][i] += c.R[3 * i + j] * (double)c.X[k][j];
            }
        for (int i = 0; i < 3; ++i) {
            const double on = P[0][i] + f * (P[1][i] - P[0][i]);
            P[2][i] = on + eps * (P[2][i] - on);
        }
        for (int i = 0; i < 3; ++i) {
            c.X[2][i] = (rp_real)(c.R[i] * (P[2][0] - c.t[0]) + c.R[3 + i] * (P[2][1] - c.t[1]) +
                                  c.R[6 + i] * (P[2][2] - c.t[2]));
            c.y[2][i] = (rp_real)P[2][i];
        }
        rp_p3p_pose_t sol[RP_P3P_MAX_SOLS];
        uint8_t ns = 0;
        rp_status_t st = rp_p3p_solve((const rp_real(*)[3])c.y, (const rp_real(*)[3])c.X, sol, &ns);
        assert_true(st == RP_OK || st == RP_E_DEGENERATE);
        for (int s = 0; s < ns; ++s) {
            for (int i = 0; i < 9; ++i) assert_true(isfinite((double)sol[s].R[i]));
            for (int i = 0; i < 3; ++i) assert_true(isfinite((double)sol[s].t[i]));
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_pose),
        cmocka_unit_test(test_random_wide),
        cmocka_unit_test(test_random_narrow),
        cmocka_unit_test(test_degenerate_refused),
        cmocka_unit_test(test_near_degenerate_finite),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
