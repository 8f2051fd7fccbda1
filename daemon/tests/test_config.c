/*
 * test_config.c - the configuration file (platform/src/rp_config.c, schema config/README.md):
 * the embedded default loads into the simulator's rig; defaults fill what a file leaves out;
 * every bad file (missing keys, wrong types, impossible values, unknown keys, broken YAML) is
 * refused with its own status and a message "FILE:LINE: KEY: ..." naming the right line and key;
 * no truncation of a valid file crashes the parser.
 */
#include <stdlib.h>
#include <string.h>

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
    assert_int_equal(g_cfg.method, RP_METHOD_STEREO2);
    assert_int_equal(g_cfg.stereo.n_pairs, 1);
    assert_int_equal(g_cfg.stereo.pair_a[0], 0);
    assert_int_equal(g_cfg.stereo.pair_b[0], 1);
    assert_near(g_cfg.rig.cam[1].D[0], 0.1, RP_TOL_TIGHT);
    assert_near(g_cfg.rig.cam[1].cam.k1, 0.1, RP_TOL_TIGHT);
    assert_near(g_cfg.rig.cam[1].cam.k2, -0.05, RP_TOL_TIGHT);
    /* Defaults for what the file leaves out. */
    assert_int_equal(g_cfg.hal.sync_tol_us, 5000);
    assert_int_equal(g_cfg.hal.retry_ms, 1000);
    assert_int_equal(g_cfg.hal.cam[0].fps, 30);
    assert_near(g_cfg.stereo.ekf.sigma_px, 0.5, RP_TOL_TIGHT);
    assert_int_equal(g_cfg.stereo.min_tracked, 50);
    assert_string_equal(g_cfg.lcm_url, "udpm://239.255.76.67:7667?ttl=0");
    assert_string_equal(g_cfg.pose_channel, "P");
    assert_string_equal(g_cfg.status_channel, "RIGPOSE_STATUS");
    assert_string_equal(g_cfg.image_channel, "");
    assert_int_equal(g_cfg.status_every, 1);
    assert_int_equal(g_cfg.track.target, 150);
    assert_int_equal(g_cfg.track.reset_q8, 205);
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
    assert_int_equal(g_cfg.method, RP_METHOD_STEREO4);
    assert_int_equal(g_cfg.stereo.n_pairs, 2);
    assert_int_equal(g_cfg.stereo.pair_a[0], RP_SIM_CAM1);
    assert_int_equal(g_cfg.stereo.pair_b[0], RP_SIM_CAM1B);
    assert_int_equal(g_cfg.stereo.pair_a[1], RP_SIM_CAM3);
    assert_int_equal(g_cfg.stereo.pair_b[1], RP_SIM_CAM3B);
    assert_int_equal(g_cfg.sim.drop_cam, -1);
    assert_near(g_cfg.sim.noise_px, 0.5, 1e-12);
}

/* tracker.reset_share sets the tracker's reset (0 turns it off). */
static void test_tracker_reset_share(void **state)
{
    (void)state;
    assert_int_equal(parse(edited(25, "  pose_channel: P\ntracker:\n  reset_share: 0.5")),
                     RP_CFG_OK);
    assert_int_equal(g_cfg.track.reset_q8, 128);
    assert_int_equal(parse(edited(25, "  pose_channel: P\ntracker:\n  reset_share: 0")),
                     RP_CFG_OK);
    assert_int_equal(g_cfg.track.reset_q8, 0);
}

/* estimator.metric_scale_sigma sets gc's metric scale step (0 turns it off). */
static void test_gc_metric_scale_sigma(void **state)
{
    (void)state;
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  metric_scale_sigma: 0")),
                     RP_CFG_OK);
    assert_near(g_cfg.gc.mscale_sigma, 0.0, 0.0);
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]\n  metric_scale_sigma: 0.1")),
                     RP_CFG_OK);
    assert_near(g_cfg.gc.mscale_sigma, 0.1, RP_TOL_TIGHT);
    assert_int_equal(parse(edited(23, "  pairs: [[left, right]]")), RP_CFG_OK);
    assert_near(g_cfg.gc.mscale_sigma, 0.3, RP_TOL_TIGHT);
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
    {3, "  kind: usb", RP_CFG_E_RANGE, "bad.yaml:3: source.kind: 'usb' is not one of"},
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
    static const struct { const char *line; rp_method_t want; uint8_t cam0; } cases[] = {
        {"  method: rc     ", RP_METHOD_RC, 0},
        {"  method: cam3   ", RP_METHOD_CAM3, 2},
        {"  method: gc     ", RP_METHOD_GC, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        memcpy(m, cases[i].line, strlen(cases[i].line));
        const rp_cfg_status_t st = rp_config_parse(text, n, "sim.yaml", &g_cfg, g_err, sizeof g_err);
        if (cases[i].want == RP_METHOD_GC) {
            /* gc needs its camera list: sim.yaml has only pairs. */
            assert_int_equal(st, RP_CFG_E_MISSING);
            assert_non_null(strstr(g_err, "estimator.cams: missing"));
            continue;
        }
        if (st != RP_CFG_OK) {
            fail_msg("%s", g_err);
        }
        assert_int_equal(g_cfg.method, cases[i].want);
        assert_int_equal(g_cfg.mono[0].cam, cases[i].cam0);
        if (cases[i].want == RP_METHOD_RC) {
            assert_int_equal(g_cfg.n_mono, 4);
            assert_int_equal(g_cfg.mono[3].cam, 3);
        }
    }
}

/* No prefix of a valid file crashes the parser or passes half-read: each is either the full
 * file's result or an error with a message. */
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_base_file_is_valid),
        cmocka_unit_test(test_embedded_default_is_the_simulated_rig),
        cmocka_unit_test(test_angles_match_the_rotation_module),
        cmocka_unit_test(test_tracker_reset_share),
        cmocka_unit_test(test_gc_metric_scale_sigma),
        cmocka_unit_test(test_each_bad_file_names_line_and_key),
        cmocka_unit_test(test_whole_file_errors),
        cmocka_unit_test(test_replay_index_is_relative_to_the_file),
        cmocka_unit_test(test_single_camera_methods),
        cmocka_unit_test(test_truncated_files_never_crash),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
