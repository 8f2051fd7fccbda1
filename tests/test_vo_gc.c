/*
 * test_vo_gc.c - the generalised camera (gc) end to end on the paper's simulation, with the
 * four single cameras (front, right, back, left): accuracy against the paper's "2 cameras"
 * row, consistency of the pose covariance (3-sigma fraction, NEES), top-up of features, cameras
 * going dark, malformed frame sets and bad configuration.
 */
#include <stdlib.h>
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_linalg.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_vo_gc.h"
#include "rp_sim.h"

typedef struct {
    rp_sim_run_t sr;
    rp_frameset_t fs;
    rp_vo_gc_t vo;
    rp_estimate_t est;
} fixture_t;

static fixture_t *fixture(double noise_px, uint32_t frames, uint32_t run)
{
    fixture_t *fx = calloc(1, sizeof(*fx));
    assert_non_null(fx);
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.noise_px = noise_px;
    cfg.n_frames = frames;
    assert_int_equal(rp_sim_run_init(&fx->sr, &cfg, 11, run), 0);
    return fx;
}

static void fixture_free(fixture_t *fx)
{
    rp_sim_run_free(&fx->sr);
    free(fx);
}

/* The simulator's configuration of gc: cam1..cam4, the shell's mid depth. */
static rp_vo_gc_cfg_t gc_cfg(double noise_px)
{
    rp_vo_gc_cfg_t c = rp_vo_gc_default_cfg();
    c.n_cams = 4;
    c.cams[0] = RP_SIM_CAM1;
    c.cams[1] = RP_SIM_CAM2;
    c.cams[2] = RP_SIM_CAM3;
    c.cams[3] = RP_SIM_CAM4;
    c.init_depth_m = RP_C(0.8335);
    c.init_depth_sigma_m = RP_C(0.15);
    c.init_on_sphere = 1;
    c.ekf.sigma_px = noise_px > 0 ? (rp_real)noise_px : RP_C(0.01);
    return c;
}

typedef void (*mutate_fn)(rp_frameset_t *fs, uint32_t j);

typedef struct {
    double err[6];      /* mean absolute error over frames 1.., m and rad */
    uint32_t lost;      /* frames whose step did not return RP_OK */
    uint32_t flags_or;  /* union of the flags */
    uint32_t in3;       /* scored frames with every pose column within 3 sigma */
    uint32_t in3_col[6];/* per column */
    double nees_sum;    /* sum of e^T P^-1 e over scored frames */
    uint32_t nees_in;   /* scored frames with e^T P^-1 e within the 6-dof 99.73 % bound */
    uint32_t scored;
} outcome_t;

/* e^T C^-1 e for the 6x6 covariance C; -1 if C is not positive definite. */
static double nees6(const double e[6], const rp_real cov[36])
{
    rp_real C[36], L[36], b[6], x[6];
    memcpy(C, cov, sizeof(C));
    for (int i = 0; i < 6; ++i) b[i] = (rp_real)e[i];
    if (rp_la_chol(&RP_MAT(6, 6, C), &RP_MAT(6, 6, L)) != RP_OK) return -1.0;
    if (rp_la_chol_solve(&RP_MAT(6, 6, L), &RP_MAT(6, 1, b), &RP_MAT(6, 1, x)) != RP_OK) {
        return -1.0;
    }
    double s = 0.0;
    for (int i = 0; i < 6; ++i) s += e[i] * (double)x[i];
    return s;
}

static void run_sequence(fixture_t *fx, const rp_vo_gc_cfg_t *cfg, uint32_t frames,
                         mutate_fn mutate, outcome_t *out)
{
    assert_ok(rp_vo_gc_init(&fx->vo, &fx->sr.rig, cfg));
    memset(out, 0, sizeof(*out));
    for (uint32_t j = 0; j < frames; ++j) {
        rp_sim_frame(&fx->sr, j, &fx->fs);
        if (mutate) mutate(&fx->fs, j);
        rp_status_t st = rp_vo_gc_step(&fx->vo, &fx->fs, &fx->est);
        if (st != RP_OK) out->lost++;
        out->flags_or |= fx->est.flags;
        for (int i = 0; i < 6; ++i) assert_true(isfinite((double)fx->est.p[i]));
        if (j == 0) {
            assert_true(fx->est.flags & RP_EST_INITIALISING);
            continue;
        }
        double e[6];
        int all_in = 1;
        for (int i = 0; i < 6; ++i) {
            double d = (double)fx->est.p[i] - fx->sr.truth[j * 6 + i];
            if (i >= 3) d = (double)rp_angle_wrap((rp_real)d);
            e[i] = d;
            out->err[i] += fabs(d) / (double)(frames - 1);
            const double sd = sqrt((double)fx->est.cov[i * 6 + i]);
            if (fabs(d) <= 3.0 * sd) {
                out->in3_col[i]++;
            } else {
                all_in = 0;
            }
        }
        out->in3 += (uint32_t)all_in;
        double q = nees6(e, fx->est.cov);
        assert_true(q >= 0.0);
        out->nees_sum += q;
        out->nees_in += q <= 20.06; /* chi-square, 6 dof, 99.73 % (the 3-sigma mass) */
        out->scored++;
    }
}

static void test_noise_free_run_follows_truth(void **state)
{
    (void)state;
    /* Without noise the only error left is the one the assumed depth leaves in the metric
     * scale before the rig's offsets correct it: millimetres, and no drift in rotation. */
    fixture_t *fx = fixture(0.0, 40, 0);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.0);
    outcome_t o;
    run_sequence(fx, &cfg, 40, NULL, &o);
    print_message("gc noise-free: tx %.2e ty %.2e tz %.2e a %.2e b %.2e g %.2e\n", o.err[0],
                  o.err[1], o.err[2], o.err[3], o.err[4], o.err[5]);
    assert_int_equal(o.lost, 0);
    for (int i = 0; i < 3; ++i) assert_true(o.err[i] < 3e-3);
    /* (float: a 0.01 px filter sigma is near the scalar's resolution) */
    for (int i = 3; i < 6; ++i) assert_true(o.err[i] < RP_TOL(1e-3, 3e-3));
    assert_true(fx->est.flags & RP_EST_TRACKING);
    fixture_free(fx);
}

static void test_noisy_runs_beat_the_papers_stereo_pair(void **state)
{
    (void)state;
    /* The paper's Table 1, "2 cameras" (its stereo pair): gc must reach it without stereo. */
    static const double paper2[6] = {.0055, .0132, .0042, .0137, .0055, .0026};
    double mean[6] = {0};
    const int runs = 4;
    for (int r = 0; r < runs; ++r) {
        fixture_t *fx = fixture(0.5, 100, (uint32_t)r);
        rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
        outcome_t o;
        run_sequence(fx, &cfg, 100, NULL, &o);
        assert_int_equal(o.lost, 0);
        for (int i = 0; i < 6; ++i) mean[i] += o.err[i] / runs;
        fixture_free(fx);
    }
    print_message("gc over %d runs: tx %.2e ty %.2e tz %.2e a %.2e b %.2e g %.2e\n", runs,
                  mean[0], mean[1], mean[2], mean[3], mean[4], mean[5]);
    for (int i = 0; i < 6; ++i) assert_true(mean[i] <= paper2[i]);
}

static void test_pose_covariance_is_consistent(void **state)
{
    (void)state;
    /* Every pose column within 3 sigma of the truth in most frames, and the NEES of the
     * 6-dof pose in a sane range (6 when perfectly consistent). */
    uint32_t in3 = 0, scored = 0, in3_col[6] = {0}, nees_in = 0;
    double nees = 0.0;
    const int runs = 4;
    for (int r = 0; r < runs; ++r) {
        fixture_t *fx = fixture(0.5, 100, (uint32_t)(10 + r));
        rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
        outcome_t o;
        run_sequence(fx, &cfg, 100, NULL, &o);
        in3 += o.in3;
        scored += o.scored;
        nees += o.nees_sum;
        nees_in += o.nees_in;
        for (int i = 0; i < 6; ++i) in3_col[i] += o.in3_col[i];
        fixture_free(fx);
    }
    const double frac = (double)in3 / scored;
    print_message("gc consistency: all six within 3 sigma in %.1f%% of %u frames; per column "
                  "%.0f %.0f %.0f %.0f %.0f %.0f %%; mean NEES %.1f (6 = consistent), "
                  "NEES within chi2(6) 99.73 %% bound in %.1f%% of frames\n",
                  100.0 * frac, scored, 100.0 * in3_col[0] / scored, 100.0 * in3_col[1] / scored,
                  100.0 * in3_col[2] / scored, 100.0 * in3_col[3] / scored,
                  100.0 * in3_col[4] / scored, 100.0 * in3_col[5] / scored, nees / scored,
                  100.0 * nees_in / scored);
    assert_true(frac >= 0.90);
    assert_true((double)nees_in / scored >= 0.90);
    assert_true(nees / scored < 20.0);
}

static void test_top_up_adds_features_and_keeps_accuracy(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 60, 1);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    cfg.min_tracked = 400; /* more than a camera sees: top up every frame */
    outcome_t o;
    run_sequence(fx, &cfg, 60, NULL, &o);
    assert_int_equal(o.lost, 0);
    assert_true(o.flags_or & RP_EST_REINIT);
    for (int i = 0; i < 3; ++i) assert_true(o.err[i] < 1e-2);
    fixture_free(fx);
}

/* The right camera delivers nothing from frame 20 to 29. */
static void right_camera_dark(rp_frameset_t *fs, uint32_t j)
{
    if (j >= 20 && j < 30) fs->n[RP_SIM_CAM2] = 0;
}

static void test_one_camera_dark_keeps_tracking_with_the_others(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 50, 2);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    outcome_t o;
    run_sequence(fx, &cfg, 50, right_camera_dark, &o);
    assert_int_equal(o.lost, 0);
    assert_true(o.flags_or & RP_EST_DEGRADED);
    for (int i = 0; i < 3; ++i) assert_true(o.err[i] < 1e-2);
    for (int i = 3; i < 6; ++i) assert_true(o.err[i] < 5e-3);
    /* the camera's landmarks survived the gap: it is used again */
    assert_true(fx->est.n_used[RP_SIM_CAM2] > 0);
    fixture_free(fx);
}

static void all_dark(rp_frameset_t *fs, uint32_t j)
{
    if (j >= 10 && j <= 12) memset(fs->n, 0, sizeof(fs->n));
}

static void test_all_cameras_dark_reports_lost_then_recovers(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 40, 3);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    outcome_t o;
    run_sequence(fx, &cfg, 40, all_dark, &o);
    assert_int_equal(o.lost, 3);
    assert_true(o.flags_or & RP_EST_LOST);
    for (int i = 0; i < 3; ++i) {
        assert_true(fabs((double)fx->est.p[i] - fx->sr.truth[39 * 6 + i]) < 0.1);
    }
    assert_true(fx->est.flags & RP_EST_TRACKING);
    fixture_free(fx);
}

static void nan_pixels(rp_frameset_t *fs, uint32_t j)
{
    if (j % 3 == 1) {
        for (uint16_t i = 0; i < fs->n[RP_SIM_CAM1] && i < 5; ++i) {
            fs->f[RP_SIM_CAM1][i].uv[0] = (rp_real)NAN;
        }
    }
}

static void test_nan_pixels_are_skipped(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 20, 4);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    outcome_t o;
    run_sequence(fx, &cfg, 20, nan_pixels, &o);
    assert_int_equal(o.lost, 0);
    for (int i = 0; i < 3; ++i) assert_true(o.err[i] < 1e-2);
    fixture_free(fx);
}

static void test_malformed_frameset_is_rejected_without_damage(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 10, 5);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    assert_ok(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg));
    rp_sim_frame(&fx->sr, 0, &fx->fs);
    assert_ok(rp_vo_gc_step(&fx->vo, &fx->fs, &fx->est));
    assert_true(fx->est.n_landmarks > 200);
    rp_sim_frame(&fx->sr, 1, &fx->fs);
    fx->fs.n[2] = RP_MAX_FEATS_PER_CAM + 1;
    assert_status(rp_vo_gc_step(&fx->vo, &fx->fs, &fx->est), RP_E_ARG);
    assert_true(fx->est.flags & RP_EST_LOST);
    assert_status(rp_vo_gc_step(&fx->vo, NULL, &fx->est), RP_E_ARG);
    assert_status(rp_vo_gc_step(NULL, &fx->fs, &fx->est), RP_E_ARG);
    rp_sim_frame(&fx->sr, 1, &fx->fs);
    assert_ok(rp_vo_gc_step(&fx->vo, &fx->fs, &fx->est));
    assert_true(fx->est.flags & RP_EST_TRACKING);
    fixture_free(fx);
}

static void test_bad_configuration_is_refused(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 2, 0);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    assert_status(rp_vo_gc_init(NULL, &fx->sr.rig, &cfg), RP_E_ARG);
    assert_status(rp_vo_gc_init(&fx->vo, NULL, &cfg), RP_E_ARG);
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, NULL), RP_E_ARG);
    cfg.n_cams = 0;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.cams[3] = RP_SIM_CAM1; /* a camera twice */
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.cams[1] = 9; /* no such camera */
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.init_depth_m = 0;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.init_depth_sigma_m = (rp_real)NAN;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.min_tracked = 3;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.mature_frac = -1;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.ekf.sigma_px = -1;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    assert_ok(rp_vo_gc_init(&fx->vo, &fx->sr.rig, &cfg));
    fixture_free(fx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_noise_free_run_follows_truth),
        cmocka_unit_test(test_noisy_runs_beat_the_papers_stereo_pair),
        cmocka_unit_test(test_pose_covariance_is_consistent),
        cmocka_unit_test(test_top_up_adds_features_and_keeps_accuracy),
        cmocka_unit_test(test_one_camera_dark_keeps_tracking_with_the_others),
        cmocka_unit_test(test_all_cameras_dark_reports_lost_then_recovers),
        cmocka_unit_test(test_nan_pixels_are_skipped),
        cmocka_unit_test(test_malformed_frameset_is_rejected_without_damage),
        cmocka_unit_test(test_bad_configuration_is_refused),
    };
    return cmocka_run_group_tests_name("vo_gc", tests, NULL, NULL);
}
