/*
 * rp_est.h - the daemon's estimator: the core's image pipeline (rp_pipe.h) set up from the
 * configuration file. Sources that deliver images (v4l2, replay) go through its trackers and
 * stereo matcher (rp_est_step_images); the sim source delivers features and goes straight to
 * the same layout's estimator (rp_est_step). One estimator dispatch for both: rp_pipe's.
 */
#ifndef RP_EST_H
#define RP_EST_H

#include "rigpose/rp_config.h"
#include "rigpose/rp_frame.h"
#include "rigpose/rp_pipe.h"

typedef struct {
    rp_pipe_t pipe; /* 4.1-4.4 MB at the default limits: keep an rp_est_t static */
} rp_est_t;

/* Set up est on cfg's rig with cfg->pipe, unchanged (layout, cameras, tracker and estimator
 * settings). rp_pipe_init's status: RP_E_ARG for a method / camera choice the estimator refuses,
 * rp_rig_check's errors. */
rp_status_t rp_est_init(rp_est_t *est, const rp_config_t *cfg);

/* One frame set of features (sim source); out is always filled. rp_pipe_step_feats's status:
 * the estimator's step status; for rc the reference camera's, the fusion's degeneracy shows as
 * RP_EST_SCALE_WEAK; RP_E_RANGE for a frame set not after the previous one. */
rp_status_t rp_est_step(rp_est_t *est, const rp_frameset_t *fs, rp_estimate_t *out);

/* One set of images (n cameras, NULL for a missing one) through trackers, matcher and
 * estimator; fs_out (optional) receives the features the estimator used, or NULL.
 * rp_pipe_step's status. */
rp_status_t rp_est_step_images(rp_est_t *est, const rp_image_t *const images[], uint8_t n,
                               int64_t utime, rp_estimate_t *out, const rp_frameset_t **fs_out);

#endif /* RP_EST_H */
