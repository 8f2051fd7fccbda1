/*
 * rp_feats.h - what rigpose-frontend and the daemon's lcm source agree on: each camera's
 * features channel, the cameras of the configured layout, a stereo camera's partner, and the
 * checks of a rigpose.features_t that came over the network.
 *
 * The front ends and the estimator read the same configuration file (they differ only in
 * source.kind): camera k's features travel on lcm.features_channel + "k" (decimal), e.g.
 * RIGPOSE_FEATURES_CAM0.
 */
#ifndef RP_FEATS_H
#define RP_FEATS_H

#include <stddef.h>
#include <stdint.h>

#include "rigpose/rp_pipe.h"
#include "rigpose_features_t.h"

/* The channel of camera cam: prefix + decimal index into out (cap bytes). 0, or -1 if it does
 * not fit. */
int rp_feats_channel(const char *prefix, uint8_t cam, char *out, size_t cap);

/* want[k] = 1 for each rig camera k (< n_cams) whose features the layout of cfg uses (its
 * trackers: rp_pipe.h), else 0. Returns how many. */
uint8_t rp_feats_layout_cams(const rp_pipe_cfg_t *cfg, uint8_t n_cams, uint8_t want[RP_MAX_CAMS]);

/* The other camera of cam's stereo pair in cfg (stereo layouts), or -1. */
int rp_feats_partner(const rp_pipe_cfg_t *cfg, uint8_t cam);

/* 0 if m can go into a frame set of a rig of n_cams cameras as camera cam (the channel's): its
 * cam is cam, 0 <= n <= RP_MAX_FEATS_PER_CAM, every used position finite; else -1 and why in
 * why (a static string). */
int rp_feats_check(const rigpose_features_t *m, uint8_t cam, uint8_t n_cams, const char **why);

/* Exit codes of both programs (daemon/README.md); a front end never writes --stats-json. */
enum {
    EXIT_DONE = 0,
    EXIT_USAGE = 1,
    EXIT_CONFIG = 2,
    EXIT_LCM = 3,
    EXIT_SOURCE = 4,
    EXIT_ESTIMATOR = 5,    /* the estimator (or a front end's pipeline) refused the configuration */
    EXIT_SOURCE_FAILED = 6,
    EXIT_STATS = 7
};

/* What both programs do at start: their instance name (pose_t / features_t .instance) into
 * out, NUL-padded: configured if not empty (cut at 31 characters), else HOST:PID (a restarted
 * process is a new instance); and the stop signals SIGINT, SIGTERM, SIGHUP (a closed terminal)
 * and SIGPIPE (stdout piped into a reader that quit) sent to handler, so that each ends with
 * its summary instead of dying. */
void rp_feats_instance(const char *configured, int8_t out[32]);
void rp_feats_stop_signals(void (*handler)(int));

#endif /* RP_FEATS_H */
