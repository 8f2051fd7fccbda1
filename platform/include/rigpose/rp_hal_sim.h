/*
 * rp_hal_sim.h - the HAL's `sim` camera source: the feature-level simulation of the paper's
 * Table 1 protocol (platform/sim/rp_sim.h), so the daemon runs with no hardware.
 *
 * Each grab delivers one frame set of the simulated run: no images (every camera's img.data is
 * NULL), the tracked features of all six cameras in set->feats (set->payload is
 * RP_HAL_PAYLOAD_FEATS; feats->utime is the simulation's time, j / 30 s, which the estimators
 * use for their time steps) and the true pose of cam1 in set->truth (has_truth = 1).
 * set->utime is the capture time on the HAL clock: with cfg.realtime the set is released at
 * start + j / 30 s (sleeping until then), otherwise as soon as it is asked for, stamped when it
 * is made.
 *
 * Beyond rp_hal_cfg_t (kind, sim_seed, sim_frames, realtime, n_cams), rp_hal_sim_opts_t
 * (cfg.sim_opts through rp_hal_open, or the opts of rp_hal_sim_open): the pixel noise and a
 * camera that vanishes from a given frame set on (its features stop: flags MISSING | GONE, its
 * drop count grows by one per set), to exercise the daemon's status reporting.
 *
 * Two ways in, the same source: rp_hal_open with cfg.kind RP_HAL_SRC_SIM (its const table,
 * like v4l2 and replay; the options come in cfg.sim_opts, NULL: defaults; rp_hal_errmsg(src)
 * tells failures), or the typed calls below (rp_hal_sim_errmsg tells failures).
 * One source per process: the state is a static instance (its trajectory and point cloud are
 * allocated once at open, never per frame).
 */
#ifndef RP_HAL_SIM_H
#define RP_HAL_SIM_H

#include <stdint.h>

#include "rigpose/rp_hal.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct rp_hal_sim_opts {
    double noise_px;    /* Gaussian pixel noise (px), >= 0; the protocol's 0.5 */
    int16_t drop_cam;   /* rig camera that vanishes, -1: none */
    uint32_t drop_from; /* first frame set without it */
    int8_t motion;      /* rp_sim_motion_t: 0 the paper's random walk (which leaves the scene
                         * on long runs), 1 the turn on the spot, 2 the pitch, 3 the smooth
                         * wander (all three stay in it for any length: soak runs) */
} rp_hal_sim_opts_t;

/* The protocol's defaults: 0.5 px, no camera dropped, the paper's motion. */
rp_hal_sim_opts_t rp_hal_sim_default_opts(void);

typedef struct rp_hal_sim rp_hal_sim_t;

/* Open the simulation described by cfg (kind must be RP_HAL_SRC_SIM, n_cams 6; sim_frames 0 is
 * the protocol's 100) and opts (NULL: defaults; cfg->sim_opts is not read here). RP_HAL_E_ARG
 * for a bad configuration or a second open while one is open, RP_HAL_E_OPEN if the run could
 * not be allocated. */
rp_hal_status_t rp_hal_sim_open(rp_hal_sim_t **sim, const rp_hal_cfg_t *cfg,
                                const rp_hal_sim_opts_t *opts);
rp_hal_status_t rp_hal_sim_start(rp_hal_sim_t *sim);
/* Next frame set. RP_HAL_E_END after sim_frames sets, RP_HAL_E_STATE before start. */
rp_hal_status_t rp_hal_sim_grab(rp_hal_sim_t *sim, rp_hal_set_t *set);
rp_hal_status_t rp_hal_sim_stop(rp_hal_sim_t *sim);
void rp_hal_sim_close(rp_hal_sim_t *sim);

/* What the last failing rp_hal_sim_open (or call on a sim it opened) found wrong, naming the
 * option or state, e.g. "sim: drop_cam 6 out of -1..5"; "" if none. Never NULL. (A sim opened
 * by rp_hal_open tells its later failures in rp_hal_errmsg(src).) */
const char *rp_hal_sim_errmsg(void);

#ifdef __cplusplus
}
#endif

#endif /* RP_HAL_SIM_H */
