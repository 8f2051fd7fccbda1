/*
 * test_simclock.c - the simulation's smooth motion and camera clocks (rp_sim.h,
 * RP_SIM_MOTION_SMOOTH, cam_offset_s / cam_phase_s / cam_fps / jitter_s): the smooth motion's
 * peaks are about 0.5 m/s and 1 rad/s and the rig stays inside the shell; a camera's features
 * are the exact projection of the true pose at its own capture time (stamp + offset), with the
 * set's truth at the set's time; cameras at 30 / 25 / 15 Hz put every frame in exactly one set
 * and flag RP_FS_NO_IMAGE otherwise; jitter is Gaussian, not in the stamps, deterministic per
 * (seed, run); with the clocks at their defaults the frame sets are those of the synchronised
 * simulation before the clocks existed (digests recorded from commit a385b8e).
 */
#include "rp_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rigpose/rp_rot.h"
#include "rp_sim.h"

#define PI 3.14159265358979323846

static rp_frameset_t *new_frameset(void)
{
    rp_frameset_t *fs = calloc(1, sizeof *fs);
    assert_non_null(fs);
    return fs;
}

static void smooth_cfg(rp_sim_cfg_t *cfg, uint32_t frames)
{
    rp_sim_default_cfg(cfg);
    cfg->motion = RP_SIM_MOTION_SMOOTH;
    cfg->n_frames = frames;
}

/* World angular rate (rad/s) of R(t) by a central difference: [w]x = R' R^T. */
static void angular_rate(const rp_sim_run_t *sr, double t, double h, double w[3])
{
    double d0[3], d1[3], R0[9], R1[9], R[9];
    assert_int_equal(rp_sim_pose(sr, t - h, d0, R0), 0);
    assert_int_equal(rp_sim_pose(sr, t + h, d1, R1), 0);
    assert_int_equal(rp_sim_pose(sr, t, d0, R), 0);
    double W[9]; /* (R1 - R0) / 2h R^T */
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            double s = 0.0;
            for (int m = 0; m < 3; ++m) {
                s += (R1[3 * i + m] - R0[3 * i + m]) / (2.0 * h) * R[3 * j + m];
            }
            W[3 * i + j] = s;
        }
    }
    w[0] = 0.5 * (W[7] - W[5]);
    w[1] = 0.5 * (W[2] - W[6]);
    w[2] = 0.5 * (W[3] - W[1]);
}

static void smooth_motion_peaks_and_stays_in_the_shell(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    smooth_cfg(&cfg, 300);
    const double rig_reach = 0.1 * sqrt(2.0); /* farthest camera from cam1 (cam3b), m */
    double v_lo = 1e9, v_hi = 0.0, w_lo = 1e9, w_hi = 0.0, far = 0.0, beta = 0.0;
    for (uint64_t seed = 1; seed <= 8; ++seed) {
        rp_sim_run_t sr, again;
        assert_int_equal(rp_sim_run_init(&sr, &cfg, seed, 0), 0);
        assert_int_equal(rp_sim_run_init(&again, &cfg, seed, 0), 0);
        assert_memory_equal(sr.truth, again.truth, 6u * cfg.n_frames * sizeof(double));
        /* Set 0 is the identity. */
        for (int i = 0; i < 6; ++i) {
            assert_near(sr.truth[i], 0.0, 1e-15);
        }
        double v_max = 0.0, w_max = 0.0;
        const double h = 1e-5; /* s */
        for (uint32_t j = 0; j < 3u * cfg.n_frames; ++j) {
            const double t = j * cfg.frame_dt / 3.0; /* three samples a frame */
            double dm[3], dp[3], R[9], w[3];
            assert_int_equal(rp_sim_pose(&sr, t - h, dm, R), 0);
            assert_int_equal(rp_sim_pose(&sr, t + h, dp, R), 0);
            const double v = sqrt((dp[0] - dm[0]) * (dp[0] - dm[0]) +
                                  (dp[1] - dm[1]) * (dp[1] - dm[1]) +
                                  (dp[2] - dm[2]) * (dp[2] - dm[2])) / (2.0 * h);
            angular_rate(&sr, t, h, w);
            v_max = fmax(v_max, v);
            w_max = fmax(w_max, sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]));
        }
        for (uint32_t j = 0; j < cfg.n_frames; ++j) {
            const double *p = &sr.truth[6u * j];
            far = fmax(far, sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) + rig_reach);
            beta = fmax(beta, fabs(p[4]));
            /* The truth is the continuous pose at the set's time. */
            double d[3], R[9];
            assert_int_equal(rp_sim_pose(&sr, rp_sim_set_time(&sr, j), d, R), 0);
            assert_memory_equal(R, &sr.truth_R[9u * j], sizeof R);
        }
        /* Within the analytic bounds (rp_sim.h): per axis 0.4 m/s, per angle 0.8 rad/s. */
        assert_true(v_max <= 0.4 * sqrt(3.0));
        v_lo = fmin(v_lo, v_max);
        v_hi = fmax(v_hi, v_max);
        w_lo = fmin(w_lo, w_max);
        w_hi = fmax(w_hi, w_max);
        rp_sim_run_free(&sr);
        rp_sim_run_free(&again);
    }
    print_message("smooth, seeds 1-8, 300 frames: peak speed %.3f..%.3f m/s, peak rate %.3f..%.3f "
                  "rad/s, farthest camera %.3f m from the start, |beta| <= %.3f rad\n",
                  v_lo, v_hi, w_lo, w_hi, far, beta);
    /* "About 0.5 m/s and 1 rad/s" */
    assert_true(v_lo > 0.35 && v_hi < 0.65);
    assert_true(w_lo > 0.7 && w_hi < 1.3);
    /* Inside the shell with margin: every camera at least 0.2 m inside r_in. */
    assert_true(far < cfg.r_in - 0.2);
    assert_true(beta < 1.1);
}

/* Noise-free pixel of world point M in rig camera k at pose (d, R) (eq. 2), in double; 0 if
 * behind. */
static int project(const rp_sim_run_t *sr, int k, const double d[3], const double R[9],
                   const double M[3], double uv[2])
{
    const rp_rig_cam_t *rc = &sr->rig.cam[k];
    double c[3], q[3], P[3];
    for (int i = 0; i < 3; ++i) {
        c[i] = d[i];
        for (int m = 0; m < 3; ++m) {
            c[i] += R[3 * i + m] * (double)rc->D[m];
        }
    }
    for (int i = 0; i < 3; ++i) {
        q[i] = 0.0;
        for (int m = 0; m < 3; ++m) {
            q[i] += R[3 * m + i] * (M[m] - c[m]); /* R^T (M - c) */
        }
    }
    for (int i = 0; i < 3; ++i) {
        P[i] = 0.0;
        for (int m = 0; m < 3; ++m) {
            P[i] += (double)rc->R[3 * m + i] * q[m]; /* R_k^T */
        }
    }
    if (P[2] <= 0.0) {
        return 0;
    }
    uv[0] = (double)rc->cam.fx * P[0] / P[2] + (double)rc->cam.cx;
    uv[1] = (double)rc->cam.fy * P[1] / P[2] + (double)rc->cam.cy;
    return 1;
}

static void features_are_the_truth_at_the_cameras_own_time(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    smooth_cfg(&cfg, 40);
    cfg.noise_px = 0.0;
    static const double off[RP_SIM_NCAMS] = {0.0, 0.012, -0.025, 0.040, 0.007, -0.003};
    memcpy(cfg.cam_offset_s, off, sizeof off);
    rp_sim_run_t sr;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 5, 2), 0);
    rp_frameset_t *fs = new_frameset();
    double moved = 0.0; /* largest pixel distance from the projection at the set's time */
    for (uint32_t j = 10; j < 40; j += 7) {
        (void)rp_sim_frame(&sr, j, fs);
        /* The stamps are the set's: offsets are not in them. */
        assert_int_equal(fs->utime, (int64_t)llround(j * cfg.frame_dt * 1e6));
        double d_set[3], R_set[9];
        assert_int_equal(rp_sim_pose(&sr, j * cfg.frame_dt, d_set, R_set), 0);
        assert_memory_equal(R_set, &sr.truth_R[9u * j], sizeof R_set);
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            assert_int_equal(fs->cam_dt_us[k], 0);
            assert_int_equal(fs->cam_flags[k], 0);
            assert_true(fs->n[k] > 50);
            double d[3], R[9];
            assert_int_equal(rp_sim_pose(&sr, j * cfg.frame_dt + off[k], d, R), 0);
            for (int i = 0; i < fs->n[k]; ++i) {
                const double *M = &sr.points[3u * fs->f[k][i].id];
                double uv[2], uv_set[2];
                assert_true(project(&sr, k, d, R, M, uv));
                assert_near((double)fs->f[k][i].uv[0], uv[0], RP_TOL(1e-9, 1e-3));
                assert_near((double)fs->f[k][i].uv[1], uv[1], RP_TOL(1e-9, 1e-3));
                if (project(&sr, k, d_set, R_set, M, uv_set)) {
                    moved = fmax(moved, hypot(uv[0] - uv_set[0], uv[1] - uv_set[1]));
                }
            }
        }
    }
    /* 40 ms at up to 1 rad/s and 800 px: pixels, not rounding. */
    assert_true(moved > 5.0);
    free(fs);
    rp_sim_run_free(&sr);
}

static void every_frame_of_30_25_15_hz_cameras_is_in_exactly_one_set(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    smooth_cfg(&cfg, 300);
    static const double fps[RP_SIM_NCAMS] = {30, 25, 15, 30, 25, 15};
    static const double phase[RP_SIM_NCAMS] = {0, 0.004, 0.021, 0.010, 0, 0.0666};
    memcpy(cfg.cam_fps, fps, sizeof fps);
    memcpy(cfg.cam_phase_s, phase, sizeof phase);
    cfg.cam_offset_s[1] = 0.012;
    cfg.jitter_s = 0.001;
    rp_sim_run_t sr;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), 0);
    rp_frameset_t *fs = new_frameset();
    int64_t next[RP_SIM_NCAMS] = {0}; /* each camera's next frame, in order */
    int64_t prev_utime = INT64_MIN;
    const int64_t last = rp_sim_set_utime(&sr, cfg.n_frames - 1);
    for (uint32_t j = 0; j < cfg.n_frames; ++j) {
        (void)rp_sim_frame(&sr, j, fs);
        /* Sets at the fastest camera's rate: cam1's stamps (phase 0, 30 Hz). */
        assert_int_equal(fs->utime, (int64_t)llround(j / 30.0 * 1e6));
        assert_true(fs->utime > prev_utime);
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            rp_sim_cam_frame_t cf;
            rp_sim_cam_frame(&sr, j, k, &cf);
            const int64_t stamp = (int64_t)llround(phase[k] * 1e6) +
                                  (int64_t)llround((double)next[k] / fps[k] * 1e6);
            if (stamp <= fs->utime) {
                /* The camera's next frame is due: it is in this set, with its stamp. */
                assert_true(cf.present);
                assert_int_equal(cf.index, next[k]);
                assert_int_equal(cf.stamp_us, stamp);
                assert_int_equal(fs->cam_flags[k], 0);
                assert_int_equal(fs->utime + fs->cam_dt_us[k], stamp);
                assert_true(fs->cam_dt_us[k] <= 0 && stamp > prev_utime);
                assert_true(fs->n[k] > 0);
                ++next[k];
            } else {
                assert_false(cf.present);
                assert_int_equal(fs->cam_flags[k], RP_FS_NO_IMAGE);
                assert_int_equal(fs->n[k], 0);
                assert_int_equal(fs->cam_dt_us[k], 0);
            }
        }
        prev_utime = fs->utime;
    }
    /* Every frame stamped up to the last set was delivered: as many as the rate says. */
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        const double span = (double)last * 1e-6 - phase[k];
        assert_int_equal(next[k], (int64_t)floor(span * fps[k] + 1e-9) + 1);
    }
    assert_int_equal(next[0], 300);
    assert_int_equal(next[1], 250); /* 25 Hz over 299 / 30 s from 4 ms: frames 0..249 */
    free(fs);
    rp_sim_run_free(&sr);
}

static void jitter_is_gaussian_unstamped_and_deterministic(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    smooth_cfg(&cfg, 2000);
    cfg.jitter_s = 0.002;
    cfg.cam_offset_s[2] = -0.025;
    rp_sim_run_t sr, again;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 3, 1), 0);
    assert_int_equal(rp_sim_run_init(&again, &cfg, 3, 1), 0);
    double s = 0.0, s2 = 0.0;
    for (uint32_t j = 0; j < cfg.n_frames; ++j) {
        rp_sim_cam_frame_t cf, cf2;
        rp_sim_cam_frame(&sr, j, 2, &cf);
        rp_sim_cam_frame(&again, j, 2, &cf2);
        assert_true(cf.present);
        assert_int_equal(cf.stamp_us, rp_sim_set_utime(&sr, j)); /* not in the stamp */
        assert_true(cf.t_true == cf2.t_true);
        const double e = cf.t_true - (j * cfg.frame_dt - 0.025);
        s += e;
        s2 += e * e;
    }
    const double n = cfg.n_frames, mean = s / n, sd = sqrt(s2 / n - mean * mean);
    assert_near(mean, 0.0, 4.0 * 0.002 / sqrt(n));
    assert_near(sd, 0.002, 0.1 * 0.002);
    rp_sim_run_free(&sr);
    rp_sim_run_free(&again);
}

static void impossible_clocks_are_refused(void **state)
{
    (void)state;
    rp_sim_cfg_t cfg;
    rp_sim_run_t sr;
    rp_sim_default_cfg(&cfg);
    cfg.cam_offset_s[1] = 0.01; /* the paper's walk has no pose between frames */
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), -2);
    smooth_cfg(&cfg, 10);
    cfg.cam_fps[1] = 29.999; /* 1.1 us a frame slower than the others: two frames in a set */
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), -2);
    cfg.cam_fps[1] = 29.9; /* 111 us slower: fine */
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), 0);
    rp_sim_run_free(&sr);
    cfg.cam_fps[1] = -1.0;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), -2);
    cfg.cam_fps[1] = 0.5; /* a 2 s frame would not fit cam_dt_us */
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), -2);
    cfg.cam_fps[1] = 0.0;
    cfg.jitter_s = -0.001;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, 0), -2);
}

/* Digest of frame sets 0..11 of runs 0, 1 (seed 1): the integers exactly (utime, counts, ids,
 * per-camera times and flags: an FNV-1a chain), the pixels as sums. */
typedef struct {
    uint64_t h;
    uint64_t n;
    double su, sv;
} digest_t;

static digest_t digest(rp_sim_motion_t motion, uint32_t run)
{
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.motion = motion;
    cfg.n_frames = 12;
    rp_sim_run_t sr;
    assert_int_equal(rp_sim_run_init(&sr, &cfg, 1, run), 0);
    rp_frameset_t *fs = new_frameset();
    digest_t g = {1469598103934665603ull, 0, 0.0, 0.0};
    const uint64_t P = 1099511628211ull;
    for (uint32_t j = 0; j < cfg.n_frames; ++j) {
        (void)rp_sim_frame(&sr, j, fs);
        g.h = (g.h ^ (uint64_t)fs->utime) * P;
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            g.h = (g.h ^ fs->n[k]) * P;
            g.h = (g.h ^ (uint64_t)(fs->cam_dt_us[k] + 7 * fs->cam_flags[k])) * P;
            for (int m = 0; m < fs->n[k]; ++m) {
                g.h = (g.h ^ fs->f[k][m].id) * P;
                g.su += (double)fs->f[k][m].uv[0];
                g.sv += (double)fs->f[k][m].uv[1];
                ++g.n;
            }
        }
    }
    free(fs);
    rp_sim_run_free(&sr);
    return g;
}

static void default_clocks_reproduce_the_synchronised_frame_sets(void **state)
{
    (void)state;
    /* Recorded with the simulation of commit a385b8e (before the clocks), double build. */
    static const struct {
        rp_sim_motion_t motion;
        uint32_t run;
        digest_t g;
    } want[] = {
        {RP_SIM_MOTION_PAPER, 0, {0xf8d9c15fc1eb533aull, 20819, 6486079.1328052068, 4864691.2655965872}},
        {RP_SIM_MOTION_PAPER, 1, {0xa54876c784f96fecull, 21110, 6526740.008587556, 4977653.1116702845}},
        {RP_SIM_MOTION_TURN, 0, {0x189490d1d01357b7ull, 20289, 6358059.7581174728, 4781542.8123714849}},
        {RP_SIM_MOTION_TURN, 1, {0x31ffdc76dd4f13ecull, 20760, 6525276.8953605471, 4907989.0662095863}},
        {RP_SIM_MOTION_PITCH, 0, {0x9daaef37f42566f9ull, 20720, 6446385.4260402741, 4868509.0093389032}},
        {RP_SIM_MOTION_PITCH, 1, {0x4fdb57ca25a9a0c2ull, 20741, 6441254.1677858233, 4815769.282303161}},
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; ++i) {
        const digest_t g = digest(want[i].motion, want[i].run);
        assert_true(g.h == want[i].g.h);
        assert_true(g.n == want[i].g.n);
        /* float builds round each pixel to float (6e-5 px at 640), a sum of 1e5 of them */
        assert_near(g.su, want[i].g.su, RP_TOL(1e-6, 1.0));
        assert_near(g.sv, want[i].g.sv, RP_TOL(1e-6, 1.0));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(smooth_motion_peaks_and_stays_in_the_shell),
        cmocka_unit_test(features_are_the_truth_at_the_cameras_own_time),
        cmocka_unit_test(every_frame_of_30_25_15_hz_cameras_is_in_exactly_one_set),
        cmocka_unit_test(jitter_is_gaussian_unstamped_and_deterministic),
        cmocka_unit_test(impossible_clocks_are_refused),
        cmocka_unit_test(default_clocks_reproduce_the_synchronised_frame_sets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
