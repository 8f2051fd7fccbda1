/*
 * test_pipe.c - the image pipeline (rp_pipe.h): rendered frames of the paper's six-camera rig
 * (320x240, f = 400 px) moving through a textured room (img_fixture.h) go through trackers,
 * stereo matching and the estimators; the pose follows the known motion for stereo4, stereo2
 * and gc; pairs share ids; a missing, blank, truncated or wrongly sized image degrades the step
 * with its state instead of failing it; bad calls give their status. Feature-level input
 * (rp_pipe_step_feats) is the layout's estimator on the simulation's frame sets. Cameras with
 * their own capture times (rp_pipe_step_timed) carry them into the frame set and trackers.
 */
#include <string.h>
#include <time.h>

#include "rp_test.h"

#include "img_fixture.h"
#include "rigpose/rp_pipe.h"

#define W 320
#define H 240
#define NCAM RP_SIM_NCAMS
#define NFRAMES 8
#define DT_US 33333

static rp_rig_t rig;
static uint8_t frames[NFRAMES][NCAM][W * H];
static rp_real truth[NFRAMES][6];
static rp_pipe_t pipe;
static int rendered = 0;
static uint32_t g_serial0 = 0; /* first track serial of every tracker (run_layout) */

/* The motion: constant velocity, per frame (4, -2, 6) mm and (4, 6, -3) mrad. */
static void pose_at(int j, rp_real p[6])
{
    static const double step[6] = {0.004, -0.002, 0.006, 0.004, 0.006, -0.003};
    for (int i = 0; i < 6; ++i) {
        p[i] = (rp_real)(step[i] * j);
    }
}

static int setup_frames(void **state)
{
    (void)state;
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.width = W;
    sc.height = H;
    sc.focal_px = 400.0;
    rp_sim_make_rig(&sc, &rig);
    if (rendered) {
        return 0;
    }
    const fx_room_t rm = fx_room_default();
    uint64_t rs = 1234;
    for (int j = 0; j < NFRAMES; ++j) {
        pose_at(j, truth[j]);
        for (int k = 0; k < NCAM; ++k) {
            fx_render(&rig, k, truth[j], &rm, frames[j][k], 2.0, &rs);
        }
    }
    rendered = 1;
    return 0;
}

typedef struct {
    double t_err, a_err; /* mean over frames 1.. of max |translation| (m) and |angle| (rad) */
    double t_last, a_last;
    double us_per_step;
    int n_ok;
} run_t;

/* rc's cameras for run_layout: the first g_rc_n of g_rc_cams (default: the paper's four) */
static uint8_t g_rc_n = RP_RC_MAX_CAMS;
static uint8_t g_rc_cams[RP_RC_MAX_CAMS] = {0, 1, 2, 3};

/* Runs the pipeline over the frames; drop_cam >= 0 withholds that camera at frame drop_at. */
static run_t run_layout(rp_pipe_layout_t layout, int nframes, int drop_cam, int drop_at)
{
    rp_pipe_cfg_t cfg;
    assert_ok(rp_pipe_default_cfg(layout, &cfg));
    cfg.rc_n = g_rc_n;
    memcpy(cfg.rc_cams, g_rc_cams, sizeof cfg.rc_cams);
    cfg.gc.init_depth_m = RP_C(1.2); /* the room's typical range */
    cfg.gc.init_depth_sigma_m = RP_C(0.3);
    cfg.gc.init_on_sphere = 1;
    cfg.mono.init_depth_m = RP_C(1.2);
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    for (int t = 0; t < RP_PIPE_MAX_TRACKERS; ++t) {
        assert_ok(rp_track_set_next_serial(&pipe.trk[t], g_serial0));
    }
    run_t r;
    memset(&r, 0, sizeof(r));
    double us = 0;
    for (int j = 0; j < nframes; ++j) {
        rp_image_t im[NCAM];
        const rp_image_t *ptr[NCAM];
        for (int k = 0; k < NCAM; ++k) {
            im[k] = fx_image(frames[j][k], W, H);
            ptr[k] = (k == drop_cam && j == drop_at) ? NULL : &im[k];
        }
        rp_estimate_t est;
        const clock_t t0 = clock();
        const rp_status_t st = rp_pipe_step(&pipe, ptr, NCAM, (int64_t)j * DT_US, &est);
        us += (double)(clock() - t0) / CLOCKS_PER_SEC * 1e6;
        r.n_ok += st == RP_OK;
        const rp_pipe_info_t *info;
        assert_ok(rp_pipe_info(&pipe, &info));
        assert_int_equal(info->frame, j + 1);
        if (j == drop_at && drop_cam >= 0) {
            assert_int_equal(info->cam_state[drop_cam], RP_PIPE_CAM_MISSING);
            assert_true(est.flags & RP_EST_DEGRADED);
        }
        if (j == 0) {
            assert_true(est.flags & RP_EST_INITIALISING);
            continue;
        }
        double te = 0, ae = 0;
        for (int i = 0; i < 3; ++i) {
            te = fmax(te, fabs((double)(est.p[i] - truth[j][i])));
            ae = fmax(ae, fabs((double)(est.p[3 + i] - truth[j][3 + i])));
        }
        r.t_err += te / (nframes - 1);
        r.a_err += ae / (nframes - 1);
        r.t_last = te;
        r.a_last = ae;
    }
    r.us_per_step = us / nframes;
    printf("  %s: %d/%d steps OK; mean error %.5f m %.5f rad, last frame %.5f m %.5f rad "
           "(moved %.3f m); %.0f us per step (this build)\n",
           rp_pipe_layout_name(layout), r.n_ok, nframes, r.t_err, r.a_err, r.t_last, r.a_last,
           sqrt(pow((double)truth[nframes - 1][0], 2) + pow((double)truth[nframes - 1][1], 2) +
                pow((double)truth[nframes - 1][2], 2)),
           r.us_per_step);
    return r;
}

/* Given the paper's two stereo pairs in the room, the pipeline tracks the motion to a few mm,
 * also when a camera (cam3's partner) delivers no image for one frame set. */
static void test_stereo4_tracks_motion(void **state)
{
    (void)state;
    const run_t r = run_layout(RP_PIPE_STEREO4, NFRAMES, RP_SIM_CAM3B, 4);
    assert_int_equal(r.n_ok, NFRAMES);
    assert_true(r.t_err < 0.002);
    assert_true(r.a_err < 0.002);
}

static void test_stereo2_tracks_motion(void **state)
{
    (void)state;
    const run_t r = run_layout(RP_PIPE_STEREO2, NFRAMES, -1, -1);
    assert_int_equal(r.n_ok, NFRAMES);
    assert_true(r.t_err < 0.005);
    assert_true(r.a_err < 0.005);
}

/* The right camera without an image in the first set (a camera late to start, a set regrouped
 * by capture time): the left camera's first features cannot be matched and are dropped, so it
 * detects again in the next set and the pair starts there, instead of keeping unmatched
 * features that hold off detection until they are lost. */
static void test_stereo2_right_missing_at_start(void **state)
{
    (void)state;
    const run_t r = run_layout(RP_PIPE_STEREO2, NFRAMES, RP_SIM_CAM1B, 0);
    /* set 0: nothing to triangulate; set 1: the new features' first set (the start uses the
     * previous set); from set 2 on tracking, with the world the pose at set 1 (the truth's
     * world is set 0: about 5 mm and 6 mrad of motion apart) */
    assert_int_equal(r.n_ok, NFRAMES - 2);
    assert_true(r.t_last < 0.01);
    assert_true(r.a_last < 0.01);
}

static void test_gc_tracks_motion(void **state)
{
    (void)state;
    const run_t r = run_layout(RP_PIPE_GC, NFRAMES, -1, -1);
    assert_int_equal(r.n_ok, NFRAMES);
    assert_true(r.t_err < 0.01);
    assert_true(r.a_err < 0.005);
}

/* cam1 alone and the rigidity constraints (on four cameras and on two) run end to end (a few
 * frames: their accuracy is the simulator's business). */
static void test_single_camera_and_rc_run(void **state)
{
    (void)state;
    const run_t c1 = run_layout(RP_PIPE_CAM1, 4, -1, -1);
    assert_int_equal(c1.n_ok, 4);
    assert_true(c1.a_err < 0.05);
    const run_t rc = run_layout(RP_PIPE_RC, 4, -1, -1);
    assert_int_equal(rc.n_ok, 4);
    assert_true(rc.a_err < 0.05);
    /* rc on two of the rig's cameras (cam1 the reference, cam3 facing away) */
    g_rc_n = 2;
    g_rc_cams[1] = 2;
    const run_t rc2 = run_layout(RP_PIPE_RC, 4, -1, -1);
    g_rc_n = RP_RC_MAX_CAMS;
    g_rc_cams[1] = 1;
    assert_int_equal(rc2.n_ok, 4);
    assert_true(rc2.a_err < 0.05);
    const rp_pipe_info_t *info;
    assert_ok(rp_pipe_info(&pipe, &info));
    assert_int_equal(info->cam_state[1], RP_PIPE_CAM_UNUSED);
    assert_int_equal(info->cam_state[2], RP_PIPE_CAM_OK);
    /* one camera is no fusion; more than RP_RC_MAX_CAMS do not fit */
    rp_pipe_cfg_t cfg;
    assert_ok(rp_pipe_default_cfg(RP_PIPE_RC, &cfg));
    cfg.rc_n = 1;
    assert_int_equal(rp_pipe_init(&pipe, &rig, &cfg), RP_E_ARG);
    cfg.rc_n = RP_RC_MAX_CAMS + 1;
    assert_int_equal(rp_pipe_init(&pipe, &rig, &cfg), RP_E_ARG);
}

/* Track ids across the serial's wrap (rp_track.h): every tracker starts 60 serials before
 * 2^28, so the first frame's detections already wrap; every layout gives what it gives from
 * serial 0 (and so the bounds of the tests above), the new left features of a stereo pair are still told from the old ones
 * (they are matched: the pair's right camera carries them), and the serials did wrap. */
static void test_ids_across_the_serial_wrap(void **state)
{
    (void)state;
    g_serial0 = RP_TRACK_SERIAL_MASK - 59u;
    static const struct {
        rp_pipe_layout_t layout;
        int frames;
        double t_max, a_max;
    } runs[] = {{RP_PIPE_STEREO4, NFRAMES, 0.002, 0.002}, {RP_PIPE_STEREO2, NFRAMES, 0.005, 0.005},
                {RP_PIPE_GC, NFRAMES, 0.01, 0.005},       {RP_PIPE_CAM1, 4, 1e9, 0.05},
                {RP_PIPE_RC, 4, 1e9, 0.05}};
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; ++i) {
        g_serial0 = 0;
        const run_t r0 = run_layout(runs[i].layout, runs[i].frames, -1, -1);
        g_serial0 = RP_TRACK_SERIAL_MASK - 59u;
        const run_t r = run_layout(runs[i].layout, runs[i].frames, -1, -1);
        printf("  %s: mean errors from serial 0 %.9f m %.9f rad, across the wrap %.9f m %.9f "
               "rad\n", rp_pipe_layout_name(runs[i].layout), r0.t_err, r0.a_err, r.t_err, r.a_err);
        /* the serial's origin changes nothing (a comparison that is not wrap-safe took the
         * wrapped new features for old ones, left them unmatched, and stereo2's error rose
         * from 0.00048 to 0.00116 m) */
        assert_true(fabs(r.t_err - r0.t_err) <= 1e-5 * r0.t_err);
        assert_true(fabs(r.a_err - r0.a_err) <= 1e-5 * r0.a_err);
        assert_int_equal(r.n_ok, runs[i].frames);
        assert_true(r.t_err < runs[i].t_max);
        assert_true(r.a_err < runs[i].a_max);
        uint32_t k = 0;
        assert_ok(rp_track_next_serial(&pipe.trk[0], &k));
        assert_true(k < 10000u); /* wrapped */
        const rp_frameset_t *fs;
        assert_ok(rp_pipe_frameset(&pipe, &fs));
        if (runs[i].layout == RP_PIPE_STEREO4 || runs[i].layout == RP_PIPE_STEREO2) {
            assert_true(fs->n[RP_SIM_CAM1B] > 20); /* matched across the wrap */
            for (uint16_t f = 0; f < fs->n[RP_SIM_CAM1B]; ++f) {
                assert_int_equal(rp_track_id_cam(fs->f[RP_SIM_CAM1B][f].id), RP_SIM_CAM1);
            }
        }
        for (int c = 0; c < NCAM; ++c) {
            for (uint16_t f = 0; f < fs->n[c]; ++f) {
                assert_true(fs->f[c][f].id != RP_IDMAP_EMPTY);
            }
        }
    }
    g_serial0 = 0;
    /* the comparison itself, across the wrap and at half the space */
    assert_true(rp_track_serial_since(3u, RP_TRACK_SERIAL_MASK - 2u));
    assert_false(rp_track_serial_since(RP_TRACK_SERIAL_MASK - 2u, 3u));
    assert_true(rp_track_serial_since(7u, 7u));
    assert_false(rp_track_serial_since(6u, 7u));
    assert_int_equal(rp_track_id_serial(rp_track_id(5, RP_TRACK_SERIAL_MASK)),
                     RP_TRACK_SERIAL_MASK);
    assert_int_equal(rp_track_id_cam(rp_track_id(5, RP_TRACK_SERIAL_MASK)), 5);
    assert_true(rp_track_id(RP_MAX_CAMS - 1, RP_TRACK_SERIAL_MASK) != RP_IDMAP_EMPTY);
    assert_status(rp_track_set_next_serial(&pipe.trk[0], RP_TRACK_SERIAL_MASK + 1u), RP_E_ARG);
}

/* rp_pipe_time_offsets: the configured offsets, and with estimate_time_offsets the start sigma of
 * the layout's cameras but the first (stereo4: its pairs' cameras; camK: none). */
static void test_time_offsets_reported(void **state)
{
    (void)state;
    rp_pipe_cfg_t cfg;
    rp_real off[RP_MAX_CAMS], sig[RP_MAX_CAMS];
    for (int est = 0; est < 2; ++est) {
        assert_ok(rp_pipe_default_cfg(RP_PIPE_STEREO4, &cfg));
        cfg.stereo.ekf.toff0_s[2] = RP_C(-0.025);
        cfg.stereo.ekf.toff_estimate = (uint8_t)est;
        assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
        assert_ok(rp_pipe_time_offsets(&pipe, off, sig));
        assert_true(off[2] == RP_C(-0.025) && off[1] == RP_C(0.0));
        assert_true(sig[0] == RP_C(0.0));
        uint8_t in_pair[RP_MAX_CAMS] = {0};
        for (uint8_t p = 0; p < cfg.stereo.n_pairs; ++p) {
            in_pair[cfg.stereo.pair_a[p]] = in_pair[cfg.stereo.pair_b[p]] = 1;
        }
        for (int k = 1; k < NCAM; ++k) {
            assert_true(sig[k] == (est && in_pair[k] ? cfg.stereo.ekf.toff_sigma_s : RP_C(0.0)));
        }
    }
    assert_ok(rp_pipe_default_cfg(RP_PIPE_CAM2, &cfg));
    cfg.mono.ekf.toff0_s[1] = RP_C(0.012);
    cfg.mono.ekf.toff_estimate = 1;
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    assert_ok(rp_pipe_time_offsets(&pipe, off, sig));
    assert_true(off[1] == RP_C(0.012) && sig[1] == RP_C(0.0));
    assert_status(rp_pipe_time_offsets(NULL, off, sig), RP_E_ARG);
    assert_status(rp_pipe_time_offsets(&pipe, NULL, sig), RP_E_ARG);
}

/* The first frame set: the right camera of each pair carries only ids of its left camera, each
 * on the epipolar line of its partner, and every left feature has its partner (the unmatched
 * ones are dropped). */
static void test_pairs_share_ids(void **state)
{
    (void)state;
    rp_pipe_cfg_t cfg;
    assert_ok(rp_pipe_default_cfg(RP_PIPE_STEREO4, &cfg));
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    const rp_frameset_t *fs;
    assert_ok(rp_pipe_frameset(&pipe, &fs));
    for (int k = 0; k < NCAM; ++k) {
        assert_int_equal(fs->n[k], 0);
    }
    rp_image_t im[NCAM];
    const rp_image_t *ptr[NCAM];
    for (int k = 0; k < NCAM; ++k) {
        im[k] = fx_image(frames[0][k], W, H);
        ptr[k] = &im[k];
    }
    rp_estimate_t est;
    assert_ok(rp_pipe_step(&pipe, ptr, NCAM, 0, &est));
    const rp_pipe_info_t *info;
    assert_ok(rp_pipe_info(&pipe, &info));
    for (int p = 0; p < 2; ++p) {
        const uint8_t a = cfg.stereo.pair_a[p], b = cfg.stereo.pair_b[p];
        rp_stereo_pair_t sp;
        assert_ok(rp_stereo_pair_init(&rig, a, b, &sp));
        assert_true(fs->n[b] >= 60);
        assert_int_equal(info->match[p].n_matched, fs->n[b]);
        assert_int_equal(fs->n[a], fs->n[b]);
        assert_true(info->match[p].n_in >= fs->n[a]);
        double epi_max = 0;
        for (uint16_t i = 0; i < fs->n[b]; ++i) {
            const rp_feat_t *fb = &fs->f[b][i];
            assert_int_equal(rp_track_id_cam(fb->id), a);
            int found = 0;
            for (uint16_t j = 0; j < fs->n[a] && !found; ++j) {
                if (fs->f[a][j].id == fb->id) {
                    rp_real d;
                    assert_ok(rp_stereo_epipolar_px(&rig, &sp, fs->f[a][j].uv, fb->uv, &d));
                    epi_max = fmax(epi_max, (double)d);
                    found = 1;
                }
            }
            assert_true(found);
        }
        printf("  pair %d (cams %u, %u): %u left features, %u matched, epipolar max %.4f px\n",
               p, a, b, fs->n[a], fs->n[b], epi_max);
        assert_true(epi_max < 0.1);
    }
    assert_true(est.n_landmarks >= 100);
}

/* Truncated, wrongly sized, blank images and a camera too small to track: each camera gets its
 * state, the others go on; no usable image at all gives RP_E_DEGENERATE. */
static void test_bad_images_give_states(void **state)
{
    (void)state;
    rp_pipe_cfg_t cfg;
    assert_ok(rp_pipe_default_cfg(RP_PIPE_GC, &cfg));
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    rp_image_t im[NCAM];
    const rp_image_t *ptr[NCAM];
    for (int k = 0; k < NCAM; ++k) {
        im[k] = fx_image(frames[0][k], W, H);
        ptr[k] = &im[k];
    }
    static uint8_t blank[W * H];
    memset(blank, 77, sizeof(blank));
    im[1].size = W * H - 1;                 /* truncated */
    im[2] = fx_image(frames[0][2], 160, 120); /* not the calibrated size */
    im[3] = fx_image(blank, W, H);          /* blank */
    rp_estimate_t est;
    assert_ok(rp_pipe_step(&pipe, ptr, NCAM, 0, &est));
    const rp_pipe_info_t *info;
    assert_ok(rp_pipe_info(&pipe, &info));
    assert_int_equal(info->cam_state[0], RP_PIPE_CAM_OK);
    assert_int_equal(info->cam_state[1], RP_PIPE_CAM_BAD_IMAGE);
    assert_int_equal(info->cam_state[2], RP_PIPE_CAM_BAD_IMAGE);
    assert_int_equal(info->cam_state[3], RP_PIPE_CAM_BLANK);
    assert_int_equal(info->cam_state[4], RP_PIPE_CAM_UNUSED);
    assert_true(est.flags & RP_EST_DEGRADED);
    /* fewer images than cameras: the rest are missing */
    assert_ok(rp_pipe_step(&pipe, ptr, 1, DT_US, &est));
    assert_int_equal(info->cam_state[3], RP_PIPE_CAM_MISSING);
    /* nothing usable */
    const rp_image_t *none[NCAM] = {NULL, NULL, NULL, NULL, NULL, NULL};
    assert_status(rp_pipe_step(&pipe, none, NCAM, 2 * DT_US, &est), RP_E_DEGENERATE);
    assert_true(est.flags & RP_EST_LOST);
    /* time must move forward */
    assert_status(rp_pipe_step(&pipe, ptr, NCAM, 2 * DT_US, &est), RP_E_RANGE);
    assert_true(est.flags & RP_EST_LOST);

    /* a rig whose cameras are smaller than the tracker's window and pyramid */
    static rp_rig_t tiny;
    tiny = rig;
    for (int k = 0; k < NCAM; ++k) {
        tiny.cam[k].cam.width = 12;
        tiny.cam[k].cam.height = 12;
    }
    static uint8_t small[12 * 12];
    for (int i = 0; i < 144; ++i) {
        small[i] = (uint8_t)(i * 37);
    }
    assert_ok(rp_pipe_init(&pipe, &tiny, &cfg));
    for (int k = 0; k < NCAM; ++k) {
        im[k] = fx_image(small, 12, 12);
        ptr[k] = &im[k];
    }
    assert_status(rp_pipe_step(&pipe, ptr, NCAM, 0, &est), RP_E_DEGENERATE);
    assert_ok(rp_pipe_info(&pipe, &info));
    assert_int_equal(info->cam_state[0], RP_PIPE_CAM_BAD_IMAGE);
    assert_int_equal(info->cam_status[0], RP_E_ARG);
}

static void test_bad_calls(void **state)
{
    (void)state;
    rp_pipe_cfg_t cfg;
    rp_pipe_layout_t l;
    assert_status(rp_pipe_default_cfg(RP_PIPE_LAYOUT_COUNT_, &cfg), RP_E_ARG);
    assert_status(rp_pipe_default_cfg(RP_PIPE_GC, NULL), RP_E_ARG);
    for (int i = 0; i < RP_PIPE_LAYOUT_COUNT_; ++i) {
        assert_ok(rp_pipe_layout_from_name(rp_pipe_layout_name((rp_pipe_layout_t)i), &l));
        assert_int_equal(l, i);
    }
    assert_status(rp_pipe_layout_from_name("stereo3", &l), RP_E_ARG);
    assert_status(rp_pipe_layout_from_name(NULL, &l), RP_E_ARG);
    assert_string_equal(rp_pipe_layout_name(RP_PIPE_LAYOUT_COUNT_), "?");

    assert_ok(rp_pipe_default_cfg(RP_PIPE_STEREO2, &cfg));
    assert_status(rp_pipe_init(NULL, &rig, &cfg), RP_E_ARG);
    assert_status(rp_pipe_init(&pipe, NULL, &cfg), RP_E_ARG);
    assert_status(rp_pipe_init(&pipe, &rig, NULL), RP_E_ARG);
    rp_pipe_cfg_t bad = cfg;
    bad.stereo.pair_b[0] = 9; /* not a camera of the rig */
    assert_status(rp_pipe_init(&pipe, &rig, &bad), RP_E_ARG);
    bad = cfg;
    bad.stereo.pair_b[0] = bad.stereo.pair_a[0]; /* a camera twice */
    assert_status(rp_pipe_init(&pipe, &rig, &bad), RP_E_ARG);
    bad = cfg;
    bad.stereo.n_pairs = 2; /* stereo2 has one pair */
    assert_status(rp_pipe_init(&pipe, &rig, &bad), RP_E_ARG);
    bad = cfg;
    bad.track.win = 4;
    assert_status(rp_pipe_init(&pipe, &rig, &bad), RP_E_ARG);
    assert_ok(rp_pipe_default_cfg(RP_PIPE_GC, &bad));
    bad.gc.cams[3] = bad.gc.cams[0];
    assert_status(rp_pipe_init(&pipe, &rig, &bad), RP_E_ARG);
    static rp_rig_t big;
    big = rig;
    big.cam[0].cam.width = RP_TRACK_MAX_W + 2;
    assert_status(rp_pipe_init(&pipe, &big, &cfg), RP_E_ARG);

    /* a failed init leaves the pipe unusable, not half set up */
    rp_estimate_t est;
    const rp_image_t *ptr[NCAM] = {NULL, NULL, NULL, NULL, NULL, NULL};
    assert_status(rp_pipe_step(&pipe, ptr, NCAM, 0, &est), RP_E_ARG);
    assert_true(est.flags & RP_EST_LOST);
    const rp_frameset_t *fs;
    assert_status(rp_pipe_frameset(&pipe, &fs), RP_E_ARG);
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    assert_status(rp_pipe_step(NULL, ptr, NCAM, 0, &est), RP_E_ARG);
    assert_status(rp_pipe_step(&pipe, NULL, NCAM, 0, &est), RP_E_ARG);
    assert_status(rp_pipe_step(&pipe, ptr, NCAM, 0, NULL), RP_E_ARG);
    assert_status(rp_pipe_step(&pipe, ptr, RP_MAX_CAMS + 1, 0, &est), RP_E_ARG);
    assert_status(rp_pipe_frameset(&pipe, NULL), RP_E_ARG);
    assert_status(rp_pipe_info(NULL, NULL), RP_E_ARG);
}

/* The phased step (rp_pipe_begin, rp_pipe_track per tracker in any order, rp_pipe_match,
 * rp_pipe_estimate) is rp_pipe_step: stereo4 and gc on 6 frames with the trackers run last to
 * first, each stereo pair matched as soon as its two trackers have run (before the other
 * pair's trackers), give the same estimates, bit for bit, as rp_pipe_step; calls out of order
 * are refused and a step left unfinished is dropped by the next begin. */
static rp_pipe_t pipe2;

static void phased_step(rp_pipe_t *p, const rp_image_t *const ptr[], int64_t utime,
                        rp_estimate_t *est)
{
    assert_int_equal(rp_pipe_topup_tracker(p), rp_pipe_n_trackers(p)); /* no step begun */
    assert_ok(rp_pipe_begin(p, utime, NULL)); /* est optional: a front end has none */
    /* one detecting tracker has the top-up turn (stereo4: a pair's first camera, 0 or 2) */
    const uint8_t turn = rp_pipe_topup_tracker(p);
    uint8_t turn_cam = 99;
    assert_ok(rp_pipe_tracker_cam(p, turn, &turn_cam));
    assert_true(turn_cam < 4); /* cam1..cam4: no pair's second camera (4, 5) */
    uint8_t tracked[RP_PIPE_MAX_TRACKERS] = {0};
    for (int t = rp_pipe_n_trackers(p) - 1; t >= 0; --t) {
        assert_ok(rp_pipe_track(p, (uint8_t)t, ptr, NCAM));
        tracked[t] = 1;
        for (int k = rp_pipe_n_pairs(p) - 1; k >= 0; --k) { /* a pair whose two have run */
            uint8_t ta = 99, tb = 99;
            assert_ok(rp_pipe_pair_trackers(p, (uint8_t)k, &ta, &tb));
            assert_true(ta < rp_pipe_n_trackers(p) && tb < rp_pipe_n_trackers(p) && ta != tb);
            if ((t == ta || t == tb) && tracked[ta] && tracked[tb]) {
                assert_ok(rp_pipe_match_pair(p, (uint8_t)k));
                assert_ok(rp_pipe_match_pair(p, (uint8_t)k)); /* twice: once */
            }
        }
    }
    assert_ok(rp_pipe_match(p));
    const rp_frameset_t *fs;
    assert_ok(rp_pipe_frameset(p, &fs));
    assert_int_equal(fs->utime, utime);
    const rp_status_t st = rp_pipe_estimate(p, est);
    assert_true(st == RP_OK || st == RP_E_TOO_FEW);
}

/* pipe and pipe2 on the same configuration of layout l (gc: the room's depth prior). */
static void init_both(rp_pipe_layout_t l)
{
    rp_pipe_cfg_t cfg;
    assert_ok(rp_pipe_default_cfg(l, &cfg));
    cfg.gc.init_depth_m = RP_C(1.2);
    cfg.gc.init_depth_sigma_m = RP_C(0.3);
    cfg.gc.init_on_sphere = 1;
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    assert_ok(rp_pipe_init(&pipe2, &rig, &cfg));
}

static void test_phased_step_is_the_step(void **state)
{
    (void)state;
    static const rp_pipe_layout_t layouts[2] = {RP_PIPE_STEREO4, RP_PIPE_GC};
    for (int li = 0; li < 2; ++li) {
        init_both(layouts[li]);
        assert_int_equal(rp_pipe_n_trackers(&pipe), 4);
        assert_int_equal(rp_pipe_n_pairs(&pipe), layouts[li] == RP_PIPE_GC ? 0 : 2);
        uint8_t cam = 99;
        assert_ok(rp_pipe_tracker_cam(&pipe, 1, &cam));
        assert_int_equal(cam, layouts[li] == RP_PIPE_GC ? 1 : 4); /* gc: cam2; stereo4: cam1b */
        for (int j = 0; j < 6; ++j) {
            rp_image_t im[NCAM];
            const rp_image_t *ptr[NCAM];
            for (int k = 0; k < NCAM; ++k) {
                im[k] = fx_image(frames[j][k], W, H);
                ptr[k] = &im[k];
            }
            rp_estimate_t a, b;
            const rp_status_t st = rp_pipe_step(&pipe, ptr, NCAM, (int64_t)j * DT_US, &a);
            assert_true(st == RP_OK || st == RP_E_TOO_FEW);
            phased_step(&pipe2, ptr, (int64_t)j * DT_US, &b);
            assert_memory_equal(a.p, b.p, sizeof a.p);
            assert_memory_equal(a.cov, b.cov, sizeof a.cov);
            assert_int_equal(a.flags, b.flags);
            assert_memory_equal(a.n_used, b.n_used, sizeof a.n_used);
        }
    }
    /* out of order */
    rp_image_t im0 = fx_image(frames[0][0], W, H);
    const rp_image_t *ptr[NCAM] = {&im0, NULL, NULL, NULL, NULL, NULL};
    rp_estimate_t est;
    uint8_t cam;
    assert_status(rp_pipe_track(&pipe2, 0, ptr, NCAM), RP_E_ARG);   /* no step begun */
    assert_status(rp_pipe_match(&pipe2), RP_E_ARG);
    assert_status(rp_pipe_estimate(&pipe2, &est), RP_E_ARG);
    assert_true(est.flags & RP_EST_LOST);
    assert_status(rp_pipe_begin(&pipe2, 5 * DT_US, &est), RP_E_RANGE); /* not after the last */
    assert_true(est.flags & RP_EST_LOST);
    assert_ok(rp_pipe_begin(&pipe2, 7 * DT_US, NULL));
    assert_status(rp_pipe_estimate(&pipe2, &est), RP_E_ARG);          /* not matched */
    assert_ok(rp_pipe_begin(&pipe2, 8 * DT_US, NULL));                /* dropped, started over */
    assert_status(rp_pipe_track(&pipe2, 4, ptr, NCAM), RP_E_ARG);     /* tracker out of range */
    assert_status(rp_pipe_track(&pipe2, 0, NULL, NCAM), RP_E_ARG);
    assert_status(rp_pipe_track(&pipe2, 0, ptr, RP_MAX_CAMS + 1), RP_E_ARG);
    assert_ok(rp_pipe_track(&pipe2, 0, ptr, NCAM));
    assert_ok(rp_pipe_match(&pipe2));
    assert_status(rp_pipe_track(&pipe2, 1, ptr, NCAM), RP_E_ARG);     /* matched already */
    assert_status(rp_pipe_match_pair(&pipe2, 0), RP_E_ARG);           /* gc: no pairs */
    assert_status(rp_pipe_estimate(&pipe2, NULL), RP_E_ARG);
    assert_status(rp_pipe_begin(NULL, 0, NULL), RP_E_ARG);
    assert_int_equal(rp_pipe_n_trackers(NULL), 0);
    assert_status(rp_pipe_tracker_cam(&pipe2, 4, &cam), RP_E_ARG);
    assert_status(rp_pipe_tracker_cam(&pipe2, 0, NULL), RP_E_ARG);
    uint8_t ta, tb;
    assert_status(rp_pipe_pair_trackers(&pipe2, 0, &ta, &tb), RP_E_ARG); /* gc: no pairs */
    assert_status(rp_pipe_pair_trackers(NULL, 0, &ta, &tb), RP_E_ARG);
    init_both(RP_PIPE_STEREO4); /* pairs (cam1, cam1b) and (cam3, cam3b): trackers 0 1, 2 3 */
    assert_ok(rp_pipe_pair_trackers(&pipe2, 1, &ta, &tb));
    assert_true(ta == 2 && tb == 3);
    assert_status(rp_pipe_pair_trackers(&pipe2, 2, &ta, &tb), RP_E_ARG);
    assert_status(rp_pipe_pair_trackers(&pipe2, 0, NULL, &tb), RP_E_ARG);
}

/* Cameras with their own capture times (rp_pipe_step_timed, rp_pipe_cam_time). Given every
 * camera stamped at the set's time, stereo4 and gc give bit for bit rp_pipe_step's estimates
 * and a frame set with cam_dt_us all 0. Given times 5 ms apart (some before the set's time),
 * the frame set carries each camera's difference, each tracker its camera's time, and a camera
 * without an image is flagged RP_FS_NO_IMAGE with its time not read (INT64_MIN there is no
 * error). A time 2^31 us away is refused with RP_E_RANGE before anything is done (the report,
 * the frame set and the time order unchanged; 2^31 - 1 us is taken); the phased call refuses
 * a camera outside the rig, a step not begun or already estimated, and the int64 ends. */
static void test_camera_times(void **state)
{
    (void)state;
    static const rp_pipe_layout_t layouts[2] = {RP_PIPE_STEREO4, RP_PIPE_GC};
    for (int li = 0; li < 2; ++li) {
        init_both(layouts[li]);
        for (int j = 0; j < 6; ++j) {
            rp_image_t im[NCAM];
            const rp_image_t *ptr[NCAM];
            int64_t t[NCAM];
            for (int k = 0; k < NCAM; ++k) {
                im[k] = fx_image(frames[j][k], W, H);
                ptr[k] = &im[k];
                t[k] = (int64_t)j * DT_US;
            }
            rp_estimate_t a, b;
            const rp_status_t sa = rp_pipe_step(&pipe, ptr, NCAM, (int64_t)j * DT_US, &a);
            const rp_status_t sb =
                rp_pipe_step_timed(&pipe2, ptr, t, NCAM, (int64_t)j * DT_US, &b);
            assert_int_equal(sa, sb);
            assert_memory_equal(a.p, b.p, sizeof a.p);
            assert_memory_equal(a.cov, b.cov, sizeof a.cov);
            assert_int_equal(a.flags, b.flags);
            const rp_frameset_t *fs;
            assert_ok(rp_pipe_frameset(&pipe2, &fs));
            for (int k = 0; k < NCAM; ++k) {
                assert_int_equal(fs->cam_dt_us[k], 0);
                assert_int_equal(fs->cam_flags[k], 0);
            }
        }
    }

    /* gc on cameras 0..3, each 5 ms after the previous one, the set's time between them;
     * camera 2 without an image */
    rp_pipe_cfg_t cfg;
    assert_ok(rp_pipe_default_cfg(RP_PIPE_GC, &cfg));
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    rp_image_t im[NCAM];
    const rp_image_t *ptr[NCAM];
    int64_t t[NCAM];
    const int64_t u = 1000000;
    for (int k = 0; k < NCAM; ++k) {
        im[k] = fx_image(frames[0][k], W, H);
        ptr[k] = &im[k];
        t[k] = u - 7000 + 5000 * k;
    }
    ptr[2] = NULL;
    t[2] = INT64_MIN; /* not read: no image */
    rp_estimate_t est;
    assert_ok(rp_pipe_step_timed(&pipe, ptr, t, NCAM, u, &est));
    const rp_frameset_t *fs;
    const rp_pipe_info_t *info;
    assert_ok(rp_pipe_frameset(&pipe, &fs));
    assert_ok(rp_pipe_info(&pipe, &info));
    assert_true(fs->utime == u);
    static const int32_t want_dt[NCAM] = {-7000, -2000, 0, 8000, 13000, 18000};
    for (int k = 0; k < NCAM; ++k) {
        assert_int_equal(fs->cam_dt_us[k], want_dt[k]);
        assert_int_equal(fs->cam_flags[k], k == 2 ? RP_FS_NO_IMAGE : 0);
    }
    assert_int_equal(info->cam_state[2], RP_PIPE_CAM_MISSING);
    for (uint8_t tr = 0; tr < rp_pipe_n_trackers(&pipe); ++tr) {
        uint8_t cam;
        assert_ok(rp_pipe_tracker_cam(&pipe, tr, &cam));
        if (cam != 2) { /* a tracker without an image keeps its last image's time */
            assert_true(pipe.trk[tr].utime == t[cam]);
        }
    }

    /* a time that does not fit: nothing done */
    t[2] = u + DT_US;
    t[3] = u + DT_US + ((int64_t)1 << 31);
    ptr[2] = &im[2];
    assert_status(rp_pipe_step_timed(&pipe, ptr, t, NCAM, u + DT_US, &est), RP_E_RANGE);
    assert_true(est.flags & RP_EST_LOST);
    assert_int_equal(info->frame, 1);
    assert_int_equal(fs->cam_dt_us[0], -7000);
    assert_int_equal(fs->cam_flags[2], RP_FS_NO_IMAGE);
    t[3] = u + DT_US - ((int64_t)1 << 31) - 1;
    assert_status(rp_pipe_step_timed(&pipe, ptr, t, NCAM, u + DT_US, &est), RP_E_RANGE);
    t[3] = u + DT_US + INT32_MAX;
    t[1] = u + DT_US + INT32_MIN;
    /* the same time again, now taken (whatever the estimator makes of 35 min) */
    const rp_status_t st = rp_pipe_step_timed(&pipe, ptr, t, NCAM, u + DT_US, &est);
    assert_true(st != RP_E_RANGE && st != RP_E_ARG);
    assert_int_equal(info->frame, 2);
    assert_int_equal(fs->cam_dt_us[3], INT32_MAX);
    assert_int_equal(fs->cam_dt_us[1], INT32_MIN);
    assert_int_equal(fs->cam_flags[2], 0);
    assert_status(rp_pipe_step_timed(NULL, ptr, t, NCAM, u, &est), RP_E_ARG);
    assert_status(rp_pipe_step_timed(&pipe, ptr, t, RP_MAX_CAMS + 1, u, &est), RP_E_ARG);

    /* phased: the time set before a camera's tracking is its tracker's */
    assert_status(rp_pipe_cam_time(&pipe, 0, u), RP_E_ARG); /* no step begun */
    const int64_t u3 = u + 3 * DT_US;
    assert_ok(rp_pipe_begin(&pipe, u3, NULL));
    assert_ok(rp_pipe_cam_time(&pipe, 1, u3 + 250));
    assert_ok(rp_pipe_cam_time(&pipe, 5, u3 - 250)); /* a rig camera outside the layout */
    assert_status(rp_pipe_cam_time(&pipe, NCAM, u3), RP_E_ARG);
    assert_status(rp_pipe_cam_time(&pipe, RP_MAX_CAMS, u3), RP_E_ARG);
    assert_status(rp_pipe_cam_time(NULL, 0, u3), RP_E_ARG);
    assert_status(rp_pipe_cam_time(&pipe, 1, INT64_MIN), RP_E_RANGE);
    assert_status(rp_pipe_cam_time(&pipe, 1, INT64_MAX), RP_E_RANGE);
    for (uint8_t tr = 0; tr < rp_pipe_n_trackers(&pipe); ++tr) {
        assert_ok(rp_pipe_track(&pipe, tr, ptr, NCAM));
    }
    assert_ok(rp_pipe_match(&pipe));
    assert_ok(rp_pipe_cam_time(&pipe, 0, u3 - 100)); /* after tracking: the frame set's only */
    assert_ok(rp_pipe_frameset(&pipe, &fs));
    assert_int_equal(fs->cam_dt_us[0], -100);
    assert_int_equal(fs->cam_dt_us[1], 250);
    assert_int_equal(fs->cam_dt_us[2], 0);
    assert_int_equal(fs->cam_dt_us[5], -250);
    assert_true(pipe.trk[pipe.cam_trk[1]].utime == u3 + 250);
    assert_true(pipe.trk[pipe.cam_trk[0]].utime == u3);
    assert_true(rp_pipe_estimate(&pipe, &est) != RP_E_ARG);
    assert_status(rp_pipe_cam_time(&pipe, 0, u3), RP_E_ARG); /* estimated */

    /* the int64 ends do not overflow the difference */
    int32_t dt = 7;
    assert_status(rp_pipe_cam_dt(INT64_MIN, INT64_MAX, &dt), RP_E_RANGE);
    assert_status(rp_pipe_cam_dt(INT64_MAX, INT64_MIN, &dt), RP_E_RANGE);
    assert_status(rp_pipe_cam_dt(0, INT32_MIN, &dt), RP_E_RANGE); /* 2^31 */
    assert_int_equal(dt, 7);
    assert_ok(rp_pipe_cam_dt(INT64_MIN, INT64_MIN + INT32_MAX, &dt));
    assert_int_equal(dt, -INT32_MAX);
    assert_ok(rp_pipe_cam_dt(-5, 7, &dt));
    assert_int_equal(dt, -12);
    assert_status(rp_pipe_cam_dt(0, 0, NULL), RP_E_ARG);
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    assert_ok(rp_pipe_begin(&pipe, INT64_MAX - 10, NULL));
    assert_status(rp_pipe_cam_time(&pipe, 0, INT64_MIN), RP_E_RANGE);
    assert_ok(rp_pipe_cam_time(&pipe, 0, INT64_MAX));
    assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
    assert_ok(rp_pipe_begin(&pipe, INT64_MIN + 10, NULL));
    assert_status(rp_pipe_cam_time(&pipe, 0, INT64_MAX), RP_E_RANGE);
    assert_ok(rp_pipe_cam_time(&pipe, 0, INT64_MIN));
}

/* Given trackers that would top up at every frame set (threshold = target), then in gc (4
 * detecting trackers) and stereo4 (2: the pairs' first cameras) only the tracker whose turn it
 * is tops up: the d-th detecting one on frame sets d modulo their count (rp_pipe.h); every
 * tracker detects at the first frame set. */
static void test_topups_take_turns(void **state)
{
    (void)state;
    static const rp_pipe_layout_t layouts[2] = {RP_PIPE_GC, RP_PIPE_STEREO4};
    static const uint8_t det_cams[2][4] = {{0, 1, 2, 3}, {0, 2, 0, 0}};
    static const uint8_t n_det[2] = {4, 2};
    for (int li = 0; li < 2; ++li) {
        rp_pipe_cfg_t cfg;
        assert_ok(rp_pipe_default_cfg(layouts[li], &cfg));
        cfg.gc.init_depth_m = RP_C(1.2);
        cfg.gc.init_on_sphere = 1;
        cfg.track.topup_below = cfg.track.target;
        assert_ok(rp_pipe_init(&pipe, &rig, &cfg));
        int n_topped = 0;
        for (int j = 0; j < NFRAMES; ++j) {
            rp_image_t im[NCAM];
            const rp_image_t *ptr[NCAM];
            for (int k = 0; k < NCAM; ++k) {
                im[k] = fx_image(frames[j][k], W, H);
                ptr[k] = &im[k];
            }
            rp_estimate_t est;
            const rp_status_t st = rp_pipe_step(&pipe, ptr, NCAM, (int64_t)j * DT_US, &est);
            assert_true(st == RP_OK || st == RP_E_TOO_FEW);
            const rp_pipe_info_t *info;
            assert_ok(rp_pipe_info(&pipe, &info));
            for (uint8_t d = 0; d < n_det[li]; ++d) {
                const rp_track_info_t *ti = &info->track[det_cams[li][d]];
                const int topped = (ti->flags & RP_TRACK_TOPPED_UP) != 0;
                if (j == 0) {
                    assert_true(topped);
                } else if (info->frame % n_det[li] != d) {
                    assert_false(topped);
                } else {
                    n_topped += topped;
                }
            }
        }
        print_message("%s: %d top-ups on the trackers' turns in %d frame sets\n",
                      rp_pipe_layout_name(layouts[li]), n_topped, NFRAMES - 1);
        assert_true(n_topped >= (NFRAMES - 1) / 2);
    }
}

/* Feature-level input: rp_pipe_step_feats gives exactly what the layout's estimator gives on
 * the same frame sets (stereo4 against rp_vo_stereo, gc against rp_vo_gc, 12 frame sets of
 * run 0 of the simulation seeded 3), keeps the frame set and reports the cameras; a repeated
 * time and bad calls give their status. */
static void test_step_feats_is_the_layouts_estimator(void **state)
{
    (void)state;
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.n_frames = 12;
    static rp_sim_run_t sr;
    static rp_frameset_t fs;
    static rp_vo_stereo_t vs;
    static rp_vo_gc_t vg;
    assert_int_equal(rp_sim_run_init(&sr, &sc, 3, 0), 0);
    static const rp_pipe_layout_t layouts[2] = {RP_PIPE_STEREO4, RP_PIPE_GC};
    for (int l = 0; l < 2; ++l) {
        rp_pipe_cfg_t cfg;
        assert_ok(rp_pipe_default_cfg(layouts[l], &cfg));
        cfg.gc = rp_sim_gc_cfg(&sc); /* features born at the simulation's shell */
        assert_ok(rp_pipe_init(&pipe, &sr.rig, &cfg));
        if (l == 0) {
            assert_ok(rp_vo_stereo_init(&vs, &sr.rig, &cfg.stereo));
        } else {
            assert_ok(rp_vo_gc_init(&vg, &sr.rig, &cfg.gc));
        }
        rp_estimate_t e_pipe, e_est;
        for (uint32_t j = 0; j < sc.n_frames; ++j) {
            rp_sim_frame(&sr, j, &fs);
            const rp_status_t st = rp_pipe_step_feats(&pipe, &fs, &e_pipe);
            assert_int_equal(st, l == 0 ? rp_vo_stereo_step(&vs, &fs, &e_est)
                                        : rp_vo_gc_step(&vg, &fs, &e_est));
            assert_ok(st);
            assert_memory_equal(e_pipe.p, e_est.p, sizeof(e_est.p));
            assert_int_equal(e_pipe.flags, e_est.flags);
            const rp_frameset_t *kept;
            const rp_pipe_info_t *info;
            assert_ok(rp_pipe_frameset(&pipe, &kept));
            assert_ok(rp_pipe_info(&pipe, &info));
            assert_memory_equal(kept->n, fs.n, sizeof(fs.n));
            assert_int_equal(info->frame, j + 1);
            assert_int_equal(info->cam_state[0], RP_PIPE_CAM_OK);
            assert_int_equal(info->cam_state[RP_SIM_CAM1B], l == 0 ? RP_PIPE_CAM_OK
                                                                   : RP_PIPE_CAM_UNUSED);
        }
        double te = 0;
        for (int i = 0; i < 3; ++i) {
            te = fmax(te, fabs((double)e_pipe.p[i] - sr.truth[6u * (sc.n_frames - 1) + i]));
        }
        printf("  %s from features: last frame error %.6f m\n", rp_pipe_layout_name(layouts[l]),
               te);
        assert_true(te < 0.01);
    }
    /* the same time again: nothing done, the last estimate marked lost */
    rp_estimate_t est;
    assert_status(rp_pipe_step_feats(&pipe, &fs, &est), RP_E_RANGE);
    assert_true(est.flags & RP_EST_LOST);
    assert_status(rp_pipe_step_feats(&pipe, NULL, &est), RP_E_ARG);
    assert_true(est.flags & RP_EST_LOST);
    assert_status(rp_pipe_step_feats(&pipe, &fs, NULL), RP_E_ARG);
    assert_status(rp_pipe_step_feats(NULL, &fs, &est), RP_E_ARG);
    rp_sim_run_free(&sr);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pairs_share_ids),
        cmocka_unit_test(test_time_offsets_reported),
        cmocka_unit_test_setup(test_ids_across_the_serial_wrap, setup_frames),
        cmocka_unit_test(test_stereo4_tracks_motion),
        cmocka_unit_test(test_stereo2_tracks_motion),
        cmocka_unit_test(test_stereo2_right_missing_at_start),
        cmocka_unit_test(test_gc_tracks_motion),
        cmocka_unit_test(test_single_camera_and_rc_run),
        cmocka_unit_test(test_bad_images_give_states),
        cmocka_unit_test(test_bad_calls),
        cmocka_unit_test(test_phased_step_is_the_step),
        cmocka_unit_test(test_camera_times),
        cmocka_unit_test(test_topups_take_turns),
        cmocka_unit_test(test_step_feats_is_the_layouts_estimator),
    };
    return cmocka_run_group_tests(tests, setup_frames, NULL);
}
