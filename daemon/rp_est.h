/*
 * rp_est.h - the daemon's estimator for sources that deliver features (the sim source): the
 * configured method (rp_config_t.method) behind one init / step pair, over the core's
 * estimators. Sources that deliver images go through the core's image pipeline (rp_pipe.h)
 * instead, which runs the same estimators behind its trackers.
 */
#ifndef RP_EST_H
#define RP_EST_H

#include "rigpose/rp_config.h"
#include "rigpose/rp_frame.h"
#include "rigpose/rp_rc.h"
#include "rigpose/rp_vo_gc.h"
#include "rigpose/rp_vo_mono.h"
#include "rigpose/rp_vo_stereo.h"

typedef struct {
    rp_method_t method;
    const rp_rig_t *rig;
    union {
        rp_vo_stereo_t stereo;
        rp_vo_gc_t gc;
        struct {
            rp_vo_mono_t mono[RP_RC_MAX_CAMS]; /* camK: mono[0]; rc: the four cameras */
            uint8_t cams[RP_RC_MAX_CAMS];
            uint8_t n;
            rp_rc_params_t prm;
            rp_real last_scale;                /* rc: last accepted S_j */
        } single;
    } u;
} rp_est_t;

/* Set up est for cfg's method on cfg's rig (cfg must outlive est). The core's init status:
 * RP_E_ARG for a method / camera choice the estimator refuses, rp_rig_check's errors. */
rp_status_t rp_est_init(rp_est_t *est, const rp_config_t *cfg);

/* One frame set; out is always filled. The estimator's step status (rp_vo_*_step). For rc the
 * reference camera's step status; the fusion's degeneracy shows as RP_EST_SCALE_WEAK. */
rp_status_t rp_est_step(rp_est_t *est, const rp_frameset_t *fs, rp_estimate_t *out);

#endif /* RP_EST_H */
