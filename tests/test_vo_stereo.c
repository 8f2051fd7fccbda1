/*
 * test_vo_stereo.c - the overlapping (stereo) estimator end to end on the paper's simulation:
 * accuracy, re-initialisation with backtracking, a camera that goes dark, malformed frame sets
 * and bad configuration.
 */
#include <stdlib.h>
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_vo_stereo.h"
#include "rp_sim.h"

typedef struct {
    rp_sim_run_t sr;
    rp_frameset_t fs;
    rp_vo_stereo_t vo;
    rp_estimate_t est;
} fixture_t;

static fixture_t *fixture(double noise_px, uint32_t frames, uint32_t run)
{
    fixture_t *fx = calloc(1, sizeof(*fx));
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.noise_px = noise_px;
    cfg.n_frames = frames;
    assert_int_equal(rp_sim_run_init(&fx->sr, &cfg, 11, run), 0);
    return fx;
}

static rp_vo_stereo_cfg_t stereo_cfg(int pairs, double noise_px)
{
    rp_vo_stereo_cfg_t c = rp_vo_stereo_default_cfg();
    c.n_pairs = (uint8_t)pairs;
    c.pair_a[0] = RP_SIM_CAM1;
    c.pair_b[0] = RP_SIM_CAM1B;
    if (pairs > 1) {
        c.pair_a[1] = RP_SIM_CAM3;
        c.pair_b[1] = RP_SIM_CAM3B;
    }
    c.ekf.sigma_px = noise_px > 0 ? (rp_real)noise_px : RP_C(0.01);
    return c;
}

/* Mean absolute error over frames 1.. of tx..tz (m) and alpha..gamma (rad), into err[6]. */
typedef void (*mutate_fn)(rp_frameset_t *fs, uint32_t j);

static uint32_t run_sequence(fixture_t *fx, const rp_vo_stereo_cfg_t *cfg, uint32_t frames,
                             mutate_fn mutate, double err[6], uint32_t *flags_or)
{
    assert_ok(rp_vo_stereo_init(&fx->vo, &fx->sr.rig, cfg));
    memset(err, 0, 6 * sizeof(double));
    uint32_t lost = 0;
    *flags_or = 0;
    for (uint32_t j = 0; j < frames; ++j) {
        rp_sim_frame(&fx->sr, j, &fx->fs);
        if (mutate) mutate(&fx->fs, j);
        rp_status_t st = rp_vo_stereo_step(&fx->vo, &fx->fs, &fx->est);
        if (st != RP_OK) lost++;
        *flags_or |= fx->est.flags;
        for (int i = 0; i < 6; ++i) assert_true(isfinite((double)fx->est.p[i]));
        if (j == 0) {
            assert_true(fx->est.flags & RP_EST_INITIALISING);
            continue;
        }
        for (int i = 0; i < 6; ++i) {
            double d = (double)fx->est.p[i] - fx->sr.truth[j * 6 + i];
            if (i >= 3) d = (double)rp_angle_wrap((rp_real)d);
            err[i] += fabs(d) / (double)(frames - 1);
        }
    }
    return lost;
}

static void test_noise_free_stereo4_follows_truth(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.0, 40, 0);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.0);
    double err[6];
    uint32_t flags;
    assert_int_equal(run_sequence(fx, &cfg, 40, NULL, err, &flags), 0);
    for (int i = 0; i < 6; ++i) assert_true(err[i] < RP_TOL(1e-6, 2e-3));
    rp_sim_run_free(&fx->sr);
    free(fx);
}

static void test_noisy_stereo4_and_stereo2_beat_the_paper_by_five(void **state)
{
    (void)state;
    /* Paper's Table 1 / 5 ("4 cameras" and "2 cameras"), on a few runs. */
    static const double paper4[6] = {.0005, .0005, .0021, .0005, .0004, .0015};
    static const double paper2[6] = {.0055, .0132, .0042, .0137, .0055, .0026};
    for (int pairs = 2; pairs >= 1; --pairs) {
        double mean[6] = {0};
        const int runs = 4;
        for (int r = 0; r < runs; ++r) {
            fixture_t *fx = fixture(0.5, 100, (uint32_t)r);
            rp_vo_stereo_cfg_t cfg = stereo_cfg(pairs, 0.5);
            double err[6];
            uint32_t flags;
            assert_int_equal(run_sequence(fx, &cfg, 100, NULL, err, &flags), 0);
            for (int i = 0; i < 6; ++i) mean[i] += err[i] / runs;
            rp_sim_run_free(&fx->sr);
            free(fx);
        }
        const double *paper = pairs == 2 ? paper4 : paper2;
        print_message("stereo%d over %d runs: tx %.2e ty %.2e tz %.2e a %.2e b %.2e g %.2e\n",
                      2 * pairs, runs, mean[0], mean[1], mean[2], mean[3], mean[4], mean[5]);
#if !RP_REAL_IS_FLOAT
        for (int i = 0; i < 6; ++i) assert_true(mean[i] <= paper[i] / 5.0);
#else
        for (int i = 0; i < 6; ++i) assert_true(mean[i] <= paper[i]);
#endif
    }
}

static void test_reinitialisation_backtracks_and_keeps_accuracy(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 60, 1);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    cfg.min_tracked = 250; /* force frequent re-initialisations */
    double err[6];
    uint32_t flags;
    assert_int_equal(run_sequence(fx, &cfg, 60, NULL, err, &flags), 0);
    assert_true(flags & RP_EST_REINIT);
    for (int i = 0; i < 3; ++i) assert_true(err[i] < 2e-3);
    rp_sim_run_free(&fx->sr);
    free(fx);
}

/* The back pair's cameras deliver nothing from frame 20 to 29 (a camera that vanished). */
static void back_pair_dark(rp_frameset_t *fs, uint32_t j)
{
    if (j >= 20 && j < 30) {
        fs->n[RP_SIM_CAM3] = 0;
        fs->n[RP_SIM_CAM3B] = 0;
    }
}

static void test_camera_pair_vanishing_keeps_tracking_with_the_other(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 50, 2);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    double err[6];
    uint32_t flags;
    assert_int_equal(run_sequence(fx, &cfg, 50, back_pair_dark, err, &flags), 0);
    assert_true(flags & RP_EST_DEGRADED);
    assert_true(flags & RP_EST_REINIT);
    for (int i = 0; i < 3; ++i) assert_true(err[i] < 5e-3);
    rp_sim_run_free(&fx->sr);
    free(fx);
}

/* Every camera dark for frames 10-12: the estimator reports LOST with the prediction. Frame 13
 * has nothing to backtrack to (frame 12 was dark), so it is lost too but keeps its features;
 * frame 14 re-initialises from frame 13 and tracks again. */
static void all_dark(rp_frameset_t *fs, uint32_t j)
{
    if (j >= 10 && j <= 12) memset(fs->n, 0, sizeof(fs->n));
}

static void test_all_cameras_dark_reports_lost_then_recovers(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 40, 3);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    double err[6];
    uint32_t flags;
    uint32_t lost = run_sequence(fx, &cfg, 40, all_dark, err, &flags);
    assert_int_equal(lost, 4);
    assert_true(flags & RP_EST_LOST);
    /* after recovery the pose is tracked again; the four predicted frames leave some drift */
    for (int i = 0; i < 3; ++i) {
        assert_true(fabs((double)fx->est.p[i] - fx->sr.truth[39 * 6 + i]) < 0.1);
    }
    assert_true(fx->est.flags & RP_EST_TRACKING);
    rp_sim_run_free(&fx->sr);
    free(fx);
}

static void nan_pixels(rp_frameset_t *fs, uint32_t j)
{
    if (j % 3 == 1) {
        for (uint16_t i = 0; i < fs->n[RP_SIM_CAM1] && i < 5; ++i) fs->f[RP_SIM_CAM1][i].uv[0] = (rp_real)NAN;
    }
}

static void test_nan_pixels_are_skipped(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 20, 4);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    double err[6];
    uint32_t flags;
    assert_int_equal(run_sequence(fx, &cfg, 20, nan_pixels, err, &flags), 0);
    for (int i = 0; i < 3; ++i) assert_true(err[i] < 2e-3);
    rp_sim_run_free(&fx->sr);
    free(fx);
}

static void test_malformed_frameset_is_rejected_without_damage(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 10, 5);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    assert_ok(rp_vo_stereo_init(&fx->vo, &fx->sr.rig, &cfg));
    rp_sim_frame(&fx->sr, 0, &fx->fs);
    assert_ok(rp_vo_stereo_step(&fx->vo, &fx->fs, &fx->est));
    rp_sim_frame(&fx->sr, 1, &fx->fs);
    fx->fs.n[2] = RP_MAX_FEATS_PER_CAM + 1;
    assert_status(rp_vo_stereo_step(&fx->vo, &fx->fs, &fx->est), RP_E_ARG);
    assert_true(fx->est.flags & RP_EST_LOST);
    assert_status(rp_vo_stereo_step(&fx->vo, NULL, &fx->est), RP_E_ARG);
    rp_sim_frame(&fx->sr, 1, &fx->fs);
    assert_ok(rp_vo_stereo_step(&fx->vo, &fx->fs, &fx->est));
    rp_sim_run_free(&fx->sr);
    free(fx);
}

static void test_bad_configuration_is_refused(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 2, 0);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    cfg.n_pairs = 0;
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = stereo_cfg(2, 0.5);
    cfg.pair_b[1] = RP_SIM_CAM1; /* a camera in two pairs */
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = stereo_cfg(1, 0.5);
    cfg.pair_b[0] = 9; /* no such camera */
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    cfg = stereo_cfg(1, 0.5);
    cfg.ekf.sigma_px = -1;
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sr.rig, &cfg), RP_E_ARG);
    rp_sim_run_free(&fx->sr);
    free(fx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_noise_free_stereo4_follows_truth),
        cmocka_unit_test(test_noisy_stereo4_and_stereo2_beat_the_paper_by_five),
        cmocka_unit_test(test_reinitialisation_backtracks_and_keeps_accuracy),
        cmocka_unit_test(test_camera_pair_vanishing_keeps_tracking_with_the_other),
        cmocka_unit_test(test_all_cameras_dark_reports_lost_then_recovers),
        cmocka_unit_test(test_nan_pixels_are_skipped),
        cmocka_unit_test(test_malformed_frameset_is_rejected_without_damage),
        cmocka_unit_test(test_bad_configuration_is_refused),
    };
    return cmocka_run_group_tests_name("vo_stereo", tests, NULL, NULL);
}
