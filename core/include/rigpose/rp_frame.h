/*
 * rp_frame.h - what flows between the front end and the estimators: a frame set of tracked
 * features from all cameras, and a pose estimate with its health flags.
 */
#ifndef RP_FRAME_H
#define RP_FRAME_H

#include "rp_opts.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One tracked feature in one camera. Ids are unique across the rig: a feature matched between
 * the two cameras of a stereo pair carries the same id in both. A track that is lost and found
 * again gets a new id from the front end. */
typedef struct {
    uint32_t id;   /* track id */
    rp_real uv[2]; /* pixel position (u, v), distorted (as seen in the image), pixels */
} rp_feat_t;

/* rp_frameset_t.cam_flags bits */
enum {
    RP_FS_NO_IMAGE = 1u << 0 /* the camera delivered no image for this set (its n is 0); a
                              * camera with an image but no features has n = 0 without it */
};

/* The features of all cameras for one frame set. Camera k's features are f[k][0 .. n[k]-1].
 * The set's time is utime; camera k captured its image at utime + cam_dt_us[k] (its own clock
 * stamp: free-running cameras are not simultaneous). Estimators apply camera k's features at
 * that time (rp_obs_t.dt), plus the camera's estimated clock offset when they estimate one.
 * All-zero cam_dt_us and cam_flags (what rp_frameset_reset and a zeroed struct give) is a
 * synchronised set in which every camera delivered an image. */
typedef struct {
    int64_t utime;                   /* time of the set, microseconds */
    uint16_t n[RP_MAX_CAMS];         /* features per camera */
    int32_t cam_dt_us[RP_MAX_CAMS];  /* camera k's capture time minus utime, microseconds */
    uint8_t cam_flags[RP_MAX_CAMS];  /* RP_FS_* of camera k */
    rp_feat_t f[RP_MAX_CAMS][RP_MAX_FEATS_PER_CAM];
} rp_frameset_t;

/* Start filling fs for a set at utime: no features, every camera synchronised and present. */
static inline void rp_frameset_reset(rp_frameset_t *fs, int64_t utime)
{
    fs->utime = utime;
    for (int k = 0; k < RP_MAX_CAMS; ++k) {
        fs->n[k] = 0;
        fs->cam_dt_us[k] = 0;
        fs->cam_flags[k] = 0;
    }
}

/* Estimator health and events, as flags (published as they are). */
enum {
    RP_EST_INITIALISING = 1u << 0, /* first frame: structure built, pose is the prior */
    RP_EST_TRACKING     = 1u << 1, /* pose updated from tracked features this frame */
    RP_EST_REINIT       = 1u << 2, /* landmarks re-initialised this frame (backtracked one frame) */
    RP_EST_DEGRADED     = 1u << 3, /* fewer features than wanted, or some cameras without any */
    RP_EST_LOST         = 1u << 4, /* no update possible: pose is the prediction only */
    RP_EST_GATED        = 1u << 5, /* some measurements rejected as outliers (Mahalanobis gate) */
    RP_EST_COV_RESET    = 1u << 6, /* numerical fault: the covariance was reset */
    RP_EST_SCALE_WEAK   = 1u << 7, /* metric scale poorly determined (non-overlapping layouts) */
    RP_EST_HELD         = 1u << 8, /* no update for longer than the filter's max_predict_s: the
                                    * pose is held, not extrapolated, its covariance growing
                                    * (rp_ekf_predict); always with LOST */
    RP_EST_UNSYNCED     = 1u << 9, /* a stereo pair's two images were farther apart in time than
                                    * the layout allows (max_pair_skew_s): no new landmarks from
                                    * it this time */
    RP_EST_CLOCK_JUMP   = 1u << 10 /* a camera's clock jumped: its offset state restarted
                                    * (rp_ekf_info_t.toff_reset) */
};

typedef struct {
    int64_t utime;              /* time of the frame set, microseconds */
    uint32_t frame;             /* frame index since start */
    rp_real p[6];               /* pose [tx ty tz alpha beta gamma] of cam1 in the world, m, rad */
    rp_real v[6];               /* velocity of cam1 (m/s, world frame), then its angular
                                 * rate omega (rad/s, world frame: R' = [omega]x R), not the
                                 * angles' derivatives */
    rp_real cov[36];            /* 6x6 covariance of p, row-major, in rp_rig.h's pose chart:
                                 * translation (m), then the world-frame rotation vector w of
                                 * R = Exp(w) R(p) (rad); not of the angles, which are singular
                                 * at beta = +-pi/2 */
    uint32_t flags;             /* RP_EST_* */
    uint16_t n_used[RP_MAX_CAMS]; /* features used in the update, per camera */
    uint16_t n_gated;           /* measurements rejected by the gate */
    uint16_t n_landmarks;       /* 3-D points held */
} rp_estimate_t;

#ifdef __cplusplus
}
#endif

#endif /* RP_FRAME_H */
