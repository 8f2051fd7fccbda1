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

/* The front pair's right camera stamped 5 ms (beyond max_pair_skew_s) / 0.5 ms (within) after
 * the set in every frame set (the sim captured it with the others). */
static void front_right_5ms(rp_frameset_t *fs, uint32_t j)
{
    (void)j;
    fs->cam_dt_us[RP_SIM_CAM1B] = 5000;
}

static void front_right_half_ms(rp_frameset_t *fs, uint32_t j)
{
    (void)j;
    fs->cam_dt_us[RP_SIM_CAM1B] = 500;
}

/* A pair whose images are farther apart in time than max_pair_skew_s makes no landmarks and
 * says so (UNSYNCED); the other pair carries the pose. Within the limit nothing is flagged. */
static void test_skewed_pair_makes_no_landmarks(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 30, 0);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    double err[6];
    uint32_t flags;
    assert_int_equal(run_sequence(fx, &cfg, 30, front_right_5ms, err, &flags), 0);
    assert_true(flags & RP_EST_UNSYNCED);
    assert_int_equal(fx->vo.lm.map.n_group[0], 0); /* the front pair (group 0) holds none */
    assert_true(fx->vo.lm.map.n_group[1] > 0);
    for (int i = 0; i < 3; ++i) assert_true(err[i] < 5e-3);
    assert_int_equal(run_sequence(fx, &cfg, 30, front_right_half_ms, err, &flags), 0);
    assert_false(flags & RP_EST_UNSYNCED);
    cfg.max_pair_skew_s = RP_C(-1.0);
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
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

/* Frame 1: sixteen features of cam1 mistracked by 15 px (a tracker's outliers). */
static void outliers_at_frame_1(rp_frameset_t *fs, uint32_t j)
{
    for (uint16_t i = 0; j == 1 && i < fs->n[RP_SIM_CAM1] && i < 16; ++i) {
        fs->f[RP_SIM_CAM1][i].uv[0] += RP_C(15.0);
    }
}

/* Frame 0: ten matches of the front pair read wrong: cam1b's pixel 20 px down (off the epipolar
 * line), and with g_both also cam1's 25 px right. */
#define RETRY_N 10
static uint32_t g_retry_id[RETRY_N];
static int g_both;
static void bad_matches_at_frame_0(rp_frameset_t *fs, uint32_t j)
{
    if (j != 0) return;
    for (uint16_t i = 0; i < RETRY_N; ++i) {
        rp_feat_t *fb = &fs->f[RP_SIM_CAM1B][i];
        g_retry_id[i] = fb->id;
        fb->uv[1] += RP_C(20.0);
        for (uint16_t k = 0; g_both && k < fs->n[RP_SIM_CAM1]; ++k) {
            if (fs->f[RP_SIM_CAM1][k].id == fb->id) fs->f[RP_SIM_CAM1][k].uv[0] += RP_C(25.0);
        }
    }
}

/* Sum of the traces of the landmark covariances of the ten ids; -1 if one is not held. */
static double retried_trace(const rp_vo_stereo_t *vo)
{
    double tr = 0.0;
    for (int i = 0; i < RETRY_N; ++i) {
        uint16_t slot;
        if (rp_lmtab_find(&vo->lm, g_retry_id[i], &slot) != RP_OK) return -1.0;
        const rp_real *C = vo->lm.pt[slot].C;
        tr += (double)(C[0] + C[3] + C[5]);
    }
    return tr;
}

/* A match that fails the checks at the start (one pixel read wrong) is no landmark then, is on
 * the list of failed matches, and becomes a landmark at the next frame set (retry_triangulation;
 * without it, not); there it also takes the right one of its two first pixels through its
 * structure EKF: its covariance is smaller than when both first pixels were wrong (the gate
 * refuses both, the landmark keeps the next frame set's triangulation alone). */
static void test_failed_matches_are_retried_with_their_first_pixels(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 2, 3);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    double err[6], tr[2];
    uint32_t flags;
    for (int both = 0; both < 2; ++both) {
        g_both = both;
        assert_int_equal(run_sequence(fx, &cfg, 1, bad_matches_at_frame_0, err, &flags), 0);
        assert_true(retried_trace(&fx->vo) < 0.0); /* not landmarks at frame 0 */
        assert_true(fx->vo.n_retry[0] >= RETRY_N);
        assert_int_equal(run_sequence(fx, &cfg, 2, bad_matches_at_frame_0, err, &flags), 0);
        tr[both] = retried_trace(&fx->vo);
        assert_true(tr[both] > 0.0); /* landmarks at frame 1 */
    }
    print_message("retried landmarks, sum of covariance traces: %.3e m^2 with one right first "
                  "pixel, %.3e with none\n", tr[0], tr[1]);
    assert_true(tr[0] < 0.9 * tr[1]);
    g_both = 0;
    cfg.retry_triangulation = 0;
    cfg.add_landmarks = 0; /* the paper's map: the failed matches wait for a re-initialisation */
    assert_int_equal(run_sequence(fx, &cfg, 2, bad_matches_at_frame_0, err, &flags), 0);
    assert_true(retried_trace(&fx->vo) < 0.0);
    assert_int_equal(fx->vo.n_retry[0], 0);
    cfg.add_landmarks = 1; /* every match not yet a landmark is tried at frame 1 anyway */
    assert_int_equal(run_sequence(fx, &cfg, 2, bad_matches_at_frame_0, err, &flags), 0);
    assert_true(retried_trace(&fx->vo) > 0.0);
    simfx_free(fx);
}

/* Ids of frame set fs seen in both cameras of pair (a, b). */
static uint16_t matched_ids(const rp_frameset_t *fs, uint8_t a, uint8_t b)
{
    uint16_t m = 0;
    for (uint16_t i = 0; i < fs->n[a]; ++i) {
        for (uint16_t j = 0; j < fs->n[b]; ++j) {
            m = (uint16_t)(m + (fs->f[a][i].id == fs->f[b][j].id));
        }
    }
    return m;
}

/* add_landmarks (rp_vo_stereo.h, step 5): the points that come into view become landmarks as
 * they are matched, so the map follows the view: after 100 frames of the paper's motion the
 * map holds nearly every match of the last frame set (a few fail the checks), where the
 * paper's map (add_landmarks 0) holds only what its initialisation saw and still tracks.
 * Checked on the structure of the two runs, not on their errors. */
static void test_new_matches_become_landmarks(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 100, 0);
    uint16_t n_lm[2] = {0, 0}, n_match = 0;
    for (int add = 0; add < 2; ++add) {
        rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
        cfg.add_landmarks = (uint8_t)add;
        assert_ok(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg));
        simfx_score_t sc;
        simfx_run(&fx->sim, stereo_step, &fx->vo, 100, NULL, NULL, NULL, &sc);
        assert_int_equal(sc.lost, 0);
        n_lm[add] = fx->vo.lm.map.n;
        n_match = (uint16_t)(matched_ids(&fx->sim.fs, RP_SIM_CAM1, RP_SIM_CAM1B) +
                             matched_ids(&fx->sim.fs, RP_SIM_CAM3, RP_SIM_CAM3B));
    }
    print_message("matches in the last frame set %u; landmarks %u with the paper's map, %u with "
                  "landmarks added\n", n_match, n_lm[0], n_lm[1]);
    assert_true(n_lm[1] >= n_match * 9 / 10);
    assert_true(n_lm[0] < n_match / 2);
    simfx_free(fx);
}

/* The filter starts at frame 1 from Lowe's method, which has no gate: the observations the
 * EKF's gate would reject at Lowe's pose are left out and the pose solved again. Before that,
 * sixteen mistracked features (of about 1,500) moved the start pose and the filter kept the
 * offset (rendered run 4 of seed 1: tz 1.6 mm off at frame 1, 0.9 mm mean). */
static void test_outliers_at_the_start_frame_are_left_out(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 12, 6);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    double err[6];
    uint32_t flags;
    assert_int_equal(run_sequence(fx, &cfg, 12, outliers_at_frame_1, err, &flags), 0);
    simfx_print_err("stereo4, 16 outliers at frame 1, 11 frames", err);
    for (int i = 0; i < 6; ++i) assert_true(err[i] < RP_TOL(1e-4, 1.5e-4));
    simfx_free(fx);
}

/* A trajectory of constant velocity (per frame 6, -4, 5 mm and 4, -3, 5 mrad) whose frame
 * `jump` and every later frame are moved by off[6]: at frame `jump` the constant-velocity
 * prediction is off by exactly that. */
static void set_jump_trajectory(rp_sim_run_t *sr, uint32_t frames, uint32_t jump,
                                const double off[6])
{
    static const double vel[6] = {0.006, -0.004, 0.005, 0.004, -0.003, 0.005};
    for (uint32_t j = 0; j < frames; ++j) {
        double *t = &sr->truth[6u * j];
        for (int i = 0; i < 6; ++i) t[i] = vel[i] * j + (j >= jump ? off[i] : 0.0);
        rp_real abg[3] = {(rp_real)t[3], (rp_real)t[4], (rp_real)t[5]}, R[9];
        rp_rot_from_angles(abg, R);
        for (int i = 0; i < 9; ++i) sr->truth_R[9u * j + i] = (double)R[i];
    }
}

/* The pose direction (unit, m and rad mixed) the back pair sees least at frame j: the principal
 * axis of the covariance of a pose fitted (rp_lowe_solve) to its exact pixels of frame j. */
static void back_pair_blind_direction(const rp_sim_run_t *sr, uint32_t j, double d[6])
{
    static rp_frameset_t fs;
    static rp_obs_t obs[2 * RP_MAX_FEATS_PER_CAM];
    rp_sim_frame(sr, j, &fs);
    rp_real p[6], cov[36];
    for (int i = 0; i < 6; ++i) p[i] = (rp_real)sr->truth[6u * j + i];
    rp_pose_lin_t pl;
    assert_ok(rp_pose_lin_set(&pl, p));
    uint32_t n = 0;
    static const uint8_t cams[2] = {RP_SIM_CAM3, RP_SIM_CAM3B};
    for (int c = 0; c < 2; ++c) {
        for (uint16_t f = 0; f < fs.n[cams[c]]; ++f) {
            rp_obs_t *o = &obs[n];
            for (int a = 0; a < 3; ++a) o->M[a] = (rp_real)sr->points[3u * fs.f[cams[c]][f].id + a];
            o->w = RP_C(1.0);
            o->cam = cams[c];
            if (rp_rig_project(&sr->rig, cams[c], &pl, o->M, o->uv, NULL, NULL) == RP_OK) n++;
        }
    }
    assert_ok(rp_lowe_solve(&sr->rig, obs, n, NULL, p, NULL, cov));
    for (int i = 0; i < 6; ++i) d[i] = 1.0;
    for (int it = 0; it < 200; ++it) { /* power iteration */
        double e[6], norm = 0.0;
        for (int i = 0; i < 6; ++i) {
            e[i] = 0.0;
            for (int k = 0; k < 6; ++k) e[i] += (double)cov[i * 6 + k] * d[k];
            norm += e[i] * e[i];
        }
        for (int i = 0; i < 6; ++i) d[i] = e[i] / sqrt(norm);
    }
}

/* Thins the frame set as the rendered frames were: the front pair keeps every 6th feature id
 * (the same ids in both of its cameras; about 60 observations), the back pair only the features
 * in the central 256 x 192 px of its images (about 90), so the back pair sees its weakest pose
 * direction hardly at all (0.3 px for the jump below) and outnumbers the front pair. */
static void thin_pairs(rp_frameset_t *fs, uint32_t j)
{
    (void)j;
    static const uint8_t cams[4] = {RP_SIM_CAM1, RP_SIM_CAM1B, RP_SIM_CAM3, RP_SIM_CAM3B};
    for (int c = 0; c < 4; ++c) {
        uint16_t m = 0;
        for (uint16_t i = 0; i < fs->n[cams[c]]; ++i) {
            const rp_feat_t *ft = &fs->f[cams[c]][i];
            const int keep = c < 2 ? ft->id % 6 == 0
                                   : fabs((double)ft->uv[0] - 320.0) <= 128.0 &&
                                         fabs((double)ft->uv[1] - 240.0) <= 96.0;
            if (keep) fs->f[cams[c]][m++] = *ft;
        }
        fs->n[cams[c]] = m;
    }
}

/* The failure of rendered run 0 of seed 1 at frame 94, without images. The scene is a sphere
 * (a smooth surface, as the rendered shell is within one camera's view) and the back pair keeps
 * only central features, so it has a nearly blind pose direction (mostly tx with beta); the
 * constant-velocity prediction is off by 30 mm along it (60 px in the front cameras, 0.3 px in
 * the back ones). The update's first gate, taken at the prediction, rejects every front
 * feature while the back pair's pass, and the back pair outnumbers the front, so the gate
 * stays on. Before the fix the pose stayed off along that direction (14 mm here, 16 mm on the
 * rendered frames) and the front pair's landmarks were dropped as outliers; now the update is
 * redone with its prior widened. The paper's motion makes such prediction errors common
 * (independent increments of 5-15 mm per frame and axis). Run with the plain gated update
 * (one_point 0) and with the defaults. With the paper's one-observation hypotheses the 1-point
 * update needed the retry here (the consensus of one pair's camera); its hypotheses now take
 * one observation of each of three cameras (rp_ekf1pt.h) and both updates use both pairs at
 * the first try (the retry count is printed: the retry stays the fallback). */
static void blind_direction_run(int plain);
static void test_prediction_off_along_one_pairs_blind_direction_is_recovered(void **state)
{
    (void)state;
    for (int plain = 1; plain >= 0; --plain) {
        blind_direction_run(plain);
    }
}

static void blind_direction_run(int plain)
{
    const uint32_t frames = 30, jump = 20;
    fixture_t *fx = fixture(0.5, frames, 0);
    rp_sim_run_t *sr = &fx->sim.sr;
    for (uint32_t i = 0; i < sr->cfg.n_points; ++i) {
        double *P = &sr->points[3u * i];
        const double r = sqrt(P[0] * P[0] + P[1] * P[1] + P[2] * P[2]);
        for (int a = 0; a < 3; ++a) P[a] *= 0.85 / r;
    }
    double off[6] = {0}, d[6];
    set_jump_trajectory(sr, frames, jump, off);
    back_pair_blind_direction(sr, jump, d);
    for (int i = 0; i < 6; ++i) off[i] = 0.03 * d[i] / sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    print_message("prediction error at the jump: %.4f %.4f %.4f m %.4f %.4f %.4f rad\n", off[0],
                  off[1], off[2], off[3], off[4], off[5]);
    set_jump_trajectory(sr, frames, jump, off);
    rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
    cfg.ekf.q_trans = RP_C(3.0); /* rp_pipe's plant noise */
    cfg.ekf.q_rot = RP_C(3.0);
    cfg.one_point = (uint8_t)!plain;
    assert_ok(rp_vo_stereo_init(&fx->vo, &sr->rig, &cfg));
    double worst_after = 0.0;
    for (uint32_t j = 0; j < frames; ++j) {
        rp_sim_frame(sr, j, &fx->sim.fs);
        thin_pairs(&fx->sim.fs, j);
        assert_ok(rp_vo_stereo_step(&fx->vo, &fx->sim.fs, &fx->sim.est));
        if (j == jump) {
            print_message("%s, jump frame: used front %u back %u, gated %u, retried %u\n",
                          plain ? "plain update" : "defaults",
                          fx->sim.est.n_used[RP_SIM_CAM1] + fx->sim.est.n_used[RP_SIM_CAM1B],
                          fx->sim.est.n_used[RP_SIM_CAM3] + fx->sim.est.n_used[RP_SIM_CAM3B],
                          fx->sim.est.n_gated, fx->vo.n_retried);
        }
        for (int i = 0; j >= jump && i < 6; ++i) {
            worst_after = fmax(worst_after, fabs((double)fx->sim.est.p[i] - sr->truth[6u * j + i]));
        }
    }
    print_message("worst pose error from the jump on: %.2e\n", worst_after);
    assert_true(worst_after < 2e-3);
    simfx_free(fx);
}

/* Replaces a share `frac` of every camera's features by gross outliers: pixels uniform over the
 * 640 x 480 image, drawn from a fixed generator (the same for every run of the test). */
static uint64_t g_outlier_rng;
static double g_outlier_frac;
static uint32_t g_outlier_from, g_outlier_to;
static double outlier_u01(void)
{
    g_outlier_rng ^= g_outlier_rng >> 12;
    g_outlier_rng ^= g_outlier_rng << 25;
    g_outlier_rng ^= g_outlier_rng >> 27;
    return (double)((g_outlier_rng * 0x2545F4914F6CDD1Dull) >> 11) / 9007199254740992.0;
}
static void gross_outliers(rp_frameset_t *fs, uint32_t j)
{
    if (j < g_outlier_from || j > g_outlier_to) return;
    for (uint8_t c = 0; c < RP_MAX_CAMS; ++c) {
        for (uint16_t i = 0; i < fs->n[c]; ++i) {
            if (outlier_u01() < g_outlier_frac) {
                fs->f[c][i].uv[0] = (rp_real)(640.0 * outlier_u01());
                fs->f[c][i].uv[1] = (rp_real)(480.0 * outlier_u01());
            }
        }
    }
}
static void set_outliers(double frac, uint32_t from, uint32_t to)
{
    g_outlier_rng = 0x9E3779B97F4A7C15ull;
    g_outlier_frac = frac;
    g_outlier_from = from;
    g_outlier_to = to;
}

static double worst_of(const double err[6])
{
    double w = 0.0;
    for (int i = 0; i < 6; ++i) w = fmax(w, err[i]);
    return w;
}

/* 30 % gross outliers in every camera at the frame that starts the filter (frame 1): rig
 * RANSAC finds the start pose from the inliers; Lowe's method on everything does not. */
static void test_gross_outliers_at_the_start_are_found_by_ransac(void **state)
{
    (void)state;
    double err_on[6], err_off[6];
    uint32_t flags;
    for (int on = 1; on >= 0; --on) {
        fixture_t *fx = fixture(0.5, 30, 3);
        rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
        cfg.ransac = (uint8_t)on;
        set_outliers(0.3, 1, 1);
        (void)run_sequence(fx, &cfg, 30, gross_outliers, on ? err_on : err_off, &flags);
        simfx_free(fx);
    }
    simfx_print_err("stereo4, 30 % outliers at frame 1, RANSAC start", err_on);
    simfx_print_err("stereo4, 30 % outliers at frame 1, Lowe's start", err_off);
    for (int i = 0; i < 3; ++i) assert_true(err_on[i] < 2e-4);
    assert_true(worst_of(err_off) > 2.0 * worst_of(err_on)); /* the test can fail */
}

/* A turn's onset: the constant-velocity prediction is off by 0.15 rad of yaw (beta; about
 * 120 px in every camera) at frame 20, and 30 % of every camera's
 * features are gross outliers at that frame, so neither the gate nor Lowe's method on all
 * observations can recover: the pose is re-found from the images by rig RANSAC. */
static void test_turn_onset_with_outliers_is_refound_by_ransac(void **state)
{
    (void)state;
    const uint32_t frames = 30, jump = 20;
    /* m = 0: the plain update without rig RANSAC, 1: the plain update with it (the re-find is
     * what recovers), 2: the defaults (1-point RANSAC's hypotheses through the prior find the
     * turn themselves) */
    double worst[3] = {0.0, 0.0, 0.0};
    uint32_t refound = 0;
    for (int m = 2; m >= 0; --m) {
        fixture_t *fx = fixture(0.5, frames, 0);
        rp_sim_run_t *sr = &fx->sim.sr;
        static const double off[6] = {0.0, 0.0, 0.0, 0.0, 0.15, 0.0};
        set_jump_trajectory(sr, frames, jump, off);
        rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
        if (m < 2) {
            cfg.ransac = (uint8_t)m;
            cfg.one_point = 0;
        }
        assert_ok(rp_vo_stereo_init(&fx->vo, &sr->rig, &cfg));
        set_outliers(0.3, jump, jump);
        for (uint32_t j = 0; j < frames; ++j) {
            rp_sim_frame(sr, j, &fx->sim.fs);
            gross_outliers(&fx->sim.fs, j);
            (void)rp_vo_stereo_step(&fx->vo, &fx->sim.fs, &fx->sim.est);
            for (int i = 0; j >= jump && i < 6; ++i) {
                worst[m] = fmax(worst[m],
                                fabs((double)fx->sim.est.p[i] - sr->truth[6u * j + i]));
            }
        }
        if (m == 1) refound = fx->vo.n_refound;
        simfx_free(fx);
    }
    print_message("turn onset + 30 %% outliers: worst pose error from the jump on %.2e with "
                  "rig RANSAC (%u re-found), %.2e without, %.2e with the defaults\n", worst[1],
                  refound, worst[0], worst[2]);
    assert_true(refound >= 1);
    assert_true(worst[1] < 2e-3);
    assert_true(worst[2] < 2e-3);
    assert_true(worst[0] > 2.0 * worst[1]); /* the test can fail */
}

/* The same input gives the same output, bit for bit: the generators of rig RANSAC and 1-point
 * RANSAC are seeded at init. */
static void test_ransac_runs_are_deterministic(void **state)
{
    (void)state;
    rp_real p[2][6];
    for (int r = 0; r < 2; ++r) {
        fixture_t *fx = fixture(0.5, 25, 4);
        rp_vo_stereo_cfg_t cfg = stereo_cfg(2, 0.5);
        cfg.one_point = 1;
        assert_ok(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg));
        set_outliers(0.3, 1, 24);
        for (uint32_t j = 0; j < 25; ++j) {
            rp_sim_frame(&fx->sim.sr, j, &fx->sim.fs);
            gross_outliers(&fx->sim.fs, j);
            (void)rp_vo_stereo_step(&fx->vo, &fx->sim.fs, &fx->sim.est);
        }
        memcpy(p[r], fx->sim.est.p, sizeof(p[r]));
        simfx_free(fx);
    }
    assert_memory_equal(p[0], p[1], sizeof(p[0]));
}

/* Feature-level simulation with 30 % gross outliers (uniform pixels, drawn anew every frame) in
 * every camera at every frame. The target is 1.5x the clean figure in every component.
 * An outlier drawn anew every frame says nothing about its track, so the layout must neither
 * drop a landmark the first frame set its pixels read wrong nor give up a match whose pixels
 * read wrong at the (re-)initialisation: the drop test and the retried matches
 * (rp_vo_stereo.h). Over 50 runs of 100 frames (docs/results.md) the defaults come to
 * 1.3-1.5x; this sample of 2 runs x 60 frames is too small for the target (0.8-2.4x by
 * component), so the test pins that the defaults beat, in every component, the rule before
 * them (a landmark left out in both cameras dropped at once, drop_odds just above 1; no retry),
 * and that the method before issue 14 (neither RANSAC) is far worse; figures printed. */
static void test_thirty_percent_gross_outliers_everywhere(void **state)
{
    (void)state;
    const int runs = 2;
    const uint32_t frames = 60;
    static const char *const label[4] = {
        "stereo4, 30 % outliers, defaults", "  drop at once, no retry", "  rig RANSAC only",
        "  neither RANSAC (before)"};
    double clean[6] = {0}, dirty[4][6] = {{0}};
    for (int r = 0; r < runs; ++r) {
        double err[6];
        uint32_t flags;
        fixture_t *fx = fixture(0.5, frames, (uint32_t)r);
        const rp_vo_stereo_cfg_t def = stereo_cfg(2, 0.5);
        assert_int_equal(run_sequence(fx, &def, frames, NULL, err, &flags), 0);
        for (int i = 0; i < 6; ++i) clean[i] += err[i] / runs;
        for (int m = 0; m < 4; ++m) {
            rp_vo_stereo_cfg_t cfg = def;
            if (m == 1) {
                cfg.drop_odds = RP_C(1.0001);
                cfg.retry_triangulation = 0;
            }
            cfg.one_point = m < 2;
            cfg.ransac = m < 3;
            set_outliers(0.3, 0, frames);
            (void)run_sequence(fx, &cfg, frames, gross_outliers, err, &flags);
            for (int i = 0; i < 6; ++i) dirty[m][i] += err[i] / runs;
        }
        simfx_free(fx);
    }
    simfx_print_err("stereo4 clean", clean);
    for (int m = 0; m < 4; ++m) simfx_print_err(label[m], dirty[m]);
    for (int i = 0; i < 6; ++i) assert_true(dirty[0][i] < dirty[1][i]);
    for (int i = 0; i < 6; ++i) assert_true(dirty[3][i] > 2.5 * clean[i]);
}

/* A moving object carried alongside the rig in front of the front pair: 40 % of the points
 * cam1 and cam1b see belong to it; each sits at the pixel where the camera first saw it and
 * drifts from there by (1.5, -1) px per frame in both cameras (the object moving across the
 * view at a constant depth, with the front camera), so its stereo triangulation is consistent
 * and its image motion agrees neither with the static scene nor with the rig's. The hook keeps,
 * per id, the first frame and pixel in each of the two cameras. */
#define OBJ_MAX 4096
static uint32_t g_obj_id[OBJ_MAX];
static rp_real g_obj_uv[OBJ_MAX][2][2];
static uint32_t g_obj_j0[OBJ_MAX][2];
static uint8_t g_obj_seen[OBJ_MAX][2];
static uint32_t g_obj_n;

static void comoving_object(rp_frameset_t *fs, uint32_t j)
{
    static const uint8_t cams[2] = {RP_SIM_CAM1, RP_SIM_CAM1B};
    for (int c = 0; c < 2; ++c) {
        for (uint16_t i = 0; i < fs->n[cams[c]]; ++i) {
            rp_feat_t *f = &fs->f[cams[c]][i];
            if ((f->id * 2654435761u) % 10u >= 4u) {
                continue; /* a static point */
            }
            uint32_t k = 0;
            while (k < g_obj_n && g_obj_id[k] != f->id) ++k;
            if (k == g_obj_n) {
                assert_true(g_obj_n < OBJ_MAX); /* every object point is the object's */
                g_obj_id[g_obj_n++] = f->id;
                g_obj_seen[k][0] = g_obj_seen[k][1] = 0;
            }
            if (!g_obj_seen[k][c]) {
                g_obj_seen[k][c] = 1;
                g_obj_j0[k][c] = j;
                g_obj_uv[k][c][0] = f->uv[0];
                g_obj_uv[k][c][1] = f->uv[1];
            }
            const rp_real age = (rp_real)(j - g_obj_j0[k][c]);
            f->uv[0] = g_obj_uv[k][c][0] + RP_C(1.5) * age;
            f->uv[1] = g_obj_uv[k][c][1] - age;
        }
    }
}

/* Largest ratio of err to clean over the six components. */
static double worst_ratio(const double err[6], const double clean[6])
{
    double w = 0.0;
    for (int i = 0; i < 6; ++i) w = fmax(w, err[i] / clean[i]);
    return w;
}

/* The co-moving object above, stereo4, 3 runs x 60 frames, with the re-initialisation threshold
 * raised to 200 landmarks so that the front pair, left with the static 60 % of its 255 after the
 * object's are dropped, re-initialises every frame (as a real camera's fewer tracks do): with
 * outlier tracks retired (rp_vo_stereo.h) the object's tracks, once rejected, stay out of the
 * map; without, every re-initialisation brings them back. Measured: retired 1.1-1.6x the clean
 * figures; not retired 5-34x in its worst component on the x86 builds before the drop test
 * (rp_vo_stereo.h; 1.6x since on x86-64 double), 1.7x on the aarch64 float build, where the
 * object happens to lose every consensus (without retiring the outcome turns on which group each
 * re-initialisation's update picks). The test pins retired within 2x
 * in every component with no frame lost and tracks actually retired (so that it can fail); the
 * not-retired figures are printed beside. */
static void test_comoving_object_tracks_are_retired(void **state)
{
    (void)state;
    const int runs = 3;
    const uint32_t frames = 60;
    double clean[6] = {0}, dirty[2][6] = {{0}};
    uint32_t most_retired = 0;
    for (int r = 0; r < runs; ++r) {
        double err[6];
        uint32_t flags;
        fixture_t *fx = fixture(0.5, frames, (uint32_t)r);
        rp_vo_stereo_cfg_t def = stereo_cfg(2, 0.5);
        def.min_tracked = 200;
        assert_int_equal(run_sequence(fx, &def, frames, NULL, err, &flags), 0);
        for (int i = 0; i < 6; ++i) clean[i] += err[i] / runs;
        for (int m = 0; m < 2; ++m) {
            rp_vo_stereo_cfg_t cfg = def;
            cfg.retire_outliers = (uint8_t)(m == 0);
            g_obj_n = 0;
            const uint32_t lost = run_sequence(fx, &cfg, frames, comoving_object, err, &flags);
            if (m == 0) {
                assert_int_equal(lost, 0);
                if (fx->vo.n_retired > most_retired) most_retired = fx->vo.n_retired;
            }
            for (int i = 0; i < 6; ++i) dirty[m][i] += err[i] / runs;
        }
        simfx_free(fx);
    }
    simfx_print_err("stereo4 clean", clean);
    simfx_print_err("stereo4, co-moving object, tracks retired", dirty[0]);
    simfx_print_err("  not retired", dirty[1]);
    printf("  retired tracks held at the end of a run: %u at most\n", (unsigned)most_retired);
    for (int i = 0; i < 6; ++i) assert_true(dirty[0][i] <= 2.0 * clean[i]);
    assert_true(most_retired > 0); /* the object's tracks were retired: it can fail */
    printf("  worst ratio to clean: retired %.2f, not retired %.2f\n",
           worst_ratio(dirty[0], clean), worst_ratio(dirty[1], clean));
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
    cfg = stereo_cfg(1, 0.5);
    cfg.ransac = 2; /* a switch is 0 or 1 */
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = stereo_cfg(1, 0.5);
    cfg.one_point = 2;
    assert_status(rp_vo_stereo_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = stereo_cfg(1, 0.5);
    cfg.retire_outliers = 2;
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
        cmocka_unit_test(test_skewed_pair_makes_no_landmarks),
        cmocka_unit_test(test_all_cameras_dark_reports_lost_then_recovers),
        cmocka_unit_test(test_nan_pixels_are_skipped),
        cmocka_unit_test(test_prediction_off_along_one_pairs_blind_direction_is_recovered),
        cmocka_unit_test(test_failed_matches_are_retried_with_their_first_pixels),
        cmocka_unit_test(test_new_matches_become_landmarks),
        cmocka_unit_test(test_outliers_at_the_start_frame_are_left_out),
        cmocka_unit_test(test_gross_outliers_at_the_start_are_found_by_ransac),
        cmocka_unit_test(test_turn_onset_with_outliers_is_refound_by_ransac),
        cmocka_unit_test(test_ransac_runs_are_deterministic),
        cmocka_unit_test(test_thirty_percent_gross_outliers_everywhere),
        cmocka_unit_test(test_comoving_object_tracks_are_retired),
        cmocka_unit_test(test_malformed_frameset_is_rejected_without_damage),
        cmocka_unit_test(test_bad_configuration_is_refused),
    };
    return cmocka_run_group_tests_name("vo_stereo", tests, NULL, NULL);
}
