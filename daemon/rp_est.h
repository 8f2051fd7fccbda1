/*
 * rp_est.h - the daemon's estimator: the core's image pipeline (rp_pipe.h) set up from the
 * configuration file. Sources that deliver images (v4l2, replay) go through its trackers and
 * stereo matcher (rp_est_step_images); the sim source delivers features and goes straight to
 * the same layout's estimator (rp_est_step). One estimator dispatch for both: rp_pipe's.
 *
 * Threads (issue 17): a fixed pool (rp_pool.h) of cfg->threads threads, the caller's included,
 * started by rp_est_init. Each camera's tracker of a set is one job of the pool (rp_pipe_track);
 * the job that finishes the second tracker of a stereo pair then matches the pair
 * (rp_pipe_match_pair) in the same job, while the other trackers still run; the estimator then
 * runs on the caller's thread. rp_est_hal_jobs lends the
 * same pool to the HAL (rp_hal_cfg_t.run_jobs), so each camera's image is decoded in a job too.
 * The poses do not depend on the number of threads (rp_pipe.h: a tracker touches only its own
 * camera's state; the estimator's input is the same frame set in the same order).
 */
#ifndef RP_EST_H
#define RP_EST_H

#include <pthread.h>

#include "rigpose/rp_config.h"
#include "rigpose/rp_frame.h"
#include "rigpose/rp_pipe.h"
#include "rigpose/rp_pool.h"

typedef struct {
    rp_pipe_t pipe; /* 7.2-8.6 MB at the default limits: keep an rp_est_t static */
    rp_pool_t pool;
    const rp_image_t *const *images; /* the set being tracked (read by the jobs) */
    uint8_t order[RP_PIPE_MAX_TRACKERS]; /* trackers in the order their jobs go out */
    uint8_t n_images;
    /* The set's stereo pairs (rp_pipe_pair_trackers): each tracker's pair (-1: none) and how
     * many of each pair's two trackers are still to run (guarded by mu). */
    int8_t trk_pair[RP_PIPE_MAX_TRACKERS];
    uint8_t pair_left[RP_MAX_PAIRS];
    pthread_mutex_t mu;
    uint8_t mu_ok;
} rp_est_t;

/* Threads rp_est_init starts for cfg: cfg->threads, or for 0 the online cores, at most one
 * per tracker of the layout (never more than RP_POOL_MAX_THREADS, at least 1), and 1 for the
 * sim and lcm sources (their sets carry features: no tracker runs). */
unsigned rp_est_threads_for(const rp_config_t *cfg, unsigned online_cores);

/* Set up est on cfg's rig with cfg->pipe, unchanged (layout, cameras, tracker and estimator
 * settings), and start its threads (rp_est_threads_for). rp_pipe_init's status: RP_E_ARG for a
 * method / camera choice the estimator refuses, rp_rig_check's errors; RP_E_FULL: the system
 * refused a thread. est must be zeroed (static) or closed. */
rp_status_t rp_est_init(rp_est_t *est, const rp_config_t *cfg);

/* Stops est's threads (NULL: nothing). */
void rp_est_close(rp_est_t *est);

/* Threads est runs (1 before rp_est_init or after rp_est_close). */
unsigned rp_est_threads(const rp_est_t *est);

/* rp_hal_jobs_fn_t over est's pool (ctx: the rp_est_t): runs the HAL's per-camera jobs on the
 * same threads. 0, or -1 for a NULL ctx or fn, or a pool not started (the HAL then runs them
 * itself). */
int rp_est_hal_jobs(void *ctx, unsigned n_jobs, void (*fn)(void *arg, unsigned job), void *arg);

/* One frame set of features (sim source); out is always filled. rp_pipe_step_feats's status:
 * the estimator's step status; for rc the reference camera's, the fusion's degeneracy shows as
 * RP_EST_SCALE_WEAK; RP_E_RANGE for a frame set not after the previous one. */
rp_status_t rp_est_step(rp_est_t *est, const rp_frameset_t *fs, rp_estimate_t *out);

/* One set of images (n cameras, NULL for a missing one) through trackers (one job per camera),
 * matcher and estimator; fs_out (optional) receives the features the estimator used, or NULL.
 * utime is the set's time; cam_utime[k] (NULL: every camera at utime) camera k's own capture
 * time (the HAL's rp_hal_frame_t.utime: v4l2's kernel stamp, replay's recorded time), which the
 * frame set carries as cam_dt_us (rp_pipe_step_timed; a missing camera's entry is not read and
 * the frame set flags it RP_FS_NO_IMAGE). rp_pipe_step_timed's status. */
rp_status_t rp_est_step_images(rp_est_t *est, const rp_image_t *const images[],
                               const int64_t cam_utime[], uint8_t n, int64_t utime,
                               rp_estimate_t *out, const rp_frameset_t **fs_out);

#endif /* RP_EST_H */
