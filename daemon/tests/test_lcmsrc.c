/*
 * test_lcmsrc.c - the daemon's source kind lcm (daemon/rp_lcmsrc.c) on memq://, fed
 * rigpose.features_t as rigpose-frontend publishes them (rp_pub_fill_features / rp_pub_features):
 *   - a set goes out once every camera of the layout is in it, with each camera's features
 *     (ids and positions exactly), seq and state; a camera outside the layout is not waited for;
 *   - a camera that sent a later frame is not waited for (MISSING, not GONE); a message older
 *     than the last set out is late and dropped; one for the wrong camera or with a
 *     non-finite position is refused;
 *   - a camera silent for timeout_ms is GONE: the set waited at most timeout_ms, later sets do
 *     not wait; when it sends again it is back in the next set;
 *   - a restarted front end (a new instance) restarting its serials at 0: its ids continue
 *     after the highest serial seen from that camera; the first front end's ids are unchanged;
 *   - a timeout with nothing heard says so (RP_HAL_E_TIMEOUT, every camera MISSING);
 *   - times: each camera's own capture time goes into its cam_dt_us (relative to the set's
 *     time: the lowest-index camera with an image, whatever order the messages came in) and
 *     set->cam[k].utime; a camera of the layout without a message, or whose message says
 *     MISSING, is RP_FS_NO_IMAGE; messages at the ends of int64 do not overflow; a tolerance
 *     over 1 s is refused;
 *   - sets: latest: a set at once per frame of the set camera (or of any camera), every other
 *     camera's newest undelivered frame at its own time, the rest MISSING without an error;
 *     late and skipped frames; a silent set camera hands the sets to the others (a frame held
 *     when it turns absent makes a set at once) and takes them back when it sends again; a
 *     queued backlog gives the newest frame; MISSING messages only count as heard; a set
 *     camera never heard is absent after timeout_ms; one outside the layout: the layout's
 *     first; outside the rig: refused.
 */
#include <lcm/lcm.h>
#include <math.h>
#include <string.h>

#include "rigpose/rp_track.h"
#include "rp_feats.h"
#include "rp_lcmsrc.h"
#include "rp_publish.h"
#include "rp_test.h"

#define TIMEOUT_MS 60

static rp_config_t g_cfg;
static rp_lsrc_t g_src;
static rp_hal_set_t g_set;
static rigpose_features_t g_m;
static lcm_t *g_lcm;

/* gc on cameras 0 and 1 of a rig of 3 (camera 2 outside the layout). */
static int setup(void **state)
{
    (void)state;
    memset(&g_cfg, 0, sizeof g_cfg);
    g_cfg.rig.n_cams = 3;
    g_cfg.pipe.layout = RP_PIPE_GC;
    g_cfg.pipe.gc.n_cams = 2;
    g_cfg.pipe.gc.cams[0] = 0;
    g_cfg.pipe.gc.cams[1] = 1;
    g_cfg.hal.sync_tol_us = 300;
    g_cfg.hal.timeout_ms = TIMEOUT_MS;
    snprintf(g_cfg.features_channel, sizeof g_cfg.features_channel, "FE");
    g_lcm = lcm_create("memq://");
    assert_non_null(g_lcm);
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_OK);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    rp_lsrc_close(&g_src);
    lcm_destroy(g_lcm);
    return 0;
}

/* Camera cam's message at utime from front end `inst`: n features, ids rp_track_id(cam, s0 + i),
 * positions (10 + i + 1/65536 * (i + 1), 20 + i). */
static void send(uint8_t cam, int64_t utime, int32_t seq, uint16_t n, uint32_t s0,
                 const char *inst)
{
    static rp_feat_t f[RP_MAX_FEATS_PER_CAM];
    for (uint16_t i = 0; i < n; ++i) {
        f[i].id = rp_track_id(cam, s0 + i);
        f[i].uv[0] = (rp_real)(10 + i) + (rp_real)(i + 1) / (rp_real)65536;
        f[i].uv[1] = (rp_real)(20 + i);
    }
    rp_pub_fill_features(&g_m, cam, utime, seq, f, n);
    memcpy(g_m.instance, inst, strlen(inst));
    char ch[RP_CFG_CHANNEL_MAX + 8];
    assert_int_equal(rp_feats_channel(g_cfg.features_channel, cam, ch, sizeof ch), 0);
    assert_int_equal(rp_pub_features(g_lcm, ch, &g_m), RP_PUB_OK);
}

static int64_t ms_since(int64_t t0) { return (rp_hal_now_us() - t0) / 1000; }

static void test_a_set_of_every_camera_goes_out_at_once(void **state)
{
    (void)state;
    send(0, 1000, 0, 5, 0, "A");
    send(1, 1200, 0, 3, 0, "B"); /* within sync_tol_us, 300 us */
    const int64_t t0 = rp_hal_now_us();
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(ms_since(t0) < TIMEOUT_MS / 2); /* camera 2 is not the layout's: not waited for */
    assert_int_equal(g_set.payload, RP_HAL_PAYLOAD_FEATS);
    assert_non_null(g_set.feats);
    assert_true(g_set.utime == 1000);
    assert_int_equal(g_set.n_cams, 3);
    assert_int_equal(g_set.cam[0].flags, RP_HAL_CAM_OK);
    assert_int_equal(g_set.cam[1].flags, RP_HAL_CAM_OK);
    assert_int_equal(g_set.cam[2].flags & RP_HAL_CAM_MISSING, RP_HAL_CAM_MISSING);
    assert_int_equal(g_set.feats->n[0], 5);
    assert_int_equal(g_set.feats->n[1], 3);
    assert_int_equal(g_set.feats->n[2], 0);
    assert_int_equal(g_set.feats->f[0][4].id, rp_track_id(0, 4));
    assert_true(g_set.feats->f[0][4].uv[0] == (rp_real)14 + (rp_real)5 / (rp_real)65536);
    assert_true(g_set.feats->f[1][2].uv[1] == (rp_real)22);
    assert_string_equal(rp_lsrc_errmsg(&g_src), "");
    /* each camera at its own time */
    assert_true(g_set.feats->utime == 1000);
    assert_int_equal(g_set.feats->cam_dt_us[0], 0);
    assert_int_equal(g_set.feats->cam_dt_us[1], 200);
    assert_true(g_set.cam[0].utime == 1000 && g_set.cam[1].utime == 1200);
    for (int k = 0; k < 3; ++k) {
        assert_int_equal(g_set.feats->cam_flags[k], 0); /* camera 2: not the layout's */
    }
}

static void test_moved_past_late_and_bad_messages(void **state)
{
    (void)state;
    send(0, 1000, 0, 2, 0, "A");
    send(1, 1000, 0, 2, 0, "B");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    send(0, 2000, 1, 2, 0, "A");
    send(1, 3000, 1, 2, 0, "B"); /* camera 1 skipped the frame of 2000 */
    send(0, 3000, 2, 2, 0, "A");
    const int64_t t0 = rp_hal_now_us();
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(ms_since(t0) < TIMEOUT_MS / 2);
    assert_true(g_set.utime == 2000);
    assert_int_equal(g_set.cam[1].flags, RP_HAL_CAM_MISSING); /* not GONE: it is sending */
    assert_int_equal(g_set.feats->n[1], 0);
    assert_int_equal(g_set.feats->cam_flags[1], RP_FS_NO_IMAGE);
    assert_int_equal(g_set.feats->cam_flags[0], 0);
    assert_non_null(strstr(rp_lsrc_errmsg(&g_src), "camera 1: no features in this set"));
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 3000);
    assert_int_equal(g_set.cam[1].flags, RP_HAL_CAM_OK);

    send(0, 2500, 3, 2, 0, "A"); /* older than the last set out */
    send(1, 4000, 2, 2, 0, "B");
    /* camera 0's frame on camera 1's channel, and a non-finite position */
    rp_pub_fill_features(&g_m, 0, 4000, 3, NULL, 0);
    assert_int_equal(rp_pub_features(g_lcm, "FE1", &g_m), RP_PUB_OK);
    rp_pub_fill_features(&g_m, 0, 4000, 3, NULL, 0);
    g_m.n = 1;
    g_m.u[0] = NAN;
    assert_int_equal(rp_pub_features(g_lcm, "FE0", &g_m), RP_PUB_OK);
    send(0, 4000, 4, 2, 0, "A");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 4000);
    assert_int_equal(g_set.cam[0].flags, RP_HAL_CAM_OK);
    assert_int_equal(g_set.feats->n[0], 2);
    assert_int_equal(g_src.n_late, 1);
    assert_int_equal(g_src.n_bad, 2);
}

static void test_a_silent_camera_is_gone_then_rejoins(void **state)
{
    (void)state;
    send(0, 1000, 0, 4, 0, "A");
    send(1, 1000, 0, 4, 0, "B");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    /* camera 1's front end dies: the next set waits timeout_ms for it, then goes without */
    send(0, 2000, 1, 4, 0, "A");
    int64_t t0 = rp_hal_now_us();
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    const int64_t waited = ms_since(t0);
    assert_true(waited >= TIMEOUT_MS / 2 && waited < 3 * TIMEOUT_MS);
    assert_true(g_set.utime == 2000);
    assert_int_equal(g_set.cam[1].flags, RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE);
    assert_int_equal(g_set.feats->cam_flags[1], RP_FS_NO_IMAGE);
    /* gone: the next sets do not wait */
    send(0, 3000, 2, 4, 0, "A");
    t0 = rp_hal_now_us();
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(ms_since(t0) < TIMEOUT_MS / 2);
    assert_int_equal(g_set.cam[1].flags, RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE);
    assert_non_null(strstr(rp_lsrc_errmsg(&g_src), "silent for longer than timeout_ms"));
    /* restarted (instance C), its serials from 0 again: back in the next set, its ids moved
     * past the 4 serials (0..3) the first front end used */
    send(1, 4000, 0, 3, 0, "C");
    send(0, 4000, 3, 4, 4, "A");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 4000);
    assert_int_equal(g_set.cam[1].flags, RP_HAL_CAM_OK);
    assert_int_equal(g_set.feats->n[1], 3);
    for (uint16_t i = 0; i < 3; ++i) {
        assert_int_equal(rp_track_id_cam(g_set.feats->f[1][i].id), 1);
        assert_int_equal(rp_track_id_serial(g_set.feats->f[1][i].id), 4 + i);
    }
    assert_int_equal(g_set.feats->f[0][0].id, rp_track_id(0, 4)); /* camera 0: its own ids */
    assert_int_equal(g_src.n_restarts, 1);
}

static void test_a_timeout_with_nothing_heard(void **state)
{
    (void)state;
    const int64_t t0 = rp_hal_now_us();
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_E_TIMEOUT);
    assert_true(ms_since(t0) >= TIMEOUT_MS - 2);
    assert_null(g_set.feats);
    assert_int_equal(g_set.cam[0].flags, RP_HAL_CAM_MISSING); /* never heard: not yet GONE */
    assert_non_null(strstr(rp_lsrc_errmsg(&g_src), "no frame set from the front ends"));
    assert_int_equal(rp_lsrc_grab(NULL, &g_set), RP_HAL_E_ARG);
}

/* The set's time is the lowest-index camera's with an image, whatever order the messages came
 * in (camera 1's first here); a camera whose front end had no image (state MISSING) is
 * RP_FS_NO_IMAGE and the next camera's time is the set's; each camera's difference in
 * cam_dt_us, negative too. */
static void test_each_camera_at_its_own_time(void **state)
{
    (void)state;
    send(1, 5100, 0, 2, 0, "B");
    send(0, 5000, 0, 2, 0, "A");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 5000 && g_set.feats->utime == 5000);
    assert_int_equal(g_set.feats->cam_dt_us[0], 0);
    assert_int_equal(g_set.feats->cam_dt_us[1], 100);
    assert_true(g_set.cam[1].utime == 5100);

    /* camera 0's front end had no image (its source's MISSING), stamped at its set's time */
    rp_pub_fill_features(&g_m, 0, 6000, 1, NULL, 0);
    g_m.state = RIGPOSE_STATUS_T_CAM_MISSING;
    assert_int_equal(rp_pub_features(g_lcm, "FE0", &g_m), RP_PUB_OK);
    send(1, 6250, 1, 2, 0, "B");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 6250);
    assert_int_equal(g_set.feats->cam_flags[0], RP_FS_NO_IMAGE);
    assert_int_equal(g_set.feats->cam_flags[1], 0);
    assert_int_equal(g_set.feats->cam_dt_us[0], -250);
    assert_int_equal(g_set.feats->cam_dt_us[1], 0);
    assert_int_equal(g_set.cam[0].flags, RP_HAL_CAM_MISSING);

    /* times at the ends of int64: late (before the last set), or a set of its own, no
     * overflow (UBSan) */
    send(0, INT64_MIN, 2, 1, 0, "A");
    send(0, INT64_MAX, 3, 1, 0, "A");
    send(1, INT64_MAX - 10, 2, 1, 0, "B");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == INT64_MAX);
    assert_int_equal(g_set.feats->cam_dt_us[1], -10);
    assert_int_equal(g_src.n_late, 1);
}

/* sets: latest (free-running cameras at their own rates), camera 0 the set camera. */
static int setup_latest(void **state)
{
    setup(state);
    rp_lsrc_close(&g_src);
    g_cfg.hal.sets_latest = 1;
    g_cfg.hal.set_cam = 0;
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_OK);
    return 0;
}

/* Each frame of the set camera makes a set at once, at its time, with every other camera's
 * newest frame not yet delivered at its own time (40 ms apart: no tolerance groups them); a
 * camera without a new frame is MISSING, not an error; older held frames are skipped; a frame
 * not after its camera's last delivered one is late. */
static void test_latest_a_set_per_frame_of_the_set_camera(void **state)
{
    (void)state;
    send(1, 40000, 0, 3, 0, "B"); /* camera 0 not heard yet (nor absent): no set */
    send(1, 60000, 1, 3, 0, "B");
    send(1, 80000, 2, 4, 0, "B"); /* replaces the frame of 60000 */
    send(0, 100000, 0, 5, 0, "A");
    int64_t t0 = rp_hal_now_us();
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(ms_since(t0) < TIMEOUT_MS / 2);
    assert_true(g_set.utime == 100000 && g_set.feats->utime == 100000);
    assert_int_equal(g_set.feats->n[0], 5);
    assert_int_equal(g_set.feats->n[1], 4);
    assert_int_equal(g_set.feats->cam_dt_us[0], 0);
    assert_int_equal(g_set.feats->cam_dt_us[1], -20000);
    assert_true(g_set.cam[1].utime == 80000);
    assert_int_equal(g_set.cam[1].seq, 2);
    assert_int_equal(g_src.n_skipped, 2);
    assert_string_equal(rp_lsrc_errmsg(&g_src), "");

    /* camera 1 has nothing new: the next set goes at once without it, MISSING, no message */
    send(0, 133000, 1, 5, 0, "A");
    t0 = rp_hal_now_us();
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(ms_since(t0) < TIMEOUT_MS / 2);
    assert_true(g_set.utime == 133000);
    assert_int_equal(g_set.cam[1].flags, RP_HAL_CAM_MISSING);
    assert_int_equal(g_set.feats->n[1], 0);
    assert_int_equal(g_set.feats->cam_flags[1], RP_FS_NO_IMAGE);
    assert_string_equal(rp_lsrc_errmsg(&g_src), "");

    /* late: camera 1's frame of 80000 again (delivered), camera 0's before its last */
    send(1, 80000, 2, 4, 0, "B");
    send(0, 120000, 2, 5, 0, "A");
    send(1, 140000, 3, 2, 0, "B"); /* after camera 0's set: held for the next one */
    send(0, 166000, 3, 5, 0, "A");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 166000);
    assert_int_equal(g_set.feats->cam_dt_us[1], -26000);
    assert_int_equal(g_set.feats->n[1], 2);
    assert_int_equal(g_src.n_late, 2);
}

/* sets: latest, set camera 0 not sending: the grab waits until camera 0 is absent, then the
 * frame held (at utime) makes the set, camera 0 MISSING and GONE. */
static void set_once_camera_0_is_absent(int64_t utime)
{
    const int64_t t0 = rp_hal_now_us();
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(ms_since(t0) >= TIMEOUT_MS / 2);
    assert_true(g_set.utime == utime);
    assert_int_equal(g_set.cam[0].flags, RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE);
}

/* set_camera any: every frame makes a set; one not after the last set's time joins the next
 * set at its own (earlier) time. A silent set camera: the other cameras' frames make the sets. */
static void test_latest_any_camera_and_a_gone_set_camera(void **state)
{
    (void)state;
    rp_lsrc_close(&g_src);
    g_cfg.hal.set_cam = -1;
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_OK);
    send(1, 10000, 0, 2, 0, "B");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 10000);
    assert_int_equal(g_set.cam[0].flags, RP_HAL_CAM_MISSING);
    send(0, 9000, 0, 3, 0, "A"); /* captured before the last set: no set of its own */
    send(1, 43000, 1, 2, 0, "B");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 43000);
    assert_int_equal(g_set.feats->n[0], 3);
    assert_int_equal(g_set.feats->cam_dt_us[0], -34000);
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_E_TIMEOUT); /* nothing new */

    /* set camera 0, silent longer than timeout_ms (or never heard for that long after the
     * source opened): camera 1's frames make the sets */
    rp_lsrc_close(&g_src);
    g_cfg.hal.set_cam = 0;
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_OK);
    send(0, 50000, 0, 3, 0, "A");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    rp_hal_sleep_us((int64_t)(TIMEOUT_MS + 10) * 1000);
    send(1, 90000, 1, 2, 0, "B");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 90000);
    assert_int_equal(g_set.cam[0].flags, RP_HAL_CAM_MISSING | RP_HAL_CAM_GONE);
    assert_non_null(strstr(rp_lsrc_errmsg(&g_src), "silent for longer than timeout_ms"));
    /* it comes back: its frames make the sets again, camera 1's alone no longer */
    send(0, 100000, 1, 3, 0, "A");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 100000);
    /* camera 1's frame waits for camera 0's; camera 0 falls silent again: when it turns
     * absent, the frame held makes the set without a new message */
    send(1, 110000, 2, 2, 0, "B");
    set_once_camera_0_is_absent(110000);
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_E_TIMEOUT); /* nothing held now */

    /* a set camera outside the layout: the layout's first (the source hears only those);
     * outside the rig: refused */
    rp_lsrc_close(&g_src);
    g_cfg.hal.set_cam = 2;
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_OK);
    assert_int_equal(g_src.set_cam, 0);
    rp_lsrc_close(&g_src);
    g_cfg.hal.set_cam = 3;
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_lsrc_errmsg(&g_src), "set_camera 3 is not a camera of the rig"));
    g_cfg.hal.set_cam = 0;
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_OK);
}

/* Camera cam's message saying it had no image (a multi-camera front end's MISSING state). */
static void send_missing(uint8_t cam, int64_t utime, int32_t seq)
{
    rp_pub_fill_features(&g_m, cam, utime, seq, NULL, 0);
    g_m.state = RIGPOSE_STATUS_T_CAM_MISSING;
    memcpy(g_m.instance, cam ? "B" : "A", 1);
    char ch[RP_CFG_CHANNEL_MAX + 8];
    assert_int_equal(rp_feats_channel(g_cfg.features_channel, cam, ch, sizeof ch), 0);
    assert_int_equal(rp_pub_features(g_lcm, ch, &g_m), RP_PUB_OK);
}

/* A slow estimator: frames queued before a grab are read first, the set camera's newest makes
 * the set, the older ones are skipped. A MISSING message neither replaces a held image nor
 * makes a set nor bounds its camera's next frames. A set camera never heard is absent
 * timeout_ms after the source opened. */
static void test_latest_backlog_missing_and_never_heard(void **state)
{
    (void)state;
    send(0, 100000, 0, 5, 0, "A");
    send(0, 133000, 1, 5, 0, "A");
    send(0, 166000, 2, 5, 0, "A");
    send(1, 150000, 0, 2, 0, "B");
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK);
    assert_true(g_set.utime == 166000);
    assert_int_equal(g_set.cam[0].seq, 2);
    assert_int_equal(g_set.feats->cam_dt_us[1], -16000);
    assert_int_equal(g_src.n_skipped, 2);

    send(1, 180000, 1, 2, 0, "B");
    send_missing(1, 199000, 2);        /* no image: camera 1's frame of 180000 stays held */
    send(1, 190000, 3, 3, 0, "B");     /* after 180000, before the MISSING stamp: not late */
    send_missing(0, 199000, 3);        /* the set camera without an image: no set */
    assert_int_equal(rp_lsrc_grab(&g_src, &g_set), RP_HAL_OK); /* camera 0 silent: absent */
    assert_true(g_set.utime == 190000);
    assert_int_equal(g_set.feats->n[1], 3);
    assert_int_equal(g_src.n_late, 0);
    assert_int_equal(g_src.n_skipped, 3);

    /* a new source; its set camera never heard: after timeout_ms camera 1's frames make sets */
    rp_lsrc_close(&g_src);
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_OK);
    send(1, 300000, 4, 2, 0, "B");
    set_once_camera_0_is_absent(300000);
    assert_non_null(strstr(rp_lsrc_errmsg(&g_src), "its front end not heard yet"));
}

static void test_a_tolerance_over_a_second_is_refused(void **state)
{
    (void)state;
    rp_lsrc_close(&g_src);
    g_cfg.hal.sync_tol_us = RP_LSRC_TOL_MAX_US + 1;
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_E_ARG);
    assert_non_null(strstr(rp_lsrc_errmsg(&g_src), "sync_tol_us 1000001 outside 0..1000000"));
    g_cfg.hal.sync_tol_us = RP_LSRC_TOL_MAX_US;
    assert_int_equal(rp_lsrc_open(&g_src, g_lcm, &g_cfg), RP_HAL_OK);
}

static void test_layout_cameras_and_partners(void **state)
{
    (void)state;
    rp_pipe_cfg_t pc;
    uint8_t want[RP_MAX_CAMS];
    assert_int_equal(rp_pipe_default_cfg(RP_PIPE_STEREO4, &pc), RP_OK);
    assert_int_equal(rp_feats_layout_cams(&pc, 6, want), 4); /* pairs (0,4), (2,5) */
    assert_true(want[0] && want[4] && want[2] && want[5] && !want[1] && !want[3]);
    assert_int_equal(rp_feats_partner(&pc, 4), 0);
    assert_int_equal(rp_feats_partner(&pc, 2), 5);
    assert_int_equal(rp_feats_partner(&pc, 1), -1);
    assert_int_equal(rp_pipe_default_cfg(RP_PIPE_CAM3, &pc), RP_OK);
    assert_int_equal(rp_feats_layout_cams(&pc, 6, want), 1);
    assert_true(want[2]);
    assert_int_equal(rp_feats_partner(&pc, 2), -1);
    char ch[8];
    assert_int_equal(rp_feats_channel("FE_CAMX", 3, ch, sizeof ch), -1); /* 8 + NUL > 8 */
    assert_int_equal(rp_feats_channel("FE_CA", 3, ch, sizeof ch), 0);
    assert_string_equal(ch, "FE_CA3");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_a_set_of_every_camera_goes_out_at_once, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_moved_past_late_and_bad_messages, setup, teardown),
        cmocka_unit_test_setup_teardown(test_a_silent_camera_is_gone_then_rejoins, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_a_timeout_with_nothing_heard, setup, teardown),
        cmocka_unit_test_setup_teardown(test_each_camera_at_its_own_time, setup, teardown),
        cmocka_unit_test_setup_teardown(test_latest_a_set_per_frame_of_the_set_camera,
                                        setup_latest, teardown),
        cmocka_unit_test_setup_teardown(test_latest_any_camera_and_a_gone_set_camera,
                                        setup_latest, teardown),
        cmocka_unit_test_setup_teardown(test_latest_backlog_missing_and_never_heard,
                                        setup_latest, teardown),
        cmocka_unit_test_setup_teardown(test_a_tolerance_over_a_second_is_refused, setup,
                                        teardown),
        cmocka_unit_test(test_layout_cameras_and_partners),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
