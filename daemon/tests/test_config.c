/*
 * test_config.c - the configuration file (platform/src/rp_config.c, schema config/README.md):
 * the embedded default loads into the simulator's rig; defaults fill what a file leaves out;
 * every bad file (missing keys, wrong types, impossible values, unknown keys, broken YAML) is
 * refused with its own status and a message "FILE:LINE: KEY: ..." naming the right line and key;
 * no truncation of a valid file crashes the parser; hostile files (deep nesting, a second
 * document, too large, control characters in values) are refused fast with an escaped message;
 * intrinsics outside the sane range and distortion that folds inside the image are refused
 * while real lenses' calibrations pass.
 */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../../host_tools/common/rp_cfg_diff.h"
#include "rigpose/rp_config.h"
#include "rigpose/rp_rot.h"
#include "rp_test.h"

/* A valid two-camera v4l2 file; the bad cases below edit one of its lines (numbers at left). */
static const char *const base[] = {
    /*  1 */ "version: 1",
    /*  2 */ "source:",
    /*  3 */ "  kind: v4l2",
    /*  4 */ "  timeout_ms: 500",
    /*  5 */ "cameras:",
    /*  6 */ "  - name: left",
    /*  7 */ "    device: /dev/video0",
    /*  8 */ "    width: 640",
    /*  9 */ "    height: 480",
    /* 10 */ "    intrinsics: [500, 500, 320, 240]",
    /* 11 */ "    position: [0, 0, 0]",
    /* 12 */ "    angles: [0, 0, 0]",
    /* 13 */ "  - name: right",
    /* 14 */ "    device: /dev/video1",
    /* 15 */ "    width: 640",
    /* 16 */ "    height: 480",
    /* 17 */ "    intrinsics: [500, 500, 320, 240]",
    /* 18 */ "    distortion: [0.1, -0.05, 0, 0, 0]",
    /* 19 */ "    position: [0.1, 0, 0]",
    /* 20 */ "    angles: [0, 0, 0]",
    /* 21 */ "estimator:",
    /* 22 */ "  method: stereo2",
    /* 23 */ "  pairs: [[left, right]]",
    /* 24 */ "lcm:",
    /* 25 */ "  pose_channel: P",
};
#define N_BASE (sizeof base / sizeof base[0])

static char g_text[8192];
static rp_config_t g_cfg;
static char g_err[RP_CFG_ERR_MAX];

/* The base file with line `line` (1-based; 0: none) replaced by `with` (NULL: deleted). */
static const char *edited(unsigned line, const char *with)
{
    size_t n = 0;
    g_text[0] = '\0';
    for (unsigned i = 0; i < N_BASE; ++i) {
        const char *l = (i + 1 == line) ? with : base[i];
        if (l != NULL) {
            n += (size_t)snprintf(g_text + n, sizeof g_text - n, "%s\n", l);
        }
    }
    return g_text;
}

static rp_cfg_status_t parse(const char *text)
{
    return rp_config_parse(text, strlen(text), "bad.yaml", &g_cfg, g_err, sizeof g_err);
}

static void test_base_file_is_valid(void **state)
{
    (void)state;
    const rp_cfg_status_t st = parse(edited(0, NULL));
    if (st != RP_CFG_OK) {
        fail_msg("base: %s", g_err);
    }
    assert_int_equal(g_cfg.rig.n_cams, 2);
    assert_int_equal(g_cfg.hal.kind, RP_HAL_SRC_V4L2);
    assert_int_equal(g_cfg.hal.timeout_ms, 500);
    assert_string_equal(g_cfg.hal.cam[1].device, "/dev/video1");
    assert_int_equal(g_cfg.pipe.layout, RP_PIPE_STEREO2);
    assert_int_equal(g_cfg.pipe.stereo.n_pairs, 1);
    assert_int_equal(g_cfg.pipe.stereo.pair_a[0], 0);
    assert_int_equal(g_cfg.pipe.stereo.pair_b[0], 1);
    assert_near(g_cfg.rig.cam[1].D[0], 0.1, RP_TOL_TIGHT);
    assert_near(g_cfg.rig.cam[1].cam.k1, 0.1, RP_TOL_TIGHT);
    assert_near(g_cfg.rig.cam[1].cam.k2, -0.05, RP_TOL_TIGHT);
    /* Defaults for what the file leaves out. */
    assert_int_equal(g_cfg.hal.sync_tol_us, 5000);
    assert_int_equal(g_cfg.hal.retry_ms, 1000);
    assert_int_equal(g_cfg.hal.cam[0].fps, 30);
    assert_near(g_cfg.pipe.stereo.ekf.sigma_px, 0.5, RP_TOL_TIGHT);
    assert_int_equal(g_cfg.pipe.stereo.min_tracked, 50);
    assert_string_equal(g_cfg.lcm_url, "udpm://239.255.76.67:7667?ttl=0");
    assert_string_equal(g_cfg.pose_channel, "P");
    assert_string_equal(g_cfg.status_channel, "RIGPOSE_STATUS");
    assert_string_equal(g_cfg.image_channel, "");
    assert_int_equal(g_cfg.status_every, 1);
    assert_int_equal(g_cfg.pipe.track.target, 150);
    assert_int_equal(g_cfg.pipe.track.reset_q8, 205);
}

/* config/sim.yaml is the simulator's rig (rp_sim_make_rig) with stereo4 on its two pairs. */
static void test_embedded_default_is_the_simulated_rig(void **state)
{
    (void)state;
    if (rp_config_load("config/sim.yaml", &g_cfg, g_err, sizeof g_err) != RP_CFG_OK) {
        fail_msg("config/sim.yaml: %s", g_err);
    }
    rp_sim_cfg_t sc;
    rp_rig_t rig;
    rp_sim_default_cfg(&sc);
    rp_sim_make_rig(&sc, &rig);
    assert_int_equal(g_cfg.rig.n_cams, rig.n_cams);
    double worst = 0.0;
    for (int k = 0; k < rig.n_cams; ++k) {
        for (int i = 0; i < 9; ++i) {
            worst = fmax(worst, fabs((double)(g_cfg.rig.cam[k].R[i] - rig.cam[k].R[i])));
        }
        for (int i = 0; i < 3; ++i) {
            worst = fmax(worst, fabs((double)(g_cfg.rig.cam[k].D[i] - rig.cam[k].D[i])));
        }
        worst = fmax(worst, fabs((double)(g_cfg.rig.cam[k].cam.fx - rig.cam[k].cam.fx)));
        worst = fmax(worst, fabs((double)(g_cfg.rig.cam[k].cam.cx - rig.cam[k].cam.cx)));
        worst = fmax(worst, fabs((double)(g_cfg.rig.cam[k].cam.cy - rig.cam[k].cam.cy)));
    }
    printf("config/sim.yaml vs rp_sim_make_rig: largest difference %.3g\n", worst);
    assert_true(worst < RP_TOL(1e-12, 1e-6));
    assert_int_equal(g_cfg.hal.kind, RP_HAL_SRC_SIM);
    assert_int_equal(g_cfg.pipe.layout, RP_PIPE_STEREO4);
    assert_int_equal(g_cfg.pipe.stereo.n_pairs, 2);
    assert_int_equal(g_cfg.pipe.stereo.pair_a[0], RP_SIM_CAM1);
    assert_int_equal(g_cfg.pipe.stereo.pair_b[0], RP_SIM_CAM1B);
    assert_int_equal(g_cfg.pipe.stereo.pair_a[1], RP_SIM_CAM3);
    assert_int_equal(g_cfg.pipe.stereo.pair_b[1], RP_SIM_CAM3B);
    assert_int_equal(g_cfg.sim.drop_cam, -1);
    assert_near(g_cfg.sim.noise_px, 0.5, 1e-12);
    assert_int_equal(g_cfg.sim.motion, 0); /* the paper's */
    assert_string_equal(g_cfg.instance, ""); /* the daemon's HOST:PID */
}

/* The file at path into buf (cap bytes), NUL-terminated; fails the test if it cannot be read. */
static void read_text(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    const size_t n = fread(buf, 1, cap - 1, f);
    fclose(f);
    buf[n] = '\0';
}

/* source.sim.motion (paper, turn, pitch; another word refused naming it) and lcm.instance. */
static void test_sim_motion_and_instance(void **state)
{
    (void)state;
    static char text[16384];
    read_text("config/sim.yaml", text, sizeof text);
    static const char *const words[4] = {"paper", "turn", "pitch", "spin"};
    for (int w = 0; w < 4; ++w) {
        static char edited_text[16640];
        const char *at = strstr(text, "    noise_px: 0.5\n");
        assert_non_null(at);
        const size_t head = (size_t)(at - text) + strlen("    noise_px: 0.5\n");
        snprintf(edited_text, sizeof edited_text, "%.*s    motion: %s\n%s", (int)head, text,
                 words[w], text + head);
        const rp_cfg_status_t st =
            rp_config_parse(edited_text, strlen(edited_text), "m.yaml", &g_cfg, g_err,
                            sizeof g_err);
        if (w < 3) {
            assert_int_equal(st, RP_CFG_OK);
            assert_int_equal(g_cfg.sim.motion, w);
        } else {
            assert_int_equal(st, RP_CFG_E_RANGE);
            assert_non_null(strstr(g_err, "source.sim.motion: 'spin' is not one of"));
        }
    }
    static char with_instance[16640];
    snprintf(with_instance, sizeof with_instance, "%s  instance: board-7\n", text);
    assert_int_equal(rp_config_parse(with_instance, strlen(with_instance), "i.yaml", &g_cfg, g_err,
                                     sizeof g_err), RP_CFG_OK);
    assert_string_equal(g_cfg.instance, "board-7");
}

/* tracker.reset_share sets the tracker's reset (0 turns it off). */
static void test_tracker_reset_share(void **state)
{
    (void)state;
    assert_int_equal(parse(edited(25, "  pose_channel: P\ntracker:\n  reset_share: 0.5")),
                     RP_CFG_OK);
    assert_int_equal(g_cfg.pipe.track.reset_q8, 128);
    assert_int_equal(parse(edited(25, "  pose_channel: P\ntracker:\n  reset_share: 0")),
                     RP_CFG_OK);
    assert_int_equal(g_cfg.pipe.track.reset_q8, 0);
}

/* estimator.metric_scale_sigma sets gc's metric scale step (0 turns it off). */
static void test_gc_metric_scale_sigma(void **state)
{
    (void)state;
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  metric_scale_sigma: 0")),
                     RP_CFG_OK);
    assert_near(g_cfg.pipe.gc.mscale_sigma, 0.0, 0.0);
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  metric_scale_sigma: 0.1")),
                     RP_CFG_OK);
    assert_near(g_cfg.pipe.gc.mscale_sigma, 0.1, RP_TOL_TIGHT);
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]")), RP_CFG_OK);
    assert_near(g_cfg.pipe.gc.mscale_sigma, 0.3, RP_TOL_TIGHT);
}

/* cameras[i].time_offset_s is every estimator's start offset of camera i and the v4l2 source's
 * grouping offset; estimator.estimate_time_offsets makes them states (rp_vo_ekf_offsets). */
static void test_time_offsets(void **state)
{
    (void)state;
    assert_int_equal(parse(edited(20, "    angles: [0, 0, 0]\n    time_offset_s: -0.025")),
                     RP_CFG_OK);
    assert_near(g_cfg.cam_time_offset_s[1], -0.025, 0.0);
    assert_true(g_cfg.hal.cam[1].offset_us == -25000); /* v4l2 groups by capture time */
    assert_true(g_cfg.hal.cam[0].offset_us == 0);
    assert_near(g_cfg.pipe.stereo.ekf.toff0_s[1], -0.025, RP_TOL_TIGHT);
    assert_near(g_cfg.pipe.gc.ekf.toff0_s[1], -0.025, RP_TOL_TIGHT);
    assert_near(g_cfg.pipe.stereo.ekf.toff0_s[0], 0.0, 0.0);
    assert_int_equal(g_cfg.pipe.stereo.ekf.toff_estimate, 0);
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  estimate_time_offsets: true\n"
                                      "  time_offset_sigma_s: 0.05")),
                     RP_CFG_OK);
    assert_int_equal(g_cfg.pipe.stereo.ekf.toff_estimate, 1);
    assert_near(g_cfg.pipe.stereo.ekf.toff_sigma_s, 0.05, RP_TOL_TIGHT);
    assert_int_equal(parse(edited(20, "    angles: [0, 0, 0]\n    time_offset_s: 2")),
                     RP_CFG_E_RANGE);
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  time_offset_sigma_s: 0")),
                     RP_CFG_E_RANGE);
}

/* `angles` is the paper's R = Rz(gamma) Ry(beta) Rx(alpha). */
static void test_angles_match_the_rotation_module(void **state)
{
    (void)state;
    assert_int_equal(parse(edited(20, "    angles: [0.1, -0.2, 0.3]")), RP_CFG_OK);
    const rp_real abg[3] = {RP_C(0.1), RP_C(-0.2), RP_C(0.3)};
    rp_real R[9];
    rp_rot_from_angles(abg, R);
    for (int i = 0; i < 9; ++i) {
        assert_near(g_cfg.rig.cam[1].R[i], R[i], RP_TOL_TIGHT);
    }
}

typedef struct {
    unsigned line;        /* line of the base file replaced */
    const char *with;     /* its replacement (NULL: deleted) */
    rp_cfg_status_t want;
    const char *where;    /* expected start of the message: "bad.yaml:LINE: KEY" */
} bad_case_t;

static const bad_case_t bad[] = {
    /* missing keys */
    {1, NULL, RP_CFG_E_MISSING, "bad.yaml:1: version: missing"},
    {3, NULL, RP_CFG_E_MISSING, "bad.yaml:3: source.kind: missing"},
    {7, NULL, RP_CFG_E_MISSING, "bad.yaml:6: cameras[0].device: missing"},
    {10, NULL, RP_CFG_E_MISSING, "bad.yaml:6: cameras[0].intrinsics: missing"},
    {20, NULL, RP_CFG_E_MISSING, "bad.yaml:13: cameras[1].rotation: missing"},
    {22, NULL, RP_CFG_E_MISSING, "bad.yaml:22: estimator.method: missing"},
    {23, NULL, RP_CFG_E_MISSING, "bad.yaml:22: estimator.pairs: missing"},
    {25, "  pose_channel: P\nlcm_typo: 1", RP_CFG_E_UNKNOWN, "bad.yaml:26: lcm_typo: unknown key"},
    /* wrong types */
    {4, "  timeout_ms: fast", RP_CFG_E_TYPE, "bad.yaml:4: source.timeout_ms: expected an integer"},
    {4, "  timeout_ms: \"500\"", RP_CFG_E_TYPE, "bad.yaml:4: source.timeout_ms: expected an integer"},
    {8, "    width: 640.5", RP_CFG_E_TYPE, "bad.yaml:8: cameras[0].width: expected an integer"},
    {10, "    intrinsics: [500, 500, 320]", RP_CFG_E_TYPE,
     "bad.yaml:10: cameras[0].intrinsics: expected 4 numbers, got 3"},
    {10, "    intrinsics: 500", RP_CFG_E_TYPE, "bad.yaml:10: cameras[0].intrinsics: expected a list"},
    {10, "    intrinsics: [500, five, 320, 240]", RP_CFG_E_TYPE,
     "bad.yaml:10: cameras[0].intrinsics: element 1"},
    {1, "version: [1]", RP_CFG_E_TYPE, "bad.yaml:1: version: expected an integer, got a sequence"},
    {25, "tracker: 5", RP_CFG_E_TYPE, "bad.yaml:25: tracker: expected a mapping"},
    {23, "  pairs: [left, right]", RP_CFG_E_TYPE, "bad.yaml:23: estimator.pairs: expected a list of 1 pair"},
    {25, "  pose_channel: [P]", RP_CFG_E_TYPE, "bad.yaml:25: lcm.pose_channel: expected a string"},
    {18, "    distorsion: [0, 0, 0, 0, 0]", RP_CFG_E_UNKNOWN,
     "bad.yaml:18: cameras[1].distorsion: unknown key"},
    /* impossible values */
    {1, "version: 2", RP_CFG_E_RANGE, "bad.yaml:1: version: 2 is outside 1..1"},
    {3, "  kind: usb", RP_CFG_E_RANGE, "bad.yaml:3: source.kind: 'usb' is not one of sim, v4l2, "
     "replay, lcm"},
    {4, "  realtime: soon", RP_CFG_E_TYPE,
     "bad.yaml:4: source.realtime: expected true, false or live"},
    {25, "  features_channel: "
         "F_THIRTY_TWO_CHARACTERS_XXXXXXXXX_THIRTY_TWO_CHARACTERS_XXXXXXXX",
     RP_CFG_E_RANGE, "bad.yaml:25: lcm.features_channel:"},
    {4, "  timeout_ms: 0", RP_CFG_E_RANGE, "bad.yaml:4: source.timeout_ms: 0 is outside"},
    {8, "    width: 1000", RP_CFG_E_RANGE, "bad.yaml:6: cameras[0].width: 1000x480 is larger"},
    {10, "    intrinsics: [-500, 500, 320, 240]", RP_CFG_E_RANGE,
     "bad.yaml:10: cameras[0].intrinsics: fx, fy"},
    {10, "    intrinsics: [500, 500, 700, 240]", RP_CFG_E_RANGE,
     "bad.yaml:10: cameras[0].intrinsics: principal point"},
    {11, "    position: [0.1, 0, 0]", RP_CFG_E_RANGE, "bad.yaml:6: cameras[0]: the first camera"},
    {18, "    distortion: [0.1, -0.05, 0, 0, 1e9]", RP_CFG_E_RANGE,
     "bad.yaml:18: cameras[1].distortion: coefficient 4"},
    {20, "    rotation: [1, 0, 0, 0, 1, 0, 0, 0, 2]", RP_CFG_E_RANGE,
     "bad.yaml:20: cameras[1].rotation: not a rotation"},
    {20, "    rotation: [-1, 0, 0, 0, 1, 0, 0, 0, 1]", RP_CFG_E_RANGE,
     "bad.yaml:20: cameras[1].rotation: not a rotation"},
    {18, "    rotation: [1, 0, 0, 0, 1, 0, 0, 0, 1]", RP_CFG_E_RANGE,
     "bad.yaml:20: cameras[1].angles: give either rotation or angles"},
    {13, "  - name: left", RP_CFG_E_RANGE, "bad.yaml:13: cameras[1].name: 'left' is already"},
    {19, "    position: [1e9, 0, 0]", RP_CFG_E_RANGE, "bad.yaml:19: cameras[1].position: coordinate 0"},
    {22, "  method: stereo3", RP_CFG_E_RANGE, "bad.yaml:22: estimator.method: 'stereo3' is not"},
    {23, "  pairs: [[left, middle]]", RP_CFG_E_RANGE,
     "bad.yaml:23: estimator.pairs[0]: no camera is named 'middle'"},
    {23, "  pairs: [[left, left]]", RP_CFG_E_RANGE,
     "bad.yaml:23: estimator.pairs[0]: camera 'left' is used twice"},
    {23, "  pairs: [[left, right]]\n  sigma_px: 0", RP_CFG_E_RANGE,
     "bad.yaml:24: estimator.sigma_px: 0 is outside (0, 100]"},
    {23, "  pairs: [[left, right]]\n  min_depth_m: 5\n  max_depth_m: 2", RP_CFG_E_RANGE,
     "bad.yaml:25: estimator.max_depth_m: must be larger"},
    {23, "  pairs: [[left, right]]\n  metric_scale_sigma: -1", RP_CFG_E_RANGE,
     "bad.yaml:24: estimator.metric_scale_sigma: -1 is outside"},
    {25, "  pose_channel: ''", RP_CFG_E_RANGE, "bad.yaml:25: lcm.pose_channel: must not be empty"},
    {25, "  status_every: 0", RP_CFG_E_RANGE, "bad.yaml:25: lcm.status_every: 0 is outside"},
    {25, "  pose_channel: P\ntracker:\n  reset_share: 1.5", RP_CFG_E_RANGE,
     "bad.yaml:27: tracker.reset_share: 1.5 is outside"},
    {3, "  kind: sim", RP_CFG_E_RANGE, "bad.yaml:6: cameras: the sim source simulates"},
    {3, "  kind: replay", RP_CFG_E_MISSING, "bad.yaml:3: source.replay_index: missing"},
    {4, "  timeout_ms: 500\n  timeout_ms: 600", RP_CFG_E_RANGE,
     "bad.yaml:5: source.timeout_ms: key given twice"},
    {6, "  - name: \"le\\eft\"", RP_CFG_E_RANGE,
     "bad.yaml:6: cameras[0].name: control character 0x1b at 2: 'le\\x1bft'"},
    {7, "    device: \"/dev/video0\\n\"", RP_CFG_E_RANGE,
     "bad.yaml:7: cameras[0].device: control character 0x0a at 11"},
    /* broken YAML */
    {10, "    intrinsics: [500, 500", RP_CFG_E_SYNTAX, "bad.yaml:11: (yaml):"},
    {6, "  - name: left\n   bad indent: 1", RP_CFG_E_SYNTAX, "bad.yaml:"},
};

static void test_each_bad_file_names_line_and_key(void **state)
{
    (void)state;
    unsigned failures = 0;
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        const rp_cfg_status_t st = parse(edited(bad[i].line, bad[i].with));
        const int ok = st == bad[i].want && strncmp(g_err, bad[i].where, strlen(bad[i].where)) == 0;
        printf("%s %-9s %s\n", ok ? "ok  " : "FAIL", rp_cfg_status_str(st), g_err);
        if (!ok) {
            printf("     wanted %s \"%s...\"\n", rp_cfg_status_str(bad[i].want), bad[i].where);
            ++failures;
        }
    }
    printf("%zu bad files, %u misreported\n", sizeof bad / sizeof bad[0], failures);
    assert_int_equal(failures, 0);
}

static void test_whole_file_errors(void **state)
{
    (void)state;
    assert_int_equal(parse(""), RP_CFG_E_SYNTAX);
    assert_non_null(strstr(g_err, "bad.yaml:0: (top): empty file"));
    assert_int_equal(parse("- 1\n- 2\n"), RP_CFG_E_SYNTAX);
    assert_non_null(strstr(g_err, "bad.yaml:1: (top): expected a mapping"));
    assert_int_equal(rp_config_load("no/such/file.yaml", &g_cfg, g_err, sizeof g_err),
                     RP_CFG_E_OPEN);
    assert_non_null(strstr(g_err, "no/such/file.yaml:0:"));
    assert_int_equal(rp_config_parse(NULL, 0, "x", &g_cfg, g_err, sizeof g_err), RP_CFG_E_ARG);
    assert_int_equal(rp_config_parse("a: 1", 4, "x", NULL, NULL, 0), RP_CFG_E_ARG);
    /* meta: is free-form. */
    char text[8192];
    snprintf(text, sizeof text, "%smeta:\n  written_by: rigpose-calib\n  rms_px: [0.2, 0.3]\n",
             edited(0, NULL));
    assert_int_equal(parse(text), RP_CFG_OK);
}

/* Every byte of the message is printable ASCII. */
static void assert_printable(const char *msg)
{
    for (const unsigned char *p = (const unsigned char *)msg; *p != '\0'; p++) {
        if (*p < 0x20 || *p >= 0x7f) {
            fail_msg("byte 0x%02x in message: %s", *p, msg);
        }
    }
}

static double seconds_since(clock_t t0) { return (double)(clock() - t0) / CLOCKS_PER_SEC; }

/* Hostile files are refused with RP_CFG_E_SYNTAX before a document is built: nesting deeper
 * than RP_CFG_MAX_DEPTH anywhere (100,000 levels under meta: took libyaml's loader over a
 * minute), a second document, more than RP_CFG_MAX_BYTES; control characters from a value are
 * escaped in the message. */
static void test_hostile_files(void **state)
{
    (void)state;
    static char text[400000];
    /* 100,000 flow levels under meta: refused at once. */
    size_t n = (size_t)snprintf(text, sizeof text, "%smeta: ", edited(0, NULL));
    for (int i = 0; i < 100000; ++i) {
        text[n++] = '[';
    }
    for (int i = 0; i < 100000; ++i) {
        text[n++] = ']';
    }
    text[n++] = '\n';
    text[n] = '\0';
    clock_t t0 = clock();
    assert_int_equal(parse(text), RP_CFG_E_SYNTAX);
    printf("100,000 levels under meta: %s (%.3f s)\n", g_err, seconds_since(t0));
    assert_non_null(strstr(g_err, "bad.yaml:26: (yaml): nested deeper than 32 levels"));
    assert_true(seconds_since(t0) < 2.0);
    /* 40 block levels refused, 31 accepted (the top mapping is level 1). */
    for (int levels = 31; levels <= 40; levels += 9) {
        n = (size_t)snprintf(text, sizeof text, "%smeta:\n", edited(0, NULL));
        for (int i = 1; i < levels; ++i) {
            n += (size_t)snprintf(text + n, sizeof text - n, "%*sk%d:\n", 2 * i, "", i);
        }
        n += (size_t)snprintf(text + n, sizeof text - n, "%*sleaf: 1\n", 2 * levels, "");
        const rp_cfg_status_t st = parse(text);
        printf("%d levels: %s\n", levels + 1, st == RP_CFG_OK ? "accepted" : g_err);
        assert_int_equal(st, levels == 31 ? RP_CFG_OK : RP_CFG_E_SYNTAX);
    }
    /* 100,001 nodes under meta: refused; 90,000 accepted. */
    for (int nodes = 90000; nodes <= 100001; nodes += 10001) {
        n = (size_t)snprintf(text, sizeof text, "%smeta: [", edited(0, NULL));
        for (int i = 0; i < nodes; ++i) {
            n += (size_t)snprintf(text + n, sizeof text - n, "%s1", i ? "," : "");
        }
        snprintf(text + n, sizeof text - n, "]\n");
        const rp_cfg_status_t st = parse(text);
        printf("%d nodes under meta: %s\n", nodes, st == RP_CFG_OK ? "accepted" : g_err);
        assert_int_equal(st, nodes == 90000 ? RP_CFG_OK : RP_CFG_E_SYNTAX);
    }
    assert_non_null(strstr(g_err, "bad.yaml:26: (yaml): more than 100000 nodes"));
    /* A second document, even a valid one. */
    snprintf(text, sizeof text, "%s---\n%s", edited(0, NULL), edited(0, NULL));
    assert_int_equal(parse(text), RP_CFG_E_SYNTAX);
    printf("second document: %s\n", g_err);
    assert_non_null(strstr(g_err, "bad.yaml:26: (yaml): a second document"));
    /* Larger than RP_CFG_MAX_BYTES, in memory and as a file (padded with a comment). */
    char *big = malloc((size_t)RP_CFG_MAX_BYTES + 100);
    assert_non_null(big);
    n = (size_t)snprintf(big, (size_t)RP_CFG_MAX_BYTES + 100, "%s#", edited(0, NULL));
    memset(big + n, 'x', (size_t)RP_CFG_MAX_BYTES + 98 - n);
    big[RP_CFG_MAX_BYTES + 98] = '\n';
    big[RP_CFG_MAX_BYTES + 99] = '\0';
    assert_int_equal(rp_config_parse(big, strlen(big), "big.yaml", &g_cfg, g_err, sizeof g_err),
                     RP_CFG_E_SYNTAX);
    assert_non_null(strstr(g_err, "big.yaml:0: (file): larger than 1048576 bytes"));
    char path[] = "/tmp/rp_cfg_big_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_true(write(fd, big, strlen(big)) == (ssize_t)strlen(big));
    close(fd);
    assert_int_equal(rp_config_load(path, &g_cfg, g_err, sizeof g_err), RP_CFG_E_SYNTAX);
    printf("big file: %s\n", g_err);
    assert_non_null(strstr(g_err, "larger than 1048576 bytes"));
    /* The same file cut under the limit loads. */
    assert_int_equal(truncate(path, 100000), 0);
    assert_int_equal(rp_config_load(path, &g_cfg, g_err, sizeof g_err), RP_CFG_OK);
    remove(path);
    free(big);
    assert_int_equal(rp_config_load("/tmp", &g_cfg, g_err, sizeof g_err), RP_CFG_E_OPEN);
    assert_non_null(strstr(g_err, "/tmp:0: (file): is a directory"));
    /* Control characters of a value (a terminal escape, a newline) come out escaped. */
    assert_int_equal(parse(edited(23, "  pairs: [[left, \"r\\e[2J\\nrm -rf\\u0085x\"]]")),
                     RP_CFG_E_RANGE);
    printf("escaped: %s\n", g_err);
    assert_printable(g_err);
    assert_non_null(strstr(g_err, "no camera is named 'r\\x1b[2J\\x0arm -rf\\xc2\\x85x'"));
    assert_int_equal(parse(edited(22, "  method: st\xff\xfe")), RP_CFG_E_SYNTAX); /* not UTF-8 */
    printf("invalid UTF-8: %s\n", g_err);
    assert_printable(g_err);
    assert_non_null(strstr(g_err, "bad.yaml:22: (yaml): invalid leading UTF-8 octet at byte"));
}

/* Intrinsics: fx, fy within [0.1, 100] x the larger image side, fy / fx within [1/4, 4]. */
static void test_intrinsics_range(void **state)
{
    (void)state;
    static const struct {
        const char *in;
        int ok;
    } cases[] = {
        {"[500, 500, 320, 240]", 1},      {"[64, 64, 320, 240]", 1},
        {"[64000, 64000, 320, 240]", 1},  {"[500, 1999, 320, 240]", 1},
        {"[1e-300, 500, 320, 240]", 0},   {"[500, 1e-300, 320, 240]", 0},
        {"[63, 63, 320, 240]", 0},        {"[64001, 64001, 320, 240]", 0},
        {"[1e9, 1e9, 320, 240]", 0},      {"[500, 2001, 320, 240]", 0},
        {"[500, 124, 320, 240]", 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char line[96];
        snprintf(line, sizeof line, "    intrinsics: %s", cases[i].in);
        const rp_cfg_status_t st = parse(edited(10, line));
        printf("intrinsics %-26s %s\n", cases[i].in, st == RP_CFG_OK ? "accepted" : g_err);
        assert_int_equal(st, cases[i].ok ? RP_CFG_OK : RP_CFG_E_RANGE);
        if (!cases[i].ok) {
            assert_non_null(strstr(g_err, "bad.yaml:10: cameras[0].intrinsics: f"));
        }
    }
}

/* Distortion that folds inside the image (rays turning back, pixels without a ray) or stretches
 * it beyond what a lens does is refused, naming the pixel; real calibrations pass: EuRoC's
 * cam0, OpenCV's sample camera, KITTI raw's camera 0 (scaled to 640x480 where larger). */
static void test_distortion_folding_inside_the_image(void **state)
{
    (void)state;
    static const struct {
        const char *intr, *dist;
        int ok;
        int height; /* of the camera (0: the base's 480) */
    } cases[] = {
        {"[458.654, 457.296, 320, 240]", "[-0.28340811, 0.07395907, 0.00019359, 1.76e-05, 0]", 1, 0},
        {"[536.07, 536.02, 342.37, 235.54]", "[-0.2651, -0.0467, 0.0018, -0.0003, 0.2523]", 1, 0},
        {"[441.2, 441.2, 320, 117.5]", "[-0.3691481, 0.1968681, 0.001353473, 0.0005677587, "
                                       "-0.06770705]", 1, 235},
        /* KITTI's model folds at a distorted radius of 0.81: a taller image reaches the fold */
        {"[441.2, 441.2, 320, 240]", "[-0.3691481, 0.1968681, 0.001353473, 0.0005677587, "
                                     "-0.06770705]", 0, 0},
        {"[500, 500, 320, 240]", "[0.1, -0.05, 0, 0, 0]", 1, 0},
        {"[500, 500, 320, 240]", "[2, 0, 0, 0, 0]", 1, 0},
        {"[500, 500, 320, 240]", "[99, 0, 0, 0, 0]", 0, 0},
        {"[500, 500, 320, 240]", "[-99, 0, 0, 0, 0]", 0, 0},
        {"[500, 500, 320, 240]", "[-1, 0, 0, 0, 0]", 0, 0},
        {"[500, 500, 320, 240]", "[0, 99, 0, 0, 0]", 0, 0},
        {"[500, 500, 320, 240]", "[0, -99, 0, 0, 0]", 0, 0},
        {"[500, 500, 320, 240]", "[0, 0, 99, 0, 0]", 0, 0},
        {"[500, 500, 320, 240]", "[0, 0, 0, -99, 0]", 0, 0},
        {"[500, 500, 320, 240]", "[0, 0, 0, 0, 99]", 0, 0},
        {"[500, 500, 320, 240]", "[0, 0, 0, 0, -99]", 0, 0},
        {"[500, 500, 320, 240]", "[-0.5, 0.01, 0, 0, 0]", 0, 0},
        {"[800, 800, 320, 240]", "[0, 0, 0.5, 0, 0]", 0, 0},
    };
    unsigned misjudged = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char lines[160];
        snprintf(lines, sizeof lines, "    height: %d\n    intrinsics: %s\n    distortion: %s",
                 cases[i].height > 0 ? cases[i].height : 480, cases[i].intr, cases[i].dist);
        edited(18, NULL);
        char text[8192];
        snprintf(text, sizeof text, "%s", g_text); /* lines 1..17, 19.. of the base */
        const char *at = strstr(text, "    height: 480\n    intrinsics: [500, 500, 320, 240]\n"
                                      "    position: [0.1");
        assert_non_null(at);
        char out[8192];
        snprintf(out, sizeof out, "%.*s%s%s", (int)(at - text), text, lines,
                 at + strlen("    height: 480\n    intrinsics: [500, 500, 320, 240]"));
        const rp_cfg_status_t st = parse(out);
        const int ok = cases[i].ok ? st == RP_CFG_OK
                                   : st == RP_CFG_E_RANGE &&
                                         strstr(g_err, "bad.yaml:18: cameras[1].distortion: ") ==
                                             g_err;
        printf("%s %-34s %s\n", ok ? "ok  " : "FAIL", cases[i].dist,
               st == RP_CFG_OK ? "accepted" : g_err);
        misjudged += !ok;
    }
    assert_int_equal(misjudged, 0);
}

/* A replay index is found relative to the configuration file's folder. */
static void test_replay_index_is_relative_to_the_file(void **state)
{
    (void)state;
    const char *t = edited(3, "  kind: replay\n  replay_index: frames.csv");
    assert_int_equal(rp_config_parse(t, strlen(t), "runs/a/rig.yaml", &g_cfg, g_err, sizeof g_err),
                     RP_CFG_OK);
    assert_string_equal(g_cfg.hal.replay_index, "runs/a/frames.csv");
    t = edited(3, "  kind: replay\n  replay_index: /data/frames.csv");
    assert_int_equal(rp_config_parse(t, strlen(t), "runs/a/rig.yaml", &g_cfg, g_err, sizeof g_err),
                     RP_CFG_OK);
    assert_string_equal(g_cfg.hal.replay_index, "/data/frames.csv");
}

/* The front ends' and the estimator's keys: source.kind lcm, realtime live, and each camera's
 * features channel (lcm.features_channel + index). */
static void test_distributed_keys(void **state)
{
    (void)state;
    const char *t = edited(3, "  kind: lcm");
    assert_int_equal(parse(t), RP_CFG_OK);
    assert_int_equal(g_cfg.hal.kind, RP_HAL_SRC_LCM);
    assert_string_equal(g_cfg.features_channel, "RIGPOSE_FEATURES_CAM");
    assert_int_equal(g_cfg.hal.realtime, RP_HAL_PACE_FAST);
    t = edited(4, "  realtime: live");
    assert_int_equal(parse(t), RP_CFG_OK);
    assert_int_equal(g_cfg.hal.realtime, RP_HAL_PACE_LIVE);
    t = edited(4, "  realtime: true");
    assert_int_equal(parse(t), RP_CFG_OK);
    assert_int_equal(g_cfg.hal.realtime, RP_HAL_PACE_SPACED);
    t = edited(25, "  features_channel: FE_CAM");
    assert_int_equal(parse(t), RP_CFG_OK);
    assert_string_equal(g_cfg.features_channel, "FE_CAM");
    /* the longest prefix leaves room for one digit and the NUL */
    static char longest[RP_CFG_CHANNEL_MAX + 32];
    const int head = snprintf(longest, sizeof longest, "  features_channel: ");
    memset(longest + head, 'F', RP_CFG_CHANNEL_MAX - 2);
    longest[head + RP_CFG_CHANNEL_MAX - 2] = '\0';
    t = edited(25, longest);
    assert_int_equal(parse(t), RP_CFG_OK);
    assert_int_equal(strlen(g_cfg.features_channel), RP_CFG_CHANNEL_MAX - 2);
    longest[head + RP_CFG_CHANNEL_MAX - 2] = 'F';
    longest[head + RP_CFG_CHANNEL_MAX - 1] = '\0';
    t = edited(25, longest);
    assert_int_equal(parse(t), RP_CFG_E_RANGE);
}

/* source.sets / set_camera: matched by default; latest with the first camera, a named one or
 * any; a bad value, an unknown camera, or set_camera without latest refused. */
static void test_source_sets(void **state)
{
    (void)state;
    assert_int_equal(parse(edited(0, NULL)), RP_CFG_OK);
    assert_int_equal(g_cfg.hal.sets_latest, 0);
    static const struct { const char *line; rp_cfg_status_t st; uint8_t latest; int8_t cam; } cases[] = {
        {"  timeout_ms: 500\n  sets: latest", RP_CFG_OK, 1, 0},
        {"  timeout_ms: 500\n  sets: latest\n  set_camera: right", RP_CFG_OK, 1, 1},
        {"  timeout_ms: 500\n  sets: latest\n  set_camera: any", RP_CFG_OK, 1, -1},
        {"  timeout_ms: 500\n  sets: matched", RP_CFG_OK, 0, 0},
        {"  timeout_ms: 500\n  sets: newest", RP_CFG_E_RANGE, 0, 0},
        {"  timeout_ms: 500\n  sets: latest\n  set_camera: middle", RP_CFG_E_RANGE, 0, 0},
        {"  timeout_ms: 500\n  set_camera: right", RP_CFG_E_RANGE, 0, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        const rp_cfg_status_t st = parse(edited(4, cases[i].line));
        if (st != cases[i].st) {
            fail_msg("case %zu: %d (%s)", i, (int)st, g_err);
        }
        if (st == RP_CFG_OK) {
            assert_int_equal(g_cfg.hal.sets_latest, cases[i].latest);
            assert_int_equal(g_cfg.hal.set_cam, cases[i].cam);
        } else {
            assert_non_null(strstr(g_err, "source.set"));
        }
    }
}

/* The non-overlapping methods pick their cameras by name (cam1..cam4) or from `cams`. */
static void test_single_camera_methods(void **state)
{
    (void)state;
    if (rp_config_load("config/sim.yaml", &g_cfg, g_err, sizeof g_err) != RP_CFG_OK) {
        fail_msg("%s", g_err);
    }
    /* Rewrite the method line of sim.yaml in memory. */
    static char text[16384];
    FILE *f = fopen("config/sim.yaml", "rb");
    assert_non_null(f);
    const size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    char *m = strstr(text, "  method: stereo4");
    assert_non_null(m);
    static const struct { const char *line; rp_pipe_layout_t want; uint8_t cam0; } cases[] = {
        {"  method: rc     ", RP_PIPE_RC, 0},
        {"  method: cam3   ", RP_PIPE_CAM3, 2},
        {"  method: gc     ", RP_PIPE_GC, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        memcpy(m, cases[i].line, strlen(cases[i].line));
        const rp_cfg_status_t st = rp_config_parse(text, n, "sim.yaml", &g_cfg, g_err, sizeof g_err);
        if (cases[i].want == RP_PIPE_GC) {
            /* gc needs its camera list: sim.yaml has only pairs. */
            assert_int_equal(st, RP_CFG_E_MISSING);
            assert_non_null(strstr(g_err, "estimator.cams: missing"));
            continue;
        }
        if (st != RP_CFG_OK) {
            fail_msg("%s", g_err);
        }
        assert_int_equal(g_cfg.pipe.layout, cases[i].want);
        if (cases[i].want == RP_PIPE_RC) {
            assert_int_equal(g_cfg.pipe.rc_n, 4);
            assert_int_equal(g_cfg.pipe.rc_cams[0], cases[i].cam0);
            assert_int_equal(g_cfg.pipe.rc_cams[3], 3);
        } else {
            assert_int_equal(g_cfg.pipe.mono.cam, cases[i].cam0);
        }
    }
    /* rc with a list: 2..4 cameras (a rig of two, e.g. a stereo rig's cameras used singly);
     * one camera is not a fusion and is refused */
    const char *const m_rc = "  method: rc     ";
    memcpy(m, m_rc, strlen(m_rc));
    char *pl = strstr(text, "  pairs: [[cam1, cam1b], [cam3, cam3b]]");
    assert_non_null(pl);
    static const struct { const char *line; rp_cfg_status_t st; uint8_t n; } lists[] = {
        {"  cams: [cam1, cam3]                   ", RP_CFG_OK, 2},
        {"  cams: [cam1, cam2, cam4]             ", RP_CFG_OK, 3},
        {"  cams: [cam1]                         ", RP_CFG_E_TYPE, 0},
    };
    for (size_t i = 0; i < sizeof lists / sizeof lists[0]; ++i) {
        assert_int_equal(strlen(lists[i].line), strlen("  pairs: [[cam1, cam1b], [cam3, cam3b]]"));
        memcpy(pl, lists[i].line, strlen(lists[i].line));
        const rp_cfg_status_t st = rp_config_parse(text, n, "sim.yaml", &g_cfg, g_err, sizeof g_err);
        assert_int_equal(st, lists[i].st);
        if (st == RP_CFG_OK) {
            assert_int_equal(g_cfg.pipe.rc_n, lists[i].n);
            assert_int_equal(g_cfg.pipe.rc_cams[0], 0);
            assert_int_equal(g_cfg.pipe.rc_cams[lists[i].n - 1], lists[i].n == 2 ? 2 : 3);
        } else {
            assert_non_null(strstr(g_err, "estimator.cams"));
        }
    }
}

/* No prefix of a valid file crashes the parser or passes half-read: each is either the full
 * file's result or an error with a message. */
/* 3,000 corrupted copies of config/sim.yaml (1..8 bytes each replaced by a random byte, a
 * control character, a bracket, a quote, a colon or a newline; a fixed seed): each accepted or
 * refused with a printable "sim.yaml:LINE: ..." message, never a crash (ASan, UBSan). */
static void test_corrupted_files_never_crash(void **state)
{
    (void)state;
    static char orig[16384], text[16384];
    FILE *f = fopen("config/sim.yaml", "rb");
    assert_non_null(f);
    const size_t n = fread(orig, 1, sizeof orig - 1, f);
    fclose(f);
    static const char special[] = "\n\t\r\x1b\x7f\xff\xc2[]{}'\":&*!|>%@`-#, 0";
    uint32_t rng = 12345u;
    unsigned ok = 0, refused = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        memcpy(text, orig, n);
        rng = rng * 1664525u + 1013904223u;
        const unsigned edits = 1u + (rng >> 16) % 8u;
        for (unsigned e = 0; e < edits; ++e) {
            rng = rng * 1664525u + 1013904223u;
            const size_t at = (size_t)(rng >> 8) % n;
            rng = rng * 1664525u + 1013904223u;
            text[at] = (rng >> 24) & 1 ? (char)(rng >> 16)
                                       : special[(rng >> 8) % (sizeof special - 1)];
        }
        g_err[0] = '\0';
        const rp_cfg_status_t st = rp_config_parse(text, n, "sim.yaml", &g_cfg, g_err,
                                                   sizeof g_err);
        if (st == RP_CFG_OK) {
            ++ok;
            continue;
        }
        ++refused;
        if (strncmp(g_err, "sim.yaml:", 9) != 0) {
            fail_msg("trial %d: status %d, message '%s'", trial, (int)st, g_err);
        }
        assert_printable(g_err);
    }
    printf("3000 corrupted copies of config/sim.yaml: %u accepted, %u refused with a printable "
           "message\n", ok, refused);
    assert_true(refused > 1000);
}

static void test_truncated_files_never_crash(void **state)
{
    (void)state;
    static char text[16384];
    FILE *f = fopen("config/sim.yaml", "rb");
    assert_non_null(f);
    const size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    unsigned ok = 0, refused = 0;
    for (size_t len = 0; len < n; ++len) {
        g_err[0] = '\0';
        const rp_cfg_status_t st = rp_config_parse(text, len, "sim.yaml", &g_cfg, g_err,
                                                   sizeof g_err);
        if (st == RP_CFG_OK) {
            ++ok;
        } else {
            ++refused;
            assert_true(strncmp(g_err, "sim.yaml:", 9) == 0);
        }
    }
    printf("%zu prefixes of config/sim.yaml: %u accepted, %u refused with a message\n", n, ok,
           refused);
    assert_true(refused > 0);
}

/* ---- one source of defaults ------------------------------------------------------------- */

/* config/sim.yaml (the paper's rig, cameras numbered as rp_pipe_default_cfg assumes) with its
 * estimator mapping replaced by the least layout l accepts: the method and its cameras. */
static const char *minimal_file(rp_pipe_layout_t l)
{
    static const char *const est[RP_PIPE_LAYOUT_COUNT_] = {
        "estimator:\n  method: stereo4\n  pairs: [[cam1, cam1b], [cam3, cam3b]]\n",
        "estimator:\n  method: stereo2\n  pairs: [[cam1, cam1b]]\n",
        "estimator:\n  method: gc\n  cams: [cam1, cam2, cam3, cam4]\n",
        "estimator:\n  method: cam1\n",
        "estimator:\n  method: cam2\n",
        "estimator:\n  method: cam3\n",
        "estimator:\n  method: cam4\n",
        "estimator:\n  method: rc\n"};
    static char text[16384];
    char file[16384];
    FILE *f = fopen("config/sim.yaml", "rb");
    assert_non_null(f);
    const size_t n = fread(file, 1, sizeof file - 1, f);
    fclose(f);
    file[n] = '\0';
    const char *a = strstr(file, "\nestimator:\n");
    const char *b = a != NULL ? strstr(a, "\nlcm:\n") : NULL;
    assert_non_null(b);
    snprintf(text, sizeof text, "%.*s\n%s%s", (int)(a - file), file, est[l], b + 1);
    return text;
}

/* Field by field over RP_PIPE_CFG_FIELDS (host_tools/common/rp_cfg_diff.h, the list the tools
 * report their deviations with): a byte comparison of the whole struct would compare padding,
 * which is not zero (the *_default_cfg return by value). */
/* Fields of got that differ from want (printed); marks each field's bytes in covered[]. */
static unsigned pipe_cfg_diff(const rp_pipe_cfg_t *got, const rp_pipe_cfg_t *want,
                              const char *what, unsigned char *covered)
{
    unsigned n = 0;
#define CMP_FIELD(f, use, kind)                                                                   \
    if (memcmp(&got->f, &want->f, sizeof got->f) != 0) {                                         \
        printf("%s: parsed %s differs from rp_pipe_default_cfg's\n", what, #f);                  \
        ++n;                                                                                      \
    }                                                                                             \
    memset(covered + ((const unsigned char *)&got->f - (const unsigned char *)got), 1,           \
           sizeof got->f);
    RP_PIPE_CFG_FIELDS(CMP_FIELD)
#undef CMP_FIELD
    return n;
}

/* The must-show: for every layout a file that gives no estimator or tracker setting parses to
 * exactly the core's rp_pipe_default_cfg of that layout (every field, bit for bit), and rp_est
 * runs it as it is (daemon/tests/test_est.c). Fails if the parser, or anything between it and
 * the core, sets a default of its own. */
static void test_minimal_file_is_the_core_default_for_every_layout(void **state)
{
    (void)state;
    for (int l = 0; l < RP_PIPE_LAYOUT_COUNT_; ++l) {
        const char *t = minimal_file((rp_pipe_layout_t)l);
        if (rp_config_parse(t, strlen(t), "minimal.yaml", &g_cfg, g_err, sizeof g_err) !=
            RP_CFG_OK) {
            fail_msg("%s: %s", rp_pipe_layout_name((rp_pipe_layout_t)l), g_err);
        }
        static rp_pipe_cfg_t def;
        memset(&def, 0, sizeof def);
        assert_ok(rp_pipe_default_cfg((rp_pipe_layout_t)l, &def));
        static unsigned char covered[sizeof(rp_pipe_cfg_t)];
        memset(covered, 0, sizeof covered);
        const unsigned n = pipe_cfg_diff(&g_cfg.pipe, &def,
                                         rp_pipe_layout_name((rp_pipe_layout_t)l), covered);
        printf("%-8s minimal file == rp_pipe_default_cfg: %s\n",
               rp_pipe_layout_name((rp_pipe_layout_t)l), n == 0 ? "yes, every field" : "NO");
        assert_int_equal(n, 0);
        /* RP_PIPE_CFG_FIELDS lists every field: what it leaves out can only be padding, shorter
         * than the widest member (a field added to a configuration struct shows here) */
        size_t run = 0;
        for (size_t i = 0; i < sizeof covered; ++i) {
            run = covered[i] ? 0 : run + 1;
            if (run >= sizeof(rp_real)) {
                fail_msg("rp_pipe_cfg_t bytes %zu..%zu are in no field of RP_PIPE_CFG_FIELDS "
                         "(host_tools/common/rp_cfg_diff.h): a new field? add it there",
                         i + 1 - run, i);
            }
        }
    }
}

/* A key given overrides the core's default of every estimator that has it; a key not given
 * keeps each estimator's own (stereo's plant noise 3, gc's 1). */
static void test_a_key_given_overrides_only_itself(void **state)
{
    (void)state;
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  q_trans: 2")), RP_CFG_OK);
    assert_near(g_cfg.pipe.stereo.ekf.q_trans, 2.0, 0.0);
    assert_near(g_cfg.pipe.gc.ekf.q_trans, 2.0, 0.0);
    assert_near(g_cfg.pipe.mono.ekf.q_trans, 2.0, 0.0);
    const rp_vo_stereo_cfg_t st = rp_vo_stereo_default_cfg();
    const rp_vo_gc_cfg_t gc = rp_vo_gc_default_cfg();
    assert_near(g_cfg.pipe.stereo.ekf.q_rot, st.ekf.q_rot, 0.0);
    assert_near(g_cfg.pipe.gc.ekf.q_rot, gc.ekf.q_rot, 0.0);
    assert_near(g_cfg.pipe.gc.init_depth_m, gc.init_depth_m, 0.0);
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  init_on_sphere: true\n"
                                      "  min_depth_m: 0.5")),
                     RP_CFG_OK);
    assert_int_equal(g_cfg.pipe.gc.init_on_sphere, 1);
    assert_near(g_cfg.pipe.stereo.min_depth_m, 0.5, RP_TOL_TIGHT);
    assert_near(g_cfg.pipe.stereo.max_depth_m, st.max_depth_m, 0.0);
    /* a min_depth_m beyond the default max names min_depth_m */
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  min_depth_m: 500")),
                     RP_CFG_E_RANGE);
    assert_non_null(strstr(g_err, "bad.yaml:24: estimator.min_depth_m: must be smaller"));
    /* tracker keys the same way: target moves the top-up threshold with it */
    assert_int_equal(parse(edited(25, "  pose_channel: P\ntracker:\n  target: 100")), RP_CFG_OK);
    rp_track_cfg_t tc;
    assert_ok(rp_track_default_cfg(&tc));
    assert_int_equal(g_cfg.pipe.track.target, 100);
    assert_int_equal(g_cfg.pipe.track.topup_below, 80);
    assert_int_equal(g_cfg.pipe.track.win, tc.win);
    assert_int_equal(g_cfg.pipe.track.reset_q8, tc.reset_q8);
}

/* The value(s) of setting `key` in p (the layout's estimator, or the tracker): 1, or 0 if the
 * layout has no such setting. */
static int setting(const char *key, const rp_pipe_cfg_t *p, double v[2])
{
    const int st = p->layout == RP_PIPE_STEREO4 || p->layout == RP_PIPE_STEREO2;
    const int gc = p->layout == RP_PIPE_GC;
    const rp_ekf_params_t *e = st ? &p->stereo.ekf : gc ? &p->gc.ekf : &p->mono.ekf;
    const rp_track_cfg_t *t = &p->track;
#define IS(k) (strcmp(key, k) == 0)
    v[1] = 0.0;
    if (IS("sigma_px")) v[0] = (double)e->sigma_px;
    else if (IS("q_trans")) v[0] = (double)e->q_trans;
    else if (IS("q_rot")) v[0] = (double)e->q_rot;
    else if (IS("gate_chi2")) v[0] = (double)e->gate_chi2;
    else if (IS("iterations")) v[0] = e->iterations;
    else if (IS("min_features")) v[0] = e->min_features;
    else if (IS("max_predict_s")) v[0] = (double)e->max_predict_s;
    else if (IS("estimate_time_offsets")) v[0] = e->toff_estimate;
    else if (IS("time_offset_sigma_s")) v[0] = (double)e->toff_sigma_s;
    else if (IS("time_offset_q")) v[0] = (double)e->toff_q;
    else if (IS("time_jitter_s")) v[0] = (double)e->time_jitter_s;
    else if (IS("group_time_noise")) v[0] = e->group_time_noise;
    else if (IS("min_tracked")) {
        v[0] = st ? p->stereo.min_tracked : gc ? p->gc.min_tracked : p->mono.min_tracked;
    } else if (IS("default_dt_s")) {
        v[0] = (double)(st ? p->stereo.default_dt_s : gc ? p->gc.default_dt_s
                                                         : p->mono.default_dt_s);
    } else if (IS("max_epipolar_px") && st) v[0] = (double)p->stereo.max_epipolar_px;
    else if (IS("min_depth_m") && st) v[0] = (double)p->stereo.min_depth_m;
    else if (IS("max_depth_m") && st) v[0] = (double)p->stereo.max_depth_m;
    else if (IS("max_reproj_px") && st) v[0] = (double)p->stereo.max_reproj_px;
    else if (IS("max_pair_skew_s") && st) v[0] = (double)p->stereo.max_pair_skew_s;
    else if (IS("refine_structure") && st) v[0] = p->stereo.refine_structure;
    else if (IS("ransac")) v[0] = st ? p->stereo.ransac : gc ? p->gc.ransac : p->mono.ransac;
    else if (IS("one_point")) {
        v[0] = st ? p->stereo.one_point : gc ? p->gc.one_point : p->mono.one_point;
    }
    else if (IS("drop_odds") && st) v[0] = (double)p->stereo.drop_odds;
    else if (IS("retry_triangulation") && st) v[0] = p->stereo.retry_triangulation;
    else if (IS("retire_outliers") && st) v[0] = p->stereo.retire_outliers;
    else if (IS("add_landmarks") && st) v[0] = p->stereo.add_landmarks;
    else if (IS("dormant_retired") && (st || gc)) v[0] = p->dormant_retired;
    else if (IS("init_depth_m") && !st) {
        v[0] = (double)(gc ? p->gc.init_depth_m : p->mono.init_depth_m);
    } else if (IS("init_depth_sigma_m") && !st) {
        v[0] = (double)(gc ? p->gc.init_depth_sigma_m : p->mono.init_depth_sigma_m);
    } else if (IS("init_on_sphere") && gc) v[0] = p->gc.init_on_sphere;
    else if (IS("metric_scale_sigma") && gc) v[0] = (double)p->gc.mscale_sigma;
    else if (IS("target")) v[0] = t->target;
    else if (IS("levels")) v[0] = t->levels;
    else if (IS("win")) v[0] = t->win;
    else if (IS("min_dist")) v[0] = t->min_dist;
    else if (IS("fb_max_px")) v[0] = t->fb_max_q16 / 65536.0;
    else if (IS("grid")) { v[0] = t->grid_x; v[1] = t->grid_y; }
    else if (IS("reset_share")) v[0] = t->reset_q8 / 256.0;
    else return 0;
#undef IS
    return 1;
}

/* Numbers of a README cell ("0.5", "true", "`[8, 6]`"): count (0: "—"), the values, and half a
 * unit of the last digit written (an integer: float rounding only). */
static int cell_values(const char *cell, double v[2], double tol[2])
{
    if (strcmp(cell, "—") == 0) {
        return 0;
    }
    if (strcmp(cell, "true") == 0 || strcmp(cell, "false") == 0) {
        v[0] = cell[0] == 't';
        tol[0] = 0.0;
        return 1;
    }
    int n = 0;
    const char *s = cell;
    while (*s != '\0' && n < 2) {
        while (*s == '`' || *s == '[' || *s == ' ' || *s == ',') {
            ++s;
        }
        char *end = NULL;
        v[n] = strtod(s, &end);
        if (end == s) {
            return -1;
        }
        const char *dot = memchr(s, '.', (size_t)(end - s));
        const int digits = dot != NULL ? (int)(end - dot - 1) : 0;
        tol[n] = digits > 0 ? 0.5 * pow(10.0, -digits) : 1e-6 * fmax(1.0, fabs(v[n]));
        ++n;
        s = end;
        while (*s == ']' || *s == '`') {
            ++s;
        }
        if (*s != ',' && *s != '\0') {
            return -1;
        }
    }
    return n;
}

/* Cells of a table row "| a | b |", trimmed, into cell[] (max of them, CELL_MAX chars each);
 * their count. */
#define CELL_MAX 400
static int row_cells(const char *line, char cell[][CELL_MAX], int max)
{
    int n = 0;
    const char *s = strchr(line, '|');
    while (s != NULL && n < max) {
        const char *next = strchr(s + 1, '|');
        if (next == NULL) {
            break;
        }
        const char *c = s + 1, *e = next;
        while (c < e && *c == ' ') {
            ++c;
        }
        while (e > c && e[-1] == ' ') {
            --e;
        }
        snprintf(cell[n++], CELL_MAX, "%.*s", (int)(e - c), c);
        s = next;
    }
    return n;
}

/* config/README.md's table under the heading that starts with `heading`: every row's default
 * (in column `col` of the header, for each layout `layouts` lists per column) must be what a
 * file without the key parses to. Returns the rows checked. */
static unsigned check_readme_table(const char *readme, const char *heading, int first_col,
                                   int n_cols, const rp_pipe_layout_t layouts[][5],
                                   const char *const header[])
{
    static rp_config_t cfgs[RP_PIPE_LAYOUT_COUNT_];
    for (int l = 0; l < RP_PIPE_LAYOUT_COUNT_; ++l) {
        const char *t = minimal_file((rp_pipe_layout_t)l);
        assert_int_equal(rp_config_parse(t, strlen(t), "minimal.yaml", &cfgs[l], g_err,
                                         sizeof g_err),
                         RP_CFG_OK);
    }
    const char *h = strstr(readme, heading);
    if (h == NULL) {
        fail_msg("config/README.md: no heading '%s'", heading);
    }
    const char *s = strstr(h, "\n|");
    assert_non_null(s);
    ++s;
    unsigned rows = 0, wrong = 0;
    for (int line_no = 0; *s == '|'; ++line_no) {
        const char *eol = strchr(s, '\n');
        char line[1024];
        snprintf(line, sizeof line, "%.*s", (int)(eol != NULL ? eol - s : (long)strlen(s)), s);
        s = eol != NULL ? eol + 1 : s + strlen(s);
        static char cell[12][CELL_MAX];
        const int nc = row_cells(line, cell, 12);
        if (line_no == 0) {
            for (int k = 0; k < n_cols; ++k) {
                assert_true(first_col + k < nc);
                assert_string_equal(cell[first_col + k], header[k]);
            }
        } else if (line_no > 1) {
            char key[CELL_MAX];
            memcpy(key, cell[0][0] == '`' ? cell[0] + 1 : cell[0], CELL_MAX - 1);
            key[CELL_MAX - 1] = '\0';
            char *tick = strchr(key, '`');
            if (tick != NULL) {
                *tick = '\0';
            }
            for (int k = 0; k < n_cols; ++k) {
                double want[2], tol[2];
                const int nv = cell_values(cell[first_col + k], want, tol);
                for (int j = 0; j < 5 && layouts[k][j] != RP_PIPE_LAYOUT_COUNT_; ++j) {
                    const rp_pipe_layout_t l = layouts[k][j];
                    double got[2];
                    const int has = setting(key, &cfgs[l].pipe, got);
                    int ok = nv >= 0 && has == (nv > 0);
                    for (int i = 0; ok && i < nv; ++i) {
                        ok = fabs(got[i] - want[i]) <= tol[i];
                    }
                    if (!ok) {
                        printf("FAIL config/README.md %s, %s: README '%s', parsed %s%g\n", key,
                               rp_pipe_layout_name(l), cell[first_col + k],
                               has ? "" : "(no such setting) ", has ? got[0] : 0.0);
                        ++wrong;
                    }
                }
            }
            ++rows;
        }
    }
    assert_int_equal(wrong, 0);
    return rows;
}

/* config/README.md lists each setting's default as the core defines it, for each layout. */
static void test_readme_lists_the_core_defaults(void **state)
{
    (void)state;
    static char readme[65536];
    read_text("config/README.md", readme, sizeof readme);
#define E RP_PIPE_LAYOUT_COUNT_ /* end of a list */
    static const rp_pipe_layout_t est_layouts[3][5] = {
        {RP_PIPE_STEREO4, RP_PIPE_STEREO2, E, E, E},
        {RP_PIPE_GC, E, E, E, E},
        {RP_PIPE_CAM1, RP_PIPE_CAM2, RP_PIPE_CAM3, RP_PIPE_CAM4, RP_PIPE_RC}};
#undef E
    static const char *const est_header[3] = {"stereo4, stereo2", "gc", "cam1..cam4, rc"};
    const unsigned est_rows = check_readme_table(
        readme, "#### `estimator` settings", 3, 3, est_layouts, est_header);
    static const rp_pipe_layout_t trk_layouts[1][5] = {
        {RP_PIPE_STEREO4, RP_PIPE_STEREO2, RP_PIPE_GC, RP_PIPE_CAM1, RP_PIPE_RC}};
    static const char *const trk_header[1] = {"default"};
    const unsigned trk_rows =
        check_readme_table(readme, "### `tracker`", 3, 1, trk_layouts, trk_header);
    printf("config/README.md: %u estimator and %u tracker defaults match the core's\n",
           est_rows, trk_rows);
    /* every setting the parser knows is listed (rp_config.c's keys but method, pairs, cams) */
    assert_int_equal(est_rows, 31);
    assert_int_equal(trk_rows, 7);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_base_file_is_valid),
        cmocka_unit_test(test_embedded_default_is_the_simulated_rig),
        cmocka_unit_test(test_angles_match_the_rotation_module),
        cmocka_unit_test(test_tracker_reset_share),
        cmocka_unit_test(test_sim_motion_and_instance),
        cmocka_unit_test(test_gc_metric_scale_sigma),
        cmocka_unit_test(test_time_offsets),
        cmocka_unit_test(test_each_bad_file_names_line_and_key),
        cmocka_unit_test(test_whole_file_errors),
        cmocka_unit_test(test_hostile_files),
        cmocka_unit_test(test_intrinsics_range),
        cmocka_unit_test(test_distortion_folding_inside_the_image),
        cmocka_unit_test(test_replay_index_is_relative_to_the_file),
        cmocka_unit_test(test_distributed_keys),
        cmocka_unit_test(test_single_camera_methods),
        cmocka_unit_test(test_source_sets),
        cmocka_unit_test(test_truncated_files_never_crash),
        cmocka_unit_test(test_corrupted_files_never_crash),
        cmocka_unit_test(test_minimal_file_is_the_core_default_for_every_layout),
        cmocka_unit_test(test_a_key_given_overrides_only_itself),
        cmocka_unit_test(test_readme_lists_the_core_defaults),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
