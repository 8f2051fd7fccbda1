/*
 * test_hal_sim.c - the sim source (platform/src/rp_hal_sim.c) through the HAL's table, like the
 * v4l2 and replay sources:
 *   - rp_hal_open dispatches RP_HAL_SRC_SIM to it; its sets carry features (payload FEATS,
 *     no images) and the truth; it ends after sim_frames sets; out-of-order calls are refused,
 *     each failure told by rp_hal_errmsg;
 *   - through the table with cfg.sim_opts it delivers exactly the sets of its typed API with the
 *     same options (noise, a camera vanishing from set K: GONE | MISSING, no features);
 *   - bad options and rigs are refused naming what is wrong;
 *   - the smooth motion (source.sim.motion: smooth) is delivered with its truth.
 */
#include <string.h>

#include "rigpose/rp_hal.h"
#include "rigpose/rp_hal_sim.h"
#include "rp_test.h"

#define FRAMES 6

static rp_hal_set_t g_set;
static rp_frameset_t g_fs[FRAMES]; /* the typed API's sets, to compare */
static rp_hal_set_t g_ref[FRAMES];

static rp_hal_cfg_t sim_cfg(void)
{
    rp_hal_cfg_t c;
    memset(&c, 0, sizeof c);
    c.kind = RP_HAL_SRC_SIM;
    c.n_cams = 6;
    c.sim_seed = 1;
    c.sim_frames = FRAMES;
    c.realtime = 0;
    return c;
}

static void test_sim_goes_through_the_table(void **state)
{
    (void)state;
    rp_hal_cfg_t cfg = sim_cfg();
    rp_hal_source_t *src = NULL;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_payload(src), RP_HAL_PAYLOAD_FEATS);
    assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_E_STATE);
    assert_non_null(strstr(rp_hal_errmsg(src), "sim: grab before start"));
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_E_STATE);
    int64_t prev = -1;
    for (uint32_t j = 0; j < FRAMES; ++j) {
        assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_OK);
        assert_string_equal(rp_hal_errmsg(src), "");
        assert_int_equal(g_set.payload, RP_HAL_PAYLOAD_FEATS);
        assert_non_null(g_set.feats);
        assert_true(g_set.has_truth);
        assert_int_equal(g_set.seq, j);
        assert_int_equal(g_set.n_cams, 6);
        assert_true(g_set.utime >= prev);
        prev = g_set.utime;
        unsigned total = 0;
        for (int k = 0; k < 6; ++k) {
            assert_null(g_set.cam[k].img.data);
            assert_int_equal(g_set.cam[k].flags, RP_HAL_CAM_OK);
            total += g_set.feats->n[k];
        }
        assert_true(total > 600);
    }
    assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_E_END);
    assert_non_null(strstr(rp_hal_errmsg(src), "sim: end after 6 sets"));
    assert_int_equal(rp_hal_stop(src), RP_HAL_OK);
    assert_int_equal(rp_hal_stop(src), RP_HAL_E_STATE);
    assert_non_null(strstr(rp_hal_errmsg(src), "sim: stop before start"));
    rp_hal_close(src);
    assert_int_equal(rp_hal_payload(NULL), RP_HAL_PAYLOAD_IMAGES);
    /* Closed: it opens again. */
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    rp_hal_close(src);
}

static void test_the_table_and_the_typed_api_deliver_the_same_sets(void **state)
{
    (void)state;
    rp_hal_cfg_t cfg = sim_cfg();
    rp_hal_sim_opts_t o = rp_hal_sim_default_opts();
    o.noise_px = 0.7;
    o.drop_cam = 2;
    o.drop_from = 3;

    rp_hal_sim_t *sim = NULL;
    assert_int_equal(rp_hal_sim_open(&sim, &cfg, &o), RP_HAL_OK);
    assert_int_equal(rp_hal_sim_start(sim), RP_HAL_OK);
    for (int j = 0; j < FRAMES; ++j) {
        assert_int_equal(rp_hal_sim_grab(sim, &g_ref[j]), RP_HAL_OK);
        g_fs[j] = *g_ref[j].feats;
    }
    assert_int_equal(rp_hal_sim_stop(sim), RP_HAL_OK);
    rp_hal_sim_close(sim);

    cfg.sim_opts = &o;
    rp_hal_source_t *src = NULL;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    for (int j = 0; j < FRAMES; ++j) {
        assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_OK);
        const rp_frameset_t *fs = g_set.feats;
        assert_int_equal(fs->utime, g_fs[j].utime);
        for (int k = 0; k < 6; ++k) {
            assert_int_equal(fs->n[k], g_fs[j].n[k]);
            assert_memory_equal(fs->f[k], g_fs[j].f[k], sizeof(rp_feat_t) * fs->n[k]);
            assert_int_equal(g_set.cam[k].flags, g_ref[j].cam[k].flags);
            assert_int_equal(g_set.cam[k].drops, g_ref[j].cam[k].drops);
        }
        for (int i = 0; i < 6; ++i) {
            assert_true(g_set.truth[i] == g_ref[j].truth[i]);
        }
        /* The options arrived: camera 2 gone from set 3 on. */
        assert_int_equal(g_set.cam[2].flags,
                         j >= 3 ? (RP_HAL_CAM_GONE | RP_HAL_CAM_MISSING) : RP_HAL_CAM_OK);
        assert_int_equal(fs->n[2] == 0, j >= 3);
        assert_int_equal(g_set.cam[2].drops, j >= 3 ? (uint32_t)(j - 2) : 0u);
    }
    rp_hal_close(src);

    /* Without options: the protocol's noise, differing features. */
    cfg.sim_opts = NULL;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_OK);
    assert_true(g_set.feats->n[0] == g_fs[0].n[0]);
    assert_true(memcmp(g_set.feats->f[0], g_fs[0].f[0], sizeof(rp_feat_t) * g_fs[0].n[0]) != 0);
    rp_hal_close(src);
}

static void test_bad_options_are_named(void **state)
{
    (void)state;
    rp_hal_source_t *src = NULL;
    rp_hal_cfg_t cfg = sim_cfg();
    rp_hal_sim_opts_t o = rp_hal_sim_default_opts();
    cfg.sim_opts = &o;

    o.drop_cam = 6;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_ARG);
    assert_null(src);
    assert_non_null(strstr(rp_hal_errmsg(NULL), "sim: drop_cam 6 out of -1..5"));
    o = rp_hal_sim_default_opts();
    o.noise_px = -1.0;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_hal_errmsg(NULL), "sim: noise_px -1 out of 0..100 px"));
    o = rp_hal_sim_default_opts();
    o.motion = 4;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_hal_errmsg(NULL), "or 3 (smooth)"));
    o = rp_hal_sim_default_opts();
    cfg.n_cams = 4;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_hal_errmsg(NULL), "sim: the simulated rig has 6 cameras, not 4"));

    /* The typed API says the same through rp_hal_sim_errmsg. */
    rp_hal_sim_t *sim = NULL;
    assert_int_equal(rp_hal_sim_open(&sim, &cfg, NULL), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_hal_sim_errmsg(), "6 cameras, not 4"));
    cfg.kind = RP_HAL_SRC_REPLAY;
    cfg.n_cams = 6;
    assert_int_equal(rp_hal_sim_open(&sim, &cfg, NULL), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_hal_sim_errmsg(), "source kind 1 is not sim"));

    /* One source per process: through the table a second open is out of order; the typed
     * API refuses a second sim. */
    cfg = sim_cfg();
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    rp_hal_source_t *second = NULL;
    assert_int_equal(rp_hal_open(&second, &cfg), RP_HAL_E_STATE);
    assert_int_equal(rp_hal_sim_open(&sim, &cfg, NULL), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_hal_sim_errmsg(), "already open"));
    rp_hal_close(src);
}

/* The smooth motion (rp_sim.h, RP_SIM_MOTION_SMOOTH) through the table: its truth, every
 * camera present at the set's time (the sim source has no camera clocks). */
static void test_smooth_motion_is_delivered(void **state)
{
    (void)state;
    rp_hal_source_t *src = NULL;
    rp_hal_cfg_t cfg = sim_cfg();
    rp_hal_sim_opts_t o = rp_hal_sim_default_opts();
    o.motion = (int8_t)RP_SIM_MOTION_SMOOTH;
    cfg.sim_opts = &o;
    assert_int_equal(rp_hal_open(&src, &cfg), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.motion = RP_SIM_MOTION_SMOOTH;
    sc.n_frames = FRAMES;
    rp_sim_run_t sr;
    assert_int_equal(rp_sim_run_init(&sr, &sc, 1, 0), 0);
    for (uint32_t j = 0; j < FRAMES; ++j) {
        assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_OK);
        for (int i = 0; i < 6; ++i) {
            assert_true(g_set.truth[i] == (rp_real)sr.truth[6u * j + (unsigned)i]);
        }
        for (int k = 0; k < 6; ++k) {
            assert_int_equal(g_set.cam[k].flags, 0);
            assert_int_equal(g_set.cam[k].utime, g_set.utime);
            assert_true(g_set.feats->n[k] > 0);
        }
    }
    assert_true(sr.truth[6u * (FRAMES - 1)] != 0.0); /* it moved */
    rp_sim_run_free(&sr);
    rp_hal_close(src);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sim_goes_through_the_table),
        cmocka_unit_test(test_the_table_and_the_typed_api_deliver_the_same_sets),
        cmocka_unit_test(test_bad_options_are_named),
        cmocka_unit_test(test_smooth_motion_is_delivered),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
