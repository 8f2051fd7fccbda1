/*
 * sim_fixture.h - what the estimator tests (test_vo_stereo.c, test_vo_mono.c, test_vo_gc.c)
 * share: one run of the paper's simulation, a loop that feeds its frame sets to an estimator
 * and scores the estimates against the truth, the usual fault injections, and the malformed
 * frame set check. Each test file wraps its estimator's step in a simfx_step_fn.
 */
#ifndef SIM_FIXTURE_H
#define SIM_FIXTURE_H

#include <stdlib.h>
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_frame.h"
#include "rigpose/rp_rot.h"
#include "rp_sim.h"

typedef struct {
    rp_sim_run_t sr;   /* the run: rig, points, truth */
    rp_frameset_t fs;  /* the frame set last fed */
    rp_estimate_t est; /* the estimate last returned */
} simfx_t;

/* One estimator step on frame set fs (vo: the estimator's state). */
typedef rp_status_t (*simfx_step_fn)(void *vo, const rp_frameset_t *fs, rp_estimate_t *est);
/* Changes frame set j before the estimator sees it (fault injection). */
typedef void (*simfx_mutate_fn)(rp_frameset_t *fs, uint32_t j);
/* Called on every scored frame with its estimate and error e = estimate - truth (angles
 * wrapped), for checks beyond the mean error (covariance consistency). */
typedef void (*simfx_frame_fn)(void *ctx, const rp_estimate_t *est, const double e[6]);

typedef struct {
    double err[6];     /* mean absolute error over frames 1.. of tx..tz (m), alpha..gamma (rad) */
    uint32_t lost;     /* frames whose step did not return RP_OK */
    uint32_t flags_or; /* union of the estimates' flags */
} simfx_score_t;

/* The simulator's configuration of gc (rp_sim_gc_cfg) at noise_px. */
static inline rp_vo_gc_cfg_t simfx_gc_cfg(double noise_px)
{
    rp_sim_cfg_t sim;
    rp_sim_default_cfg(&sim);
    sim.noise_px = noise_px;
    return rp_sim_gc_cfg(&sim);
}

/* A zeroed fixture of `size` bytes whose first member is a simfx_t, with run `run` (seed 11)
 * of the protocol at noise_px pixel noise and `frames` frames. Free with simfx_free. */
static inline void *simfx_new(size_t size, double noise_px, uint32_t frames, uint32_t run)
{
    simfx_t *fx = calloc(1, size);
    assert_non_null(fx);
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.noise_px = noise_px;
    cfg.n_frames = frames;
    assert_int_equal(rp_sim_run_init(&fx->sr, &cfg, 11, run), 0);
    return fx;
}

static inline void simfx_free(void *p)
{
    simfx_t *fx = p;
    rp_sim_run_free(&fx->sr);
    free(fx);
}

/* Feed frames 0..frames-1 to step (on estimator vo), mutated by mutate if given; every
 * estimate must be finite and frame 0 must report RP_EST_INITIALISING. */
static inline void simfx_run(simfx_t *fx, simfx_step_fn step, void *vo, uint32_t frames,
                             simfx_mutate_fn mutate, simfx_frame_fn on_frame, void *ctx,
                             simfx_score_t *out)
{
    memset(out, 0, sizeof(*out));
    for (uint32_t j = 0; j < frames; ++j) {
        rp_sim_frame(&fx->sr, j, &fx->fs);
        if (mutate) mutate(&fx->fs, j);
        rp_status_t st = step(vo, &fx->fs, &fx->est);
        if (st != RP_OK) out->lost++;
        out->flags_or |= fx->est.flags;
        for (int i = 0; i < 6; ++i) assert_true(isfinite((double)fx->est.p[i]));
        if (j == 0) {
            assert_true(fx->est.flags & RP_EST_INITIALISING);
            continue;
        }
        double e[6];
        for (int i = 0; i < 6; ++i) {
            double d = (double)fx->est.p[i] - fx->sr.truth[j * 6 + i];
            if (i >= 3) d = (double)rp_angle_wrap((rp_real)d);
            e[i] = d;
            out->err[i] += fabs(d) / (double)(frames - 1);
        }
        if (on_frame) on_frame(ctx, &fx->est, e);
    }
}

/* |estimate - truth| of the last frame's position is under tol in every axis. */
static inline void simfx_assert_last_position_near(const simfx_t *fx, uint32_t j, double tol)
{
    for (int i = 0; i < 3; ++i) {
        assert_true(fabs((double)fx->est.p[i] - fx->sr.truth[j * 6 + i]) < tol);
    }
}

static inline void simfx_print_err(const char *label, const double err[6])
{
    print_message("%s: tx %.2e ty %.2e tz %.2e a %.2e b %.2e g %.2e\n", label, err[0], err[1],
                  err[2], err[3], err[4], err[5]);
}

/* Every camera dark (no features) for frames 10-12. */
static inline void simfx_all_dark_10_12(rp_frameset_t *fs, uint32_t j)
{
    if (j >= 10 && j <= 12) memset(fs->n, 0, sizeof(fs->n));
}

/* Every third frame, cam1's first five features get a NaN pixel. */
static inline void simfx_nan_pixels_cam1(rp_frameset_t *fs, uint32_t j)
{
    if (j % 3 == 1) {
        for (uint16_t i = 0; i < fs->n[RP_SIM_CAM1] && i < 5; ++i) {
            fs->f[RP_SIM_CAM1][i].uv[0] = (rp_real)NAN;
        }
    }
}

/* A frame set with a count over the limit (in camera `cam`) and a NULL frame set are refused
 * with RP_E_ARG and a LOST estimate, and the estimator then tracks the next good frame set. The
 * estimator must be freshly initialised on fx's rig. */
static inline void simfx_check_malformed(simfx_t *fx, simfx_step_fn step, void *vo, uint8_t cam)
{
    rp_sim_frame(&fx->sr, 0, &fx->fs);
    assert_ok(step(vo, &fx->fs, &fx->est));
    rp_sim_frame(&fx->sr, 1, &fx->fs);
    fx->fs.n[cam] = RP_MAX_FEATS_PER_CAM + 1;
    assert_status(step(vo, &fx->fs, &fx->est), RP_E_ARG);
    assert_true(fx->est.flags & RP_EST_LOST);
    assert_status(step(vo, NULL, &fx->est), RP_E_ARG);
    rp_sim_frame(&fx->sr, 1, &fx->fs);
    assert_ok(step(vo, &fx->fs, &fx->est));
    assert_true(fx->est.flags & RP_EST_TRACKING);
}

#endif /* SIM_FIXTURE_H */
