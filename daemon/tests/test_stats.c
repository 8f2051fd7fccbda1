/*
 * test_stats.c - the daemon's accounting (daemon/rp_stats.c), given frame sets made by hand:
 *   - a camera changing state is seen once (changed, with the state before), missing frames
 *     are not counted, a failed grab takes the states as the source reported them;
 *   - a status message reports the period's rates and worst latency, then starts a new period;
 *     estimator events and frames count since start;
 *   - the truth error leaves frame 0 out of the mean and wraps angles to [-pi, pi];
 *   - the summary's percentiles and rate; bad arguments refused.
 */
#include <string.h>

#include "rp_stats.h"
#include "rp_test.h"

static rp_stats_t g_s;
static rp_hal_set_t g_set;

static void make_set(uint8_t n, uint32_t missing_mask)
{
    memset(&g_set, 0, sizeof g_set);
    g_set.n_cams = n;
    for (uint8_t k = 0; k < n; ++k) {
        g_set.cam[k].flags = (missing_mask >> k) & 1u ? RP_HAL_CAM_MISSING : RP_HAL_CAM_OK;
        g_set.cam[k].drops = 10u * k;
    }
}

static void test_camera_states_and_counts(void **state)
{
    (void)state;
    rp_estimate_t est;
    memset(&est, 0, sizeof est);
    assert_ok(rp_stats_init(&g_s, RP_HAL_SRC_V4L2, 1, 3, 0));
    rp_stats_set_t r;
    make_set(3, 0);
    assert_ok(rp_stats_set(&g_s, &g_set, &est, 1.0f, 1000, &r));
    assert_false(r.changed);
    assert_false(r.has_err);
    make_set(3, 1u << 1); /* camera 1 missing */
    assert_ok(rp_stats_set(&g_s, &g_set, &est, 1.0f, 2000, &r));
    assert_true(r.changed);
    assert_int_equal(g_s.cam_state[1], RP_HAL_CAM_MISSING);
    assert_int_equal(g_s.prev_state[1], RP_HAL_CAM_OK);
    assert_ok(rp_stats_set(&g_s, &g_set, &est, 1.0f, 3000, &r));
    assert_false(r.changed); /* still missing: no change */
    assert_int_equal(g_s.frames[0], 3);
    assert_int_equal(g_s.frames[1], 1);
    /* A failed grab: the source says camera 2 is gone. */
    make_set(3, 0);
    g_set.cam[2].flags = RP_HAL_CAM_GONE | RP_HAL_CAM_MISSING | (1u << 7); /* other bits dropped */
    rp_stats_grab_failed(&g_s, &g_set);
    assert_int_equal(g_s.cam_state[2], RP_HAL_CAM_GONE | RP_HAL_CAM_MISSING);
    assert_int_equal(g_s.n_sets, 3); /* a failed grab is no pose */
}

static void test_status_reports_the_period_then_starts_a_new_one(void **state)
{
    (void)state;
    rp_estimate_t est;
    memset(&est, 0, sizeof est);
    est.cov[0] = est.cov[7] = est.cov[14] = (rp_real)3e-4;
    est.cov[21] = est.cov[28] = est.cov[35] = (rp_real)1e-6;
    est.n_used[0] = 50;
    est.n_landmarks = 77;
    assert_ok(rp_stats_init(&g_s, RP_HAL_SRC_SIM, 2, 2, 1000000));
    /* 30 sets over one second, camera 1 missing in 10 of them, one LOST, two REINIT. */
    for (int j = 0; j < 30; ++j) {
        make_set(2, j < 10 ? 1u << 1 : 0u);
        est.flags = RP_EST_TRACKING | (j == 5 ? RP_EST_LOST : 0u) | (j % 15 == 1 ? RP_EST_REINIT : 0u);
        assert_ok(rp_stats_set(&g_s, &g_set, &est, (float)j, 1000000 + 33333 * j, NULL));
    }
    rp_frameset_t fs;
    memset(&fs, 0, sizeof fs);
    fs.n[0] = 120;
    fs.n[1] = 110;
    fs.cam_dt_us[0] = -1500; /* camera 0 captured 1.5 ms before the set's time */
    fs.cam_dt_us[1] = 2500;
    fs.cam_flags[1] = RP_FS_NO_IMAGE; /* no image: no time reported */
    rigpose_status_t m;
    rp_stats_fill_status(&g_s, &m, &g_set, RP_HAL_OK, &fs, &est, 29.0f, 2.5f, 2000000);
    assert_int_equal(m.seq, 0);
    assert_int_equal(m.last_pose_seq, 29);
    assert_int_equal(m.source, RIGPOSE_STATUS_T_SOURCE_SIM);
    assert_int_equal(m.method, 2);
    assert_int_equal(m.n_cams, 2);
    assert_near(m.fps[0], 30.0, 1e-4);
    assert_near(m.fps[1], 20.0, 1e-4);
    assert_near(m.set_rate_hz, 30.0, 1e-4);
    assert_int_equal(m.frames[1], 20);
    assert_int_equal(m.drops[1], 10);
    assert_int_equal(m.features[0], 120);
    assert_int_equal(m.features_used[0], 50);
    assert_int_equal(m.cam_dt_us[0], -1500);
    assert_int_equal(m.cam_dt_us[1], 0);
    assert_near(m.latency_ms_max, 29.0, 1e-6);
    assert_near(m.process_ms, 2.5, 1e-6);
    assert_int_equal(m.n_lost, 1);
    assert_int_equal(m.n_reinit, 2);
    assert_int_equal(m.n_landmarks, 77);
    assert_near(m.pos_sigma_m, 0.03, 1e-6);
    assert_near(m.rot_sigma_rad, sqrt(3e-6), 1e-6);
    assert_int_equal(m.fps[2], 0.0f); /* past n_cams: zero */

    /* The next period: one set, half a second; the worst latency is the period's. */
    make_set(2, 0);
    assert_ok(rp_stats_set(&g_s, &g_set, &est, 4.0f, 2400000, NULL));
    rp_stats_fill_status(&g_s, &m, &g_set, RP_HAL_E_TIMEOUT, NULL, &est, 0.0f, 0.0f, 2500000);
    assert_int_equal(m.seq, 1);
    assert_int_equal(m.hal_status, RP_HAL_E_TIMEOUT);
    assert_near(m.set_rate_hz, 2.0, 1e-4);
    assert_near(m.latency_ms_max, 4.0, 1e-6);
    assert_int_equal(m.features[0], 0); /* no front end features given */
    assert_int_equal(m.frames[0], 31);
    assert_int_equal(m.n_lost, 1);

    /* the clock offsets, s -> ms, n_cams of them */
    rp_real off[RP_MAX_CAMS] = {0, RP_C(0.012), RP_C(-0.025)};
    rp_real sig[RP_MAX_CAMS] = {0, RP_C(0.0005), RP_C(0.001)};
    off[3] = RP_C(0.04);
    rp_stats_fill_offsets(&m, off, sig, 3);
    assert_near(m.cam_offset_ms[1], 12.0, 1e-4);
    assert_near(m.cam_offset_ms[2], -25.0, 1e-4);
    assert_near(m.cam_offset_sigma_ms[1], 0.5, 1e-4);
    assert_true(m.cam_offset_ms[3] == 0.0f); /* past n_cams */
    rp_stats_fill_offsets(NULL, off, sig, 3);  /* no effect, no crash */
}

static void test_truth_error_and_summary(void **state)
{
    (void)state;
    rp_estimate_t est;
    memset(&est, 0, sizeof est);
    assert_ok(rp_stats_init(&g_s, RP_HAL_SRC_SIM, 0, 1, 0));
    make_set(1, 0);
    g_set.has_truth = 1;
    /* Frame 0: a large error, left out of the mean (it defines the world). */
    est.p[0] = (rp_real)1.0;
    rp_stats_set_t r;
    assert_ok(rp_stats_set(&g_s, &g_set, &est, 1.0f, 0, &r));
    assert_true(r.has_err);
    assert_near(r.err_t_m, 1.0, RP_TOL_TIGHT);
    /* Then 0.3 m / 0.4 m off in x / y and gamma across the +-pi seam. */
    for (int j = 1; j <= 99; ++j) {
        est.p[0] = (rp_real)0.3;
        est.p[1] = (rp_real)0.4;
        est.p[5] = (rp_real)3.1;
        g_set.truth[5] = (rp_real)-3.1;
        assert_ok(rp_stats_set(&g_s, &g_set, &est, (float)(j + 1), 10000 * j, &r));
    }
    assert_near(r.err_t_m, 0.5, RP_TOL(1e-9, 1e-6));
    assert_near(r.err_r_rad, 2.0 * 3.14159265358979323846 - 6.2, RP_TOL(1e-9, 1e-5));
    rp_stats_summary_t s;
    rp_stats_summary(&g_s, &s);
    assert_int_equal(s.n_poses, 100);
    assert_int_equal(s.n_err, 99);
    assert_near(s.err_mean[0], 0.3, RP_TOL(1e-9, 1e-6));
    assert_near(s.err_mean[1], 0.4, RP_TOL(1e-9, 1e-6));
    assert_near(s.err_mean[5], 2.0 * 3.14159265358979323846 - 6.2, RP_TOL(1e-9, 1e-5));
    /* latencies 1..100 ms: the 50th and 99th, within half a histogram bin (0.5 %) */
    assert_near(s.lat_p50_ms, 50.0, 0.005 * 50.0);
    assert_near(s.lat_p99_ms, 99.0, 0.005 * 99.0);
    assert_near(s.fps, 100.0, 1e-9);       /* 99 intervals over 0.99 s */

    /* Percentiles over the whole run, however long: 100,000 sets (more than the 65,536 the
     * daemon kept before), the last 5 % of them slow (80 ms against 2 ms): p99 is a slow one. */
    assert_ok(rp_stats_init(&g_s, RP_HAL_SRC_REPLAY, 0, 1, 0));
    for (int j = 0; j < 100000; ++j) {
        assert_ok(rp_stats_set(&g_s, &g_set, &est, j < 95000 ? 2.0f : 80.0f, 1000 * j, NULL));
    }
    rp_stats_summary(&g_s, &s);
    assert_int_equal(s.n_poses, 100000);
    assert_near(s.lat_p50_ms, 2.0, 0.005 * 2.0);
    assert_near(s.lat_p99_ms, 80.0, 0.005 * 80.0);
    /* No truth, no poses: zeros. */
    assert_ok(rp_stats_init(&g_s, RP_HAL_SRC_REPLAY, 0, 1, 0));
    rp_stats_summary(&g_s, &s);
    assert_int_equal(s.n_poses, 0);
    assert_int_equal(s.n_err, 0);
    assert_true(s.fps == 0.0 && s.lat_p99_ms == 0.0);
}

static void test_bad_arguments(void **state)
{
    (void)state;
    rp_estimate_t est;
    memset(&est, 0, sizeof est);
    assert_status(rp_stats_init(NULL, RP_HAL_SRC_SIM, 0, 1, 0), RP_E_ARG);
    assert_status(rp_stats_init(&g_s, RP_HAL_SRC_SIM, 0, 0, 0), RP_E_ARG);
    assert_status(rp_stats_init(&g_s, RP_HAL_SRC_SIM, 0, RP_MAX_CAMS + 1, 0), RP_E_ARG);
    assert_ok(rp_stats_init(&g_s, RP_HAL_SRC_SIM, 0, 1, 0));
    assert_status(rp_stats_set(&g_s, NULL, &est, 0.0f, 0, NULL), RP_E_ARG);
    assert_status(rp_stats_set(&g_s, &g_set, NULL, 0.0f, 0, NULL), RP_E_ARG);
    assert_status(rp_stats_set(NULL, &g_set, &est, 0.0f, 0, NULL), RP_E_ARG);
    rp_stats_grab_failed(NULL, &g_set); /* no crash */
    rp_stats_fill_status(&g_s, NULL, &g_set, RP_HAL_OK, NULL, &est, 0.0f, 0.0f, 0);
    rp_stats_summary(&g_s, NULL);
    assert_int_equal(g_s.n_sets, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_states_and_counts),
        cmocka_unit_test(test_status_reports_the_period_then_starts_a_new_one),
        cmocka_unit_test(test_truth_error_and_summary),
        cmocka_unit_test(test_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
