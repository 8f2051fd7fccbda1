/*
 * test_est.c - the daemon's feature path: the HAL's sim source (platform/src/rp_hal_sim.c)
 * feeding the configured estimator (daemon/rp_est.c), as `rigpose` runs them (the methods
 * through rp_hal_open, the source's own checks through its typed API).
 *   - the sim source delivers frame sets in order with features, the truth and monotonic
 *     capture times; it ends after sim_frames sets; calls out of order are refused;
 *   - every method of the configuration file follows the simulated truth, run with the parsed
 *     configuration unchanged;
 *   - a camera dropped from frame K is flagged GONE | MISSING with no features and a growing
 *     drop count, and the estimator keeps tracking on the other cameras.
 */
#include <string.h>

#include "rigpose/rp_config.h"
#include "rigpose/rp_hal_sim.h"
#include "rp_est.h"
#include "rp_test.h"

static rp_config_t g_cfg;
static rp_est_t g_est;
static rp_hal_set_t g_set;

static void load_default(void)
{
    char err[RP_CFG_ERR_MAX];
    if (rp_config_load("config/sim.yaml", &g_cfg, err, sizeof err) != RP_CFG_OK) {
        fail_msg("%s", err);
    }
}

static void test_sim_source_delivers_ordered_sets_then_ends(void **state)
{
    (void)state;
    load_default();
    g_cfg.hal.sim_frames = 5;
    g_cfg.hal.realtime = 0;
    rp_hal_sim_t *sim = NULL;
    assert_int_equal(rp_hal_sim_open(&sim, &g_cfg.hal, NULL), RP_HAL_OK);
    rp_hal_sim_t *second = NULL;
    assert_int_equal(rp_hal_sim_open(&second, &g_cfg.hal, NULL), RP_HAL_E_ARG); /* one source */
    assert_int_equal(rp_hal_sim_grab(sim, &g_set), RP_HAL_E_STATE);              /* not started */
    assert_int_equal(rp_hal_sim_start(sim), RP_HAL_OK);
    int64_t prev = -1;
    for (uint32_t j = 0; j < 5; ++j) {
        assert_int_equal(rp_hal_sim_grab(sim, &g_set), RP_HAL_OK);
        assert_int_equal(g_set.seq, j);
        assert_int_equal(g_set.n_cams, 6);
        assert_true(g_set.payload == RP_HAL_PAYLOAD_FEATS && g_set.feats != NULL && g_set.has_truth);
        assert_true(g_set.utime >= prev);
        prev = g_set.utime;
        assert_int_equal(g_set.feats->utime, (int64_t)(j * 1000000.0 / 30.0 + 0.5));
        unsigned total = 0;
        for (int k = 0; k < 6; ++k) {
            assert_null(g_set.cam[k].img.data);
            assert_int_equal(g_set.cam[k].flags, RP_HAL_CAM_OK);
            total += g_set.feats->n[k];
        }
        assert_true(total > 600);
        if (j == 0) {
            for (int i = 0; i < 6; ++i) {
                assert_near(g_set.truth[i], 0.0, 1e-12); /* frame 0 defines the world */
            }
        }
    }
    assert_int_equal(rp_hal_sim_grab(sim, &g_set), RP_HAL_E_END);
    assert_int_equal(rp_hal_sim_stop(sim), RP_HAL_OK);
    assert_int_equal(rp_hal_sim_stop(sim), RP_HAL_E_STATE);
    rp_hal_sim_close(sim);
    /* Bad configurations. */
    rp_hal_sim_opts_t o = rp_hal_sim_default_opts();
    o.drop_cam = 6;
    assert_int_equal(rp_hal_sim_open(&sim, &g_cfg.hal, &o), RP_HAL_E_ARG);
    g_cfg.hal.n_cams = 4;
    assert_int_equal(rp_hal_sim_open(&sim, &g_cfg.hal, NULL), RP_HAL_E_ARG);
    assert_int_equal(rp_hal_sim_open(NULL, &g_cfg.hal, NULL), RP_HAL_E_ARG);
}

/* config/sim.yaml with its method and cameras replaced by layout m's (its other keys kept):
 * the configuration the daemon runs for `--config` of that file. */
static void load_default_as(rp_pipe_layout_t m)
{
    static const char *const est[RP_PIPE_LAYOUT_COUNT_] = {
        "  method: stereo4\n  pairs: [[cam1, cam1b], [cam3, cam3b]]\n",
        "  method: stereo2\n  pairs: [[cam1, cam1b]]\n",
        "  method: gc\n  cams: [cam1, cam2, cam3, cam4]\n",
        "  method: cam1\n", "  method: cam2\n", "  method: cam3\n", "  method: cam4\n",
        "  method: rc\n"};
    static char text[16384], out[16384];
    FILE *f = fopen("config/sim.yaml", "rb");
    assert_non_null(f);
    const size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    char *a = strstr(text, "  method: stereo4");
    char *b = a != NULL ? strstr(a, "  pairs: [[cam1, cam1b], [cam3, cam3b]]\n") : NULL;
    assert_non_null(b);
    b += strlen("  pairs: [[cam1, cam1b], [cam3, cam3b]]\n");
    const int len = snprintf(out, sizeof out, "%.*s%s%s", (int)(a - text), text, est[m], b);
    char err[RP_CFG_ERR_MAX];
    if (rp_config_parse(out, (size_t)len, "config/sim.yaml", &g_cfg, err, sizeof err) !=
        RP_CFG_OK) {
        fail_msg("%s", err);
    }
    assert_int_equal(g_cfg.pipe.layout, m);
}

/* Run `frames` sets of the sim through layout m; mean abs translation / angle error over
 * sets 1.. . opts may drop a camera. Returns the count of sets with RP_EST_TRACKING. */
static unsigned run_method(rp_pipe_layout_t m, uint32_t frames, const rp_hal_sim_opts_t *opts,
                           double *et, double *er, unsigned *n_gone_sets)
{
    load_default_as(m);
    g_cfg.hal.sim_frames = frames;
    assert_ok(rp_est_init(&g_est, &g_cfg));
    /* rp_est runs the parsed configuration as it is: no setting of its own. */
    assert_memory_equal(&g_est.pipe.cfg, &g_cfg.pipe, sizeof g_cfg.pipe);
    /* As the daemon opens it: through the HAL's table, the options in cfg.sim_opts. */
    rp_hal_cfg_t hc = g_cfg.hal;
    hc.sim_opts = opts;
    rp_hal_source_t *src = NULL;
    assert_int_equal(rp_hal_open(&src, &hc), RP_HAL_OK);
    assert_int_equal(rp_hal_payload(src), RP_HAL_PAYLOAD_FEATS);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    unsigned tracking = 0;
    *et = *er = 0.0;
    *n_gone_sets = 0;
    for (uint32_t j = 0; j < frames; ++j) {
        assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_OK);
        assert_int_equal(g_set.payload, RP_HAL_PAYLOAD_FEATS);
        rp_estimate_t est;
        /* ignored: the test counts the flags; a set without an update says so in them */
        (void)rp_est_step(&g_est, g_set.feats, &est);
        tracking += (est.flags & RP_EST_TRACKING) ? 1u : 0u;
        for (int k = 0; k < 6; ++k) {
            if (g_set.cam[k].flags & RP_HAL_CAM_GONE) {
                assert_int_equal(g_set.feats->n[k], 0);
                assert_true(g_set.cam[k].flags & RP_HAL_CAM_MISSING);
                assert_int_equal(g_set.cam[k].drops, ++*n_gone_sets);
            }
        }
        if (j > 0) {
            for (int i = 0; i < 3; ++i) {
                *et += fabs((double)(est.p[i] - g_set.truth[i])) / (3.0 * (frames - 1));
                *er += fabs(remainder((double)(est.p[3 + i] - g_set.truth[3 + i]), 6.283185307179586)) /
                       (3.0 * (frames - 1));
            }
        }
    }
    assert_int_equal(rp_hal_stop(src), RP_HAL_OK);
    rp_hal_close(src);
    return tracking;
}

static void test_every_method_follows_the_simulated_truth(void **state)
{
    (void)state;
    static const struct { rp_pipe_layout_t m; double max_t, max_r; } cases[] = {
        /* Bounds: a tenth of the paper's Table 1 row for stereo4 / stereo2 (4 / 2 cameras), the
         * paper's own row for cam1 and RC, the "2 cameras" row for gc (its comparison). */
        {RP_PIPE_STEREO4, 0.0021 / 10, 0.0015 / 10},
        {RP_PIPE_STEREO2, 0.0132 / 10, 0.0137 / 10},
        {RP_PIPE_GC, 0.0132, 0.0137},
        {RP_PIPE_CAM1, 0.0337, 0.0260},
        {RP_PIPE_RC, 0.0746, 0.0624},
    };
    const uint32_t frames = 30;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        double et, er;
        unsigned gone;
        const unsigned tracking = run_method(cases[i].m, frames, NULL, &et, &er, &gone);
        printf("%-8s %u sets: mean abs error %.6f m, %.6f rad; tracking in %u\n",
               rp_pipe_layout_name(cases[i].m), frames, et, er, tracking);
        assert_true(tracking >= frames - 2);
        assert_true(et < cases[i].max_t);
        assert_true(er < cases[i].max_r);
        assert_int_equal(gone, 0);
    }
}

static void test_a_vanished_camera_is_flagged_and_tracking_goes_on(void **state)
{
    (void)state;
    rp_hal_sim_opts_t o = rp_hal_sim_default_opts();
    o.drop_cam = RP_SIM_CAM3; /* the back pair loses its left camera */
    o.drop_from = 10;
    double et, er;
    unsigned gone;
    const unsigned tracking = run_method(RP_PIPE_STEREO4, 30, &o, &et, &er, &gone);
    printf("stereo4 with cam3 gone from set 10: %u sets flagged gone, error %.6f m, %.6f rad, "
           "tracking in %u of 30\n", gone, et, er, tracking);
    assert_int_equal(gone, 20);
    assert_true(tracking >= 28);
    assert_true(et < 0.0021 / 5 && er < 0.0015 / 5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sim_source_delivers_ordered_sets_then_ends),
        cmocka_unit_test(test_every_method_follows_the_simulated_truth),
        cmocka_unit_test(test_a_vanished_camera_is_flagged_and_tracking_goes_on),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
