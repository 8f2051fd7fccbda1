/*
 * test_vo_gc.c - the generalised camera (gc) end to end on the paper's simulation, with the
 * four single cameras (front, right, back, left): accuracy against the paper's "2 cameras"
 * row, consistency of the pose covariance (3-sigma fraction, NEES), the metric scale from the
 * offsets when the assumed depth is wrong, top-up of features, cameras
 * going dark, malformed frame sets and bad configuration.
 */
#include <string.h>

#include "rigpose/rp_linalg.h"
#include "rigpose/rp_vo_gc.h"
#include "sim_fixture.h"

typedef struct {
    simfx_t sim; /* first: the run, frame set and estimate */
    rp_vo_gc_t vo;
} fixture_t;

static fixture_t *fixture(double noise_px, uint32_t frames, uint32_t run)
{
    return simfx_new(sizeof(fixture_t), noise_px, frames, run);
}

static rp_vo_gc_cfg_t gc_cfg(double noise_px)
{
    return simfx_gc_cfg(noise_px);
}

typedef struct {
    double err[6];      /* mean absolute error over frames 1.., m and rad */
    uint32_t lost;      /* frames whose step did not return RP_OK */
    uint32_t flags_or;  /* union of the flags */
    uint32_t in3;       /* scored frames with every pose column within 3 sigma */
    uint32_t in3_col[6];/* per column */
    double nees_sum;    /* sum of e^T P^-1 e over scored frames */
    uint32_t nees_in;   /* scored frames with e^T P^-1 e within the 6-dof 99.73 % bound */
    uint32_t scored;
} outcome_t;

/* e^T C^-1 e for the 6x6 covariance C; -1 if C is not positive definite. */
static double nees6(const double e[6], const rp_real cov[36])
{
    rp_real C[36], L[36], b[6], x[6];
    memcpy(C, cov, sizeof(C));
    for (int i = 0; i < 6; ++i) b[i] = (rp_real)e[i];
    if (rp_la_chol(&RP_MAT(6, 6, C), &RP_MAT(6, 6, L)) != RP_OK) return -1.0;
    if (rp_la_chol_solve(&RP_MAT(6, 6, L), &RP_MAT(6, 1, b), &RP_MAT(6, 1, x)) != RP_OK) {
        return -1.0;
    }
    double s = 0.0;
    for (int i = 0; i < 6; ++i) s += e[i] * (double)x[i];
    return s;
}

static rp_status_t gc_step(void *vo, const rp_frameset_t *fs, rp_estimate_t *est)
{
    return rp_vo_gc_step(vo, fs, est);
}

/* Per scored frame: the covariance's 3-sigma bounds and the NEES. */
static void score_covariance(void *ctx, const rp_estimate_t *est, const double e[6])
{
    outcome_t *out = ctx;
    int all_in = 1;
    for (int i = 0; i < 6; ++i) {
        const double sd = sqrt((double)est->cov[i * 6 + i]);
        if (fabs(e[i]) <= 3.0 * sd) {
            out->in3_col[i]++;
        } else {
            all_in = 0;
        }
    }
    out->in3 += (uint32_t)all_in;
    double q = nees6(e, est->cov);
    assert_true(q >= 0.0);
    out->nees_sum += q;
    out->nees_in += q <= 20.06; /* chi-square, 6 dof, 99.73 % (the 3-sigma mass) */
    out->scored++;
}

static void run_sequence(fixture_t *fx, const rp_vo_gc_cfg_t *cfg, uint32_t frames,
                         simfx_mutate_fn mutate, outcome_t *out)
{
    assert_ok(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, cfg));
    memset(out, 0, sizeof(*out));
    simfx_score_t sc;
    simfx_run(&fx->sim, gc_step, &fx->vo, frames, mutate, score_covariance, out, &sc);
    memcpy(out->err, sc.err, sizeof(sc.err));
    out->lost = sc.lost;
    out->flags_or = sc.flags_or;
}

static void test_noise_free_run_follows_truth(void **state)
{
    (void)state;
    /* Without noise the only error left is the one the assumed depth leaves in the metric
     * scale before the rig's offsets correct it: millimetres, and no drift in rotation. */
    fixture_t *fx = fixture(0.0, 40, 0);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.0);
    outcome_t o;
    run_sequence(fx, &cfg, 40, NULL, &o);
    simfx_print_err("gc noise-free", o.err);
    assert_int_equal(o.lost, 0);
    for (int i = 0; i < 3; ++i) assert_true(o.err[i] < 3e-3);
    /* (float: a 0.01 px filter sigma is near the scalar's resolution) */
    for (int i = 3; i < 6; ++i) assert_true(o.err[i] < RP_TOL(1e-3, 3e-3));
    assert_true(fx->sim.est.flags & RP_EST_TRACKING);
    simfx_free(fx);
}

static void test_noisy_runs_beat_the_papers_stereo_pair(void **state)
{
    (void)state;
    /* The paper's Table 1, "2 cameras" (its stereo pair): gc must reach it without stereo. */
    static const double paper2[6] = {.0055, .0132, .0042, .0137, .0055, .0026};
    double mean[6] = {0};
    const int runs = 4;
    for (int r = 0; r < runs; ++r) {
        fixture_t *fx = fixture(0.5, 100, (uint32_t)r);
        rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
        outcome_t o;
        run_sequence(fx, &cfg, 100, NULL, &o);
        assert_int_equal(o.lost, 0);
        for (int i = 0; i < 6; ++i) mean[i] += o.err[i] / runs;
        simfx_free(fx);
    }
    simfx_print_err("gc over 4 runs", mean);
    for (int i = 0; i < 6; ++i) assert_true(mean[i] <= paper2[i]);
}

static void test_pose_covariance_is_consistent(void **state)
{
    (void)state;
    /* Every pose column within 3 sigma of the truth in most frames, and the NEES of the
     * 6-dof pose in a sane range (6 when perfectly consistent). */
    uint32_t in3 = 0, scored = 0, in3_col[6] = {0}, nees_in = 0;
    double nees = 0.0;
    const int runs = 4;
    for (int r = 0; r < runs; ++r) {
        fixture_t *fx = fixture(0.5, 100, (uint32_t)(10 + r));
        rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
        outcome_t o;
        run_sequence(fx, &cfg, 100, NULL, &o);
        in3 += o.in3;
        scored += o.scored;
        nees += o.nees_sum;
        nees_in += o.nees_in;
        for (int i = 0; i < 6; ++i) in3_col[i] += o.in3_col[i];
        simfx_free(fx);
    }
    const double frac = (double)in3 / scored;
    print_message("gc consistency: all six within 3 sigma in %.1f%% of %u frames; per column "
                  "%.0f %.0f %.0f %.0f %.0f %.0f %%; mean NEES %.1f (6 = consistent), "
                  "NEES within chi2(6) 99.73 %% bound in %.1f%% of frames\n",
                  100.0 * frac, scored, 100.0 * in3_col[0] / scored, 100.0 * in3_col[1] / scored,
                  100.0 * in3_col[2] / scored, 100.0 * in3_col[3] / scored,
                  100.0 * in3_col[4] / scored, 100.0 * in3_col[5] / scored, nees / scored,
                  100.0 * nees_in / scored);
    assert_true(frac >= 0.90);
    assert_true((double)nees_in / scored >= 0.90);
    assert_true(nees / scored < 20.0);
}

static void test_wrong_assumed_depth_is_corrected_by_the_offsets(void **state)
{
    (void)state;
    /* New features assumed at 0.7 m in a shell of 0.667..1 m: the map starts about 15 %
     * small. Without step 6 that error is the trajectory's scale for good; with it, the
     * window adjustments find the map's unit from the rig's offsets. */
    double err_on[6] = {0}, err_off[6] = {0}, mu = 0.0;
    const int runs = 3;
    for (int r = 0; r < runs; ++r) {
        for (int on = 0; on < 2; ++on) {
            fixture_t *fx = fixture(0.5, 100, (uint32_t)(20 + r));
            rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
            cfg.init_depth_m = (rp_real)0.7;
            if (!on) cfg.mscale_sigma = 0;
            outcome_t o;
            run_sequence(fx, &cfg, 100, NULL, &o);
            assert_int_equal(o.lost, 0);
            for (int i = 0; i < 6; ++i) (on ? err_on : err_off)[i] += o.err[i] / runs;
            /* RP_EST_SCALE_WEAK: raised while the unit is the assumed depth's, cleared once
             * the windows have told it as well as the reported covariance claims */
            if (on) {
                mu += (double)fx->vo.mu / runs;
                assert_true(fx->vo.n_ba > 5);
                assert_true(o.flags_or & RP_EST_SCALE_WEAK); /* at the start */
                assert_false(fx->sim.est.flags & RP_EST_SCALE_WEAK);
            } else {
                assert_int_equal(fx->vo.n_ba, 0);
                assert_near(fx->vo.mu, 1.0, 0.0);
                assert_true(fx->sim.est.flags & RP_EST_SCALE_WEAK);
            }
            simfx_free(fx);
        }
    }
    simfx_print_err("gc, depth assumed 0.7 m, metric scale off", err_off);
    simfx_print_err("gc, depth assumed 0.7 m, metric scale on ", err_on);
    print_message("gc: map units per metre at the end, mean of %d runs: %.3f\n", runs, mu);
    for (int i = 0; i < 3; ++i) assert_true(err_on[i] < 0.4 * err_off[i]);
    assert_true(mu < 0.95);
}

static void test_top_up_adds_features_and_keeps_accuracy(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 60, 1);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    cfg.min_tracked = 400; /* more than a camera sees: top up every frame */
    outcome_t o;
    run_sequence(fx, &cfg, 60, NULL, &o);
    assert_int_equal(o.lost, 0);
    assert_true(o.flags_or & RP_EST_REINIT);
    for (int i = 0; i < 3; ++i) assert_true(o.err[i] < 1e-2);
    simfx_free(fx);
}

/* The right camera delivers nothing from frame 20 to 29. */
static void right_camera_dark(rp_frameset_t *fs, uint32_t j)
{
    if (j >= 20 && j < 30) fs->n[RP_SIM_CAM2] = 0;
}

static void test_one_camera_dark_keeps_tracking_with_the_others(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 50, 2);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    outcome_t o;
    run_sequence(fx, &cfg, 50, right_camera_dark, &o);
    assert_int_equal(o.lost, 0);
    assert_true(o.flags_or & RP_EST_DEGRADED);
    for (int i = 0; i < 3; ++i) assert_true(o.err[i] < 1e-2);
    for (int i = 3; i < 6; ++i) assert_true(o.err[i] < 5e-3);
    /* the camera's landmarks survived the gap: it is used again */
    assert_true(fx->sim.est.n_used[RP_SIM_CAM2] > 0);
    simfx_free(fx);
}

static void test_all_cameras_dark_reports_lost_then_recovers(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 40, 3);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    outcome_t o;
    run_sequence(fx, &cfg, 40, simfx_all_dark_10_12, &o);
    assert_int_equal(o.lost, 3);
    assert_true(o.flags_or & RP_EST_LOST);
    simfx_assert_last_position_near(&fx->sim, 39, 0.1);
    assert_true(fx->sim.est.flags & RP_EST_TRACKING);
    simfx_free(fx);
}

static void test_nan_pixels_are_skipped(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 20, 4);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    outcome_t o;
    run_sequence(fx, &cfg, 20, simfx_nan_pixels_cam1, &o);
    assert_int_equal(o.lost, 0);
    for (int i = 0; i < 3; ++i) assert_true(o.err[i] < 1e-2);
    simfx_free(fx);
}

static void test_malformed_frameset_is_rejected_without_damage(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 10, 5);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    assert_ok(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg));
    simfx_check_malformed(&fx->sim, gc_step, &fx->vo, 2);
    assert_true(fx->sim.est.n_landmarks > 200);
    assert_status(rp_vo_gc_step(NULL, &fx->sim.fs, &fx->sim.est), RP_E_ARG);
    simfx_free(fx);
}

/* Gross outliers (uniform pixels over the 640 x 480 image, drawn anew every frame) replacing a
 * share of every camera's features, from a fixed generator. */
static uint64_t g_out_rng;
static double g_out_frac;
static double out_u01(void)
{
    g_out_rng ^= g_out_rng >> 12;
    g_out_rng ^= g_out_rng << 25;
    g_out_rng ^= g_out_rng >> 27;
    return (double)((g_out_rng * 0x2545F4914F6CDD1Dull) >> 11) / 9007199254740992.0;
}
static void gross_outliers(rp_frameset_t *fs, uint32_t j)
{
    (void)j;
    for (uint8_t c = 0; c < RP_MAX_CAMS; ++c) {
        for (uint16_t i = 0; i < fs->n[c]; ++i) {
            if (out_u01() < g_out_frac) {
                fs->f[c][i].uv[0] = (rp_real)(640.0 * out_u01());
                fs->f[c][i].uv[1] = (rp_real)(480.0 * out_u01());
            }
        }
    }
}

/* Feature-level simulation with 30 % gross outliers in every camera at every frame (issue 14's
 * must-show: gc within 1.5x of its clean figures). On this sample (6 runs x 60 frames, the
 * defaults: 1-point RANSAC, the re-find, keyframes of the window adjustment holding only the
 * pixels their landmark's structure gate took, step 3b's drop test) the six columns are
 * 0.86-1.39x the clean figures; over 50 runs x 100 frames (`rigpose-sim --outliers 0.3`,
 * docs/results.md) 1.05-1.40x. Two runs were too few: with a first version of the drop test
 * (odds 100) one column read 1.56x on them against 1.41x over the 50 runs. With every pixel of a
 * keyframe's landmarks in the window (before) the angles were 2.1-3.3x over the 50 runs: the
 * outliers in the windows had the adjustments refused, and gc's rotations drifted without
 * them. */
static void test_thirty_percent_gross_outliers_everywhere(void **state)
{
    (void)state;
    const int runs = 6;
    const uint32_t frames = 60;
    double clean[6] = {0}, robust[6] = {0}, plain[6] = {0};
    for (int r = 0; r < runs; ++r) {
        fixture_t *fx = fixture(0.5, frames, (uint32_t)r);
        const rp_vo_gc_cfg_t def = gc_cfg(0.5);
        outcome_t o;
        run_sequence(fx, &def, frames, NULL, &o);
        for (int i = 0; i < 6; ++i) clean[i] += o.err[i] / runs;
        for (int m = 0; m < 2; ++m) {
            rp_vo_gc_cfg_t cfg = def;
            cfg.one_point = (uint8_t)(m == 0);
            cfg.ransac = (uint8_t)(m == 0);
            g_out_rng = 0x9E3779B97F4A7C15ull;
            g_out_frac = 0.3;
            run_sequence(fx, &cfg, frames, gross_outliers, &o);
            for (int i = 0; i < 6; ++i) (m == 0 ? robust : plain)[i] += o.err[i] / runs;
        }
        simfx_free(fx);
    }
    simfx_print_err("gc clean", clean);
    simfx_print_err("gc, 30 % outliers, 1-point RANSAC + re-find", robust);
    simfx_print_err("gc, 30 % outliers, plain gated update", plain);
    double w_robust = 0.0, w_plain = 0.0;
    for (int i = 0; i < 6; ++i) {
        w_robust = fmax(w_robust, robust[i] / clean[i]);
        w_plain = fmax(w_plain, plain[i] / clean[i]);
    }
    print_message("worst column: %.1fx clean with the defaults, %.1fx with the plain update\n",
                  w_robust, w_plain);
    for (int i = 0; i < 6; ++i) assert_true(robust[i] <= 1.5 * clean[i]);
    assert_true(w_plain > 1.5); /* the test can fail */
}

/* A group of cam1's tracks that moves on its own (an object: 1.5 px (3 sigma) per frame to the right, a
 * third of cam1's features) in a run otherwise clean: step 3b's drop test drops their
 * landmarks and retires the tracks, and leaves the static scene's alone. */
static uint32_t g_mov_ids[RP_MAX_FEATS_PER_CAM], g_static_ids[RP_MAX_FEATS_PER_CAM];
static uint16_t g_n_mov, g_n_static;
static uint32_t g_first_max_id; /* ids up to it were landmarks from frame 0 (step 1) */
static void moving_group(rp_frameset_t *fs, uint32_t j)
{
    g_n_mov = g_n_static = 0;
    for (uint16_t i = 0; i < fs->n[0]; ++i) {
        rp_feat_t *f = &fs->f[0][i];
        if (j == 0) {
            g_first_max_id = f->id > g_first_max_id ? f->id : g_first_max_id;
        }
        if (f->id % 3 == 0) {
            f->uv[0] += (rp_real)(1.5 * (double)j);
        }
        if (f->id > g_first_max_id) {
            continue; /* born later: a landmark only if cam1 ran short (step 4) */
        }
        if (f->id % 3 == 0) {
            g_mov_ids[g_n_mov++] = f->id;
        } else {
            g_static_ids[g_n_static++] = f->id;
        }
    }
}

static void test_a_moving_group_of_tracks_is_dropped_and_retired(void **state)
{
    (void)state;
    const uint32_t frames = 40;
    fixture_t *fx = fixture(0.5, frames, 0);
    for (int on = 0; on < 2; ++on) {
        rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
        cfg.drop_odds = on ? rp_vo_gc_default_cfg().drop_odds : RP_C(0.0);
        g_first_max_id = 0;
        outcome_t o;
        run_sequence(fx, &cfg, frames, moving_group, &o);
        /* of the moving tracks that were landmarks (the table, full, takes only the first
         * few hundred of frame 0's features): retired, or still a landmark */
        uint16_t mov_retired = 0, mov_kept = 0, static_retired = 0;
        for (uint16_t i = 0; i < g_n_mov; ++i) {
            uint8_t r = 0;
            uint16_t slot;
            assert_ok(rp_vo_gc_is_retired(&fx->vo, g_mov_ids[i], &r));
            mov_retired = (uint16_t)(mov_retired + r);
            mov_kept = (uint16_t)(mov_kept + (rp_lmtab_find(&fx->vo.lm, g_mov_ids[i], &slot) == RP_OK));
        }
        for (uint16_t i = 0; i < g_n_static; ++i) {
            uint8_t r = 0;
            assert_ok(rp_vo_gc_is_retired(&fx->vo, g_static_ids[i], &r));
            static_retired = (uint16_t)(static_retired + r);
        }
        print_message("drop test %s: of cam1's tracks since frame 0, %u moving ones retired and %u "
                      "still landmarks (of %u), %u of %u static ones retired; %u landmarks "
                      "dropped\n", on ? "on" : "off", mov_retired, mov_kept, g_n_mov,
                      static_retired, g_n_static, fx->vo.n_dropped);
        simfx_print_err(on ? "gc, moving group, drop test" : "gc, moving group, no drop test",
                        o.err);
        assert_int_equal(o.lost, 0);
        if (on) {
            assert_true(mov_retired > 10);
            assert_true(mov_retired * 10 >= (mov_retired + mov_kept) * 9); /* nearly all */
            assert_true(static_retired * 20 <= g_n_static);     /* few of the scene's */
        } else {
            assert_int_equal(mov_retired + static_retired, 0);
            assert_int_equal(fx->vo.n_dropped, 0);
        }
    }
    uint8_t r = 1;
    assert_int_equal(rp_vo_gc_is_retired(NULL, 1, &r), RP_E_ARG);
    assert_int_equal(rp_vo_gc_is_retired(&fx->vo, 1, NULL), RP_E_ARG);
    simfx_free(fx);
}

static void test_bad_configuration_is_refused(void **state)
{
    (void)state;
    fixture_t *fx = fixture(0.5, 2, 0);
    rp_vo_gc_cfg_t cfg = gc_cfg(0.5);
    assert_status(rp_vo_gc_init(NULL, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    assert_status(rp_vo_gc_init(&fx->vo, NULL, &cfg), RP_E_ARG);
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, NULL), RP_E_ARG);
    cfg.n_cams = 0;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.cams[3] = RP_SIM_CAM1; /* a camera twice */
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.one_point = 2; /* a switch is 0 or 1 */
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.ransac = 2;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.cams[1] = 9; /* no such camera */
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.init_depth_m = 0;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.init_depth_sigma_m = (rp_real)NAN;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.min_tracked = 3;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.mature_frac = -1;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.ekf.sigma_px = -1;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    /* the metric scale step's settings (checked while it is on) */
    cfg = gc_cfg(0.5);
    cfg.mscale_sigma = -1;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.ba_kf = RP_GCBA_MAX_KF + 1;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.ba_stride = 0;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.ba_per_cam = 4;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.ba_var_scale = (rp_real)0.5;
    assert_status(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg), RP_E_ARG);
    cfg = gc_cfg(0.5);
    cfg.mscale_sigma = 0;
    cfg.ba_stride = 0; /* step 6 off: its settings are not looked at */
    assert_ok(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg));
    cfg = gc_cfg(0.5);
    assert_ok(rp_vo_gc_init(&fx->vo, &fx->sim.sr.rig, &cfg));
    simfx_free(fx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_noise_free_run_follows_truth),
        cmocka_unit_test(test_noisy_runs_beat_the_papers_stereo_pair),
        cmocka_unit_test(test_pose_covariance_is_consistent),
        cmocka_unit_test(test_wrong_assumed_depth_is_corrected_by_the_offsets),
        cmocka_unit_test(test_top_up_adds_features_and_keeps_accuracy),
        cmocka_unit_test(test_one_camera_dark_keeps_tracking_with_the_others),
        cmocka_unit_test(test_all_cameras_dark_reports_lost_then_recovers),
        cmocka_unit_test(test_nan_pixels_are_skipped),
        cmocka_unit_test(test_malformed_frameset_is_rejected_without_damage),
        cmocka_unit_test(test_thirty_percent_gross_outliers_everywhere),
        cmocka_unit_test(test_a_moving_group_of_tracks_is_dropped_and_retired),
        cmocka_unit_test(test_bad_configuration_is_refused),
    };
    return cmocka_run_group_tests_name("vo_gc", tests, NULL, NULL);
}
