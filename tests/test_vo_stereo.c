/*
 * test_vo_stereo.c - the overlapping (stereo) estimator end to end on the paper's simulation:
 * accuracy, re-initialisation with backtracking, a camera that goes dark, malformed frame sets
 * and bad configuration.
 */
#include <string.h>

#include "rigpose/rp_vo_stereo.h"
#include "sim_fixture.h"

typedef struct {
    simfx_t sim; /* first: the run, frame set and estimate */
    rp_vo_stereo_t vo;
} fixture_t;

static fixture_t *fixture(double noise_px, uint32_t frames, uint32_t run)
{
    return simfx_new(sizeof(fixture_t), noise_px, frames, run);
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

static rp_status_t stereo_step(void *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    return rp_vo_stereo_step(vo, fs, est);
}

/* Mean absolute error over frames 1.. into err[6]; returns the frames lost. */
static uint32_t run_sequence(fixture_t *fx, const rp_vo_stereo_cfg_t *cfg, uint32_t frames,
                             simfx_mutate_fn mutate, double err[6], uint32_t *flags_or)
{
    assert_ok(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, cfg));
    simfx_score_t sc;
    simfx_run(&fx->sim, stereo_step, &fx->vo, frames, mutate, NULL, NULL, &sc);
    memcpy(err, sc.err, sizeof(sc.err));
    *flags_or = sc.flags_or;
    return sc.lost;
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
    simfx_free(fx);
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
            simfx_free(fx);
        }
        const double *paper = pairs == 2 ? paper4 : paper2;
        char label[32];
        snprintf(label, sizeof(label), "stereo%d over %d runs", 2 * pairs, runs);
        simfx_print_err(label, mean);
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
    simfx_free(fx);
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
    simfx_free(fx);
}

/* Every camera dark for frames 10-12 (simfx_all_dark_10_12): the estimator reports LOST with
 * the prediction. Frame 13 has nothing to backtrack to (frame 12 was dark), so it is lost too
 * but keeps its features; frame 14 re-initialises from frame 13 and tracks again. */
static void test_all_cameras_dark_reports_lost_then_recovers(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 40, 3);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    double err[6];
    uint32_t flags;
    uint32_t lost = run_sequence(fx, &cfg, 40, simfx_all_dark_10_12, err, &flags);
    assert_int_equal(lost, 4);
    assert_true(flags & RP_EST_LOST);
    /* after recovery the pose is tracked again; the four predicted frames leave some drift */
    simfx_assert_last_position_near(&fx->sim, 39, 0.1);
    assert_true(fx->sim.est.flags & RP_EST_TRACKING);
    simfx_free(fx);
}

static void test_nan_pixels_are_skipped(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 20, 4);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    double err[6];
    uint32_t flags;
    assert_int_equal(run_sequence(fx, &cfg, 20, simfx_nan_pixels_cam1, err, &flags), 0);
    for (int i = 0; i < 3; ++i) assert_true(err[i] < 2e-3);
    simfx_free(fx);
}

static void test_malformed_frameset_is_rejected_without_damage(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 10, 5);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    assert_ok(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg));
    simfx_check_malformed(&fx->sim, stereo_step, &fx->vo, 2);
    simfx_free(fx);
}

static void test_bad_configuration_is_refused(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 2, 0);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    cfg.n_pairs = 0;
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = stereo_cfg(2, 0.5);
    cfg.pair_b[1] = RP_SIM_CAM1; /* a camera in two pairs */
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = stereo_cfg(1, 0.5);
    cfg.pair_b[0] = 9; /* no such camera */
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = stereo_cfg(1, 0.5);
    cfg.ekf.sigma_px = -1;
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    simfx_free(fx);
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
