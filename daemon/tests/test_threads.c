/*
 * test_threads.c - the daemon's threads (issue 17 item 1), built under ThreadSanitizer:
 *   - the pool (platform/src/rp_pool.c) runs every job of a batch exactly once, for batch
 *     sizes 0..40 on 1..5 threads and thousands of batches in a row; with one thread in
 *     order on the caller's; bad calls refused; stop and start again;
 *   - the default thread count (rp_est_threads_for): the online cores, at most one per
 *     tracker of the layout; the file's `threads:` wins;
 *   - the image path as the daemon runs it: a replay folder of rendered frames of the paper's
 *     rig (img_fixture.h, PGM) read by the HAL's replay source with each camera's image decoded
 *     in a job of the pool (rp_hal_cfg_t.run_jobs), then each camera's tracker in a job
 *     (rp_est_step_images): the estimates on 2, 3 and 4 threads are bit for bit those of one
 *     thread, for stereo4 and gc; and they follow the rendered motion (the run is a real one).
 *     Each camera carries its own capture time (frames.csv's utime_us_<column>, CAM_DT_US
 *     apart), passed as the daemon passes it: the frame sets carry them on every thread count.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "img_fixture.h"
#include "rigpose/rp_config.h"
#include "rigpose/rp_hal.h"
#include "rigpose/rp_pool.h"
#include "rp_sim.h"
#include "rp_est.h"
#include "rp_test.h"

/* ---- the pool -------------------------------------------------------------------------------- */

#define MAX_JOBS 40

typedef struct {
    unsigned hits[MAX_JOBS];
    unsigned order[MAX_JOBS];
    unsigned n_order;
    pthread_t caller;
    unsigned on_caller;
} jobs_t;

static void count_job(void *arg, unsigned j)
{
    jobs_t *b = (jobs_t *)arg;
    b->hits[j]++; /* job j's own slot: no other job touches it */
}

static void order_job(void *arg, unsigned j)
{
    jobs_t *b = (jobs_t *)arg;
    b->order[b->n_order++] = j; /* one thread only: the single-threaded pool */
    b->on_caller += pthread_equal(pthread_self(), b->caller) ? 1u : 0u;
}

static void test_pool_runs_every_job_once(void **state)
{
    (void)state;
    static rp_pool_t pool;
    static jobs_t b;
    for (unsigned n = 1; n <= 5; ++n) {
        assert_ok(rp_pool_start(&pool, n));
        assert_int_equal(rp_pool_threads(&pool), n);
        for (unsigned rep = 0; rep < 200; ++rep) {
            for (unsigned k = 0; k <= MAX_JOBS; ++k) {
                memset(&b, 0, sizeof b);
                assert_ok(rp_pool_run(&pool, k, count_job, &b));
                for (unsigned j = 0; j < MAX_JOBS; ++j) {
                    assert_int_equal(b.hits[j], j < k ? 1u : 0u);
                }
            }
        }
        rp_pool_stop(&pool);
        assert_int_equal(rp_pool_threads(&pool), 0);
    }
}

static void test_pool_single_thread_runs_in_order_on_caller(void **state)
{
    (void)state;
    static rp_pool_t pool;
    static jobs_t b;
    assert_ok(rp_pool_start(&pool, 1));
    memset(&b, 0, sizeof b);
    b.caller = pthread_self();
    assert_ok(rp_pool_run(&pool, 7, order_job, &b));
    assert_int_equal(b.n_order, 7);
    assert_int_equal(b.on_caller, 7);
    for (unsigned j = 0; j < 7; ++j) {
        assert_int_equal(b.order[j], j);
    }
    rp_pool_stop(&pool);
}

static void test_pool_refuses_bad_calls(void **state)
{
    (void)state;
    static rp_pool_t pool;
    static jobs_t b;
    assert_int_equal(rp_pool_start(NULL, 2), RP_E_ARG);
    assert_int_equal(rp_pool_start(&pool, 0), RP_E_ARG);
    assert_int_equal(rp_pool_start(&pool, RP_POOL_MAX_THREADS + 1), RP_E_ARG);
    assert_int_equal(rp_pool_run(&pool, 3, count_job, &b), RP_E_ARG); /* not started */
    assert_ok(rp_pool_start(&pool, 3));
    assert_int_equal(rp_pool_start(&pool, 3), RP_E_ARG); /* started twice */
    assert_int_equal(rp_pool_run(&pool, 3, NULL, &b), RP_E_ARG);
    assert_int_equal(rp_pool_run(NULL, 3, count_job, &b), RP_E_ARG);
    rp_pool_stop(&pool);
    rp_pool_stop(&pool); /* stopped twice: nothing */
    rp_pool_stop(NULL);
    assert_ok(rp_pool_start(&pool, 2)); /* and again */
    memset(&b, 0, sizeof b);
    assert_ok(rp_pool_run(&pool, 5, count_job, &b));
    assert_int_equal(b.hits[4], 1);
    rp_pool_stop(&pool);
    assert_true(rp_pool_online_cores() >= 1);
}

/* ---- the default thread count ------------------------------------------------------------------ */

static rp_config_t g_cfg;

static void load_default(void)
{
    char err[RP_CFG_ERR_MAX];
    if (rp_config_load("config/sim.yaml", &g_cfg, err, sizeof err) != RP_CFG_OK) {
        fail_msg("%s", err);
    }
}

static void test_default_threads_one_per_core_at_most_one_per_tracker(void **state)
{
    (void)state;
    load_default(); /* stereo4: 4 trackers */
    assert_int_equal(g_cfg.threads, 0);
    assert_int_equal(rp_est_threads_for(&g_cfg, 64), 1); /* the sim source: features only */
    g_cfg.hal.kind = RP_HAL_SRC_REPLAY;
    assert_int_equal(rp_est_threads_for(&g_cfg, 1), 1);
    assert_int_equal(rp_est_threads_for(&g_cfg, 2), 2);
    assert_int_equal(rp_est_threads_for(&g_cfg, 64), 4);
    g_cfg.pipe.layout = RP_PIPE_STEREO2;
    assert_int_equal(rp_est_threads_for(&g_cfg, 64), 2);
    g_cfg.pipe.layout = RP_PIPE_CAM2;
    assert_int_equal(rp_est_threads_for(&g_cfg, 64), 1);
    g_cfg.threads = 3; /* the file's (or --threads) wins */
    assert_int_equal(rp_est_threads_for(&g_cfg, 64), 3);
    char err[RP_CFG_ERR_MAX];
    static const char bad[] = "version: 1\nthreads: 17\n";
    assert_int_equal(rp_config_parse(bad, sizeof bad - 1, "t.yaml", &g_cfg, err, sizeof err),
                     RP_CFG_E_RANGE);
    assert_non_null(strstr(err, "threads"));
}

/* ---- the image path on threads ------------------------------------------------------------------ */

#define W 320
#define H 240
#define NFRAMES 10
#define DT_US 33333
/* Camera k's capture time minus the set's in the replay folder, us (small: the images are
 * rendered at the set's time). */
#define CAM_DT_US(k) (100 * (k) - 200)

static char g_dir[64];
static uint8_t g_img[W * H];
static rp_real g_truth[NFRAMES][6];
static rp_est_t g_est;
static rp_hal_set_t g_set;
static rp_estimate_t g_runs[2][NFRAMES];

/* The paper's rig at 320x240, f = 400 px, rigpose-sim's numbering (config/sim.yaml's order). */
static void small_rig(rp_rig_t *rig)
{
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.width = W;
    sc.height = H;
    sc.focal_px = 400.0;
    rp_sim_make_rig(&sc, rig);
}

static void write_pgm(const char *path, const uint8_t *img)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "P5\n%d %d\n255\n", W, H);
    assert_int_equal(fwrite(img, 1, (size_t)W * H, f), (size_t)W * H);
    fclose(f);
}

/* Renders the run (constant velocity (4, -2, 6) mm and (4, 6, -3) mrad per frame) into a
 * replay folder: cK_J.pgm and frames.csv. */
static int setup_replay(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/rp_threads_XXXXXX");
    if (mkdtemp(g_dir) == NULL) {
        return -1;
    }
    rp_rig_t rig;
    small_rig(&rig);
    static const double step[6] = {0.004, -0.002, 0.006, 0.004, 0.006, -0.003};
    const fx_room_t rm = fx_room_default();
    uint64_t rs = 99;
    char path[160];
    snprintf(path, sizeof path, "%s/frames.csv", g_dir);
    FILE *csv = fopen(path, "w");
    if (csv == NULL) {
        return -1;
    }
    fprintf(csv, "utime_us,c0,c1,c2,c3,c4,c5");
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        fprintf(csv, ",utime_us_c%d", k);
    }
    fprintf(csv, "\n");
    for (int j = 0; j < NFRAMES; ++j) {
        for (int i = 0; i < 6; ++i) {
            g_truth[j][i] = (rp_real)(step[i] * j);
        }
        fprintf(csv, "%d", j * DT_US);
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            fx_render(&rig, k, g_truth[j], &rm, g_img, 2.0, &rs);
            snprintf(path, sizeof path, "%s/c%d_%d.pgm", g_dir, k, j);
            write_pgm(path, g_img);
            fprintf(csv, ",c%d_%d.pgm", k, j);
        }
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            fprintf(csv, ",%d", j * DT_US + CAM_DT_US(k));
        }
        fprintf(csv, "\n");
    }
    fclose(csv);
    return 0;
}

static int teardown_replay(void **state)
{
    (void)state;
    char path[160];
    for (int j = 0; j < NFRAMES; ++j) {
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            snprintf(path, sizeof path, "%s/c%d_%d.pgm", g_dir, k, j);
            unlink(path);
        }
    }
    snprintf(path, sizeof path, "%s/frames.csv", g_dir);
    unlink(path);
    rmdir(g_dir);
    return 0;
}

/* The configuration the daemon would run on the replay folder: config/sim.yaml's estimator
 * keys with the small rig, source replay, `threads` threads. */
static void replay_cfg(rp_pipe_layout_t layout, unsigned threads)
{
    load_default();
    small_rig(&g_cfg.rig);
    g_cfg.hal.kind = RP_HAL_SRC_REPLAY;
    g_cfg.hal.realtime = 0;
    g_cfg.hal.partial_sets = 1;
    snprintf(g_cfg.hal.replay_index, sizeof g_cfg.hal.replay_index, "%s", g_dir);
    for (int k = 0; k < g_cfg.hal.n_cams; ++k) {
        g_cfg.hal.cam[k].device[0] = '\0'; /* the k-th image column */
        g_cfg.hal.cam[k].w = W;
        g_cfg.hal.cam[k].h = H;
    }
    if (layout == RP_PIPE_GC) {
        g_cfg.pipe.layout = RP_PIPE_GC; /* gc over cam1..cam4 (rp_pipe_default_cfg) */
        g_cfg.pipe.gc.init_depth_m = RP_C(1.2); /* the room's typical range */
        g_cfg.pipe.gc.init_depth_sigma_m = RP_C(0.3);
        g_cfg.pipe.gc.init_on_sphere = 1;
    }
    g_cfg.threads = (uint8_t)threads;
}

/* One run of the replay through the daemon's estimator on `threads` threads into out[]. */
static void run_replay(rp_pipe_layout_t layout, unsigned threads, rp_estimate_t out[NFRAMES])
{
    replay_cfg(layout, threads);
    assert_ok(rp_est_init(&g_est, &g_cfg));
    assert_int_equal(rp_est_threads(&g_est), threads);
    rp_hal_cfg_t hc = g_cfg.hal;
    hc.run_jobs = threads > 1 ? rp_est_hal_jobs : NULL; /* as the daemon does */
    hc.run_jobs_ctx = &g_est;
    rp_hal_source_t *src = NULL;
    assert_int_equal(rp_hal_open(&src, &hc), RP_HAL_OK);
    assert_int_equal(rp_hal_start(src), RP_HAL_OK);
    for (int j = 0; j < NFRAMES; ++j) {
        assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_OK);
        const rp_image_t *img[RP_MAX_CAMS];
        int64_t cam_utime[RP_MAX_CAMS];
        for (uint8_t k = 0; k < RP_MAX_CAMS; ++k) {
            img[k] = k < g_set.n_cams && g_set.cam[k].img.data != NULL ? &g_set.cam[k].img
                                                                      : NULL;
            cam_utime[k] = img[k] != NULL ? g_set.cam[k].utime : g_set.utime; /* the daemon's */
        }
        memset(&out[j], 0, sizeof out[j]);
        const rp_frameset_t *fs = NULL;
        const rp_status_t st =
            rp_est_step_images(&g_est, img, cam_utime, g_set.n_cams, g_set.utime, &out[j], &fs);
        assert_true(st == RP_OK || st == RP_E_TOO_FEW);
        assert_non_null(fs);
        assert_true(fs->utime == (int64_t)j * DT_US);
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            assert_int_equal(fs->cam_dt_us[k], CAM_DT_US(k));
            assert_int_equal(fs->cam_flags[k], 0);
        }
    }
    assert_int_equal(rp_hal_grab(src, &g_set), RP_HAL_E_END);
    /* ignored: a started source stops */
    (void)rp_hal_stop(src);
    rp_hal_close(src);
    rp_est_close(&g_est);
}

static void assert_same_estimate(const rp_estimate_t *a, const rp_estimate_t *b)
{
    assert_true(a->utime == b->utime && a->frame == b->frame && a->flags == b->flags);
    assert_memory_equal(a->p, b->p, sizeof a->p);
    assert_memory_equal(a->v, b->v, sizeof a->v);
    assert_memory_equal(a->cov, b->cov, sizeof a->cov);
    assert_memory_equal(a->n_used, b->n_used, sizeof a->n_used);
    assert_int_equal(a->n_gated, b->n_gated);
    assert_int_equal(a->n_landmarks, b->n_landmarks);
}

static void check_threads_identical(rp_pipe_layout_t layout)
{
    run_replay(layout, 1, g_runs[0]);
    /* a real run: tracking, following the rendered motion */
    const rp_estimate_t *last = &g_runs[0][NFRAMES - 1];
    assert_true(last->flags & RP_EST_TRACKING);
    for (int i = 0; i < 3; ++i) {
        assert_near(last->p[i], g_truth[NFRAMES - 1][i], 0.01);
        assert_near(last->p[3 + i], g_truth[NFRAMES - 1][3 + i], 0.01);
    }
    for (unsigned n = 2; n <= 4; ++n) {
        run_replay(layout, n, g_runs[1]);
        for (int j = 0; j < NFRAMES; ++j) {
            assert_same_estimate(&g_runs[0][j], &g_runs[1][j]);
        }
    }
}

static void test_stereo4_on_threads_identical_to_one(void **state)
{
    (void)state;
    check_threads_identical(RP_PIPE_STEREO4);
}

static void test_gc_on_threads_identical_to_one(void **state)
{
    (void)state;
    check_threads_identical(RP_PIPE_GC);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pool_runs_every_job_once),
        cmocka_unit_test(test_pool_single_thread_runs_in_order_on_caller),
        cmocka_unit_test(test_pool_refuses_bad_calls),
        cmocka_unit_test(test_default_threads_one_per_core_at_most_one_per_tracker),
        cmocka_unit_test_setup_teardown(test_stereo4_on_threads_identical_to_one, setup_replay,
                                        teardown_replay),
        cmocka_unit_test_setup_teardown(test_gc_on_threads_identical_to_one, setup_replay,
                                        teardown_replay),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
