/*
 * rp_pipe.h - the image pipeline of the core: grey images of all cameras of a frame set in, one
 * pose estimate out.
 *
 *   images (8-bit grey, one per rig camera) -> a tracker per camera of the layout (rp_track)
 *     -> stereo matching of each pair's new features (rp_smatch, stereo layouts only)
 *     -> rp_frameset_t -> the layout's estimator (rp_vo_stereo | rp_vo_gc | rp_vo_mono + rp_rc)
 *     -> rp_estimate_t (pose of cam1 in the world, rp_frame.h)
 *
 * Layouts (names as in rigpose-sim and the configuration file):
 *   stereo4  two stereo pairs (cfg.stereo.pair_a/pair_b, n_pairs = 2), one pose EKF
 *   stereo2  one stereo pair (n_pairs = 1)
 *   gc       single cameras (cfg.gc.cams), rigpose's generalised-camera EKF
 *   cam1..cam4  one single camera alone (cfg.mono.cam), pose mapped to the rig frame
 *   rc       single cameras (cfg.rc_cams, cfg.rc_n of them: 2..4, the paper's four by
 *            default) fused by the paper's rigidity constraints
 *
 * Stereo pairs and feature ids. The first camera of a pair ("left", a) runs a full tracker
 * (detection, tracking, top-up). The second ("right", b) never detects: it only tracks the
 * features it was given by the matcher, which keep the left feature's id. Whenever the left
 * tracker creates features (the first frame, every top-up), the new ones are matched into the
 * right image of the same frame set (rp_smatch) and the matches are handed to the right
 * tracker; a new left feature without a match is dropped from the left tracker at once (it
 * would give the estimator nothing and hold its cell against the next top-up). So at every
 * frame set the two cameras of a pair share the ids of every feature that was matched at its
 * birth and is still tracked in both; the stereo estimator triangulates
 * these whenever it (re-)initialises (its backtracking uses the previous frame set, which
 * carries them too) and, with add_landmarks, every frame set those not yet landmarks
 * (rp_vo_stereo.h, step 5). Matching costs only at births, not every frame.
 *
 * Top-ups take turns. Of the trackers that detect (all but the pairs' second cameras), one per
 * frame set may top up: the d-th of n_det on the frame sets whose number (rp_pipe_info_t.frame)
 * is d modulo n_det, fixed at rp_pipe_begin, so the turns do not depend on how the trackers are
 * scheduled. A tracker under its threshold waits at most n_det - 1 frame sets (n_det more for
 * each of its turns without an image); one with no track left (the first frame set, every
 * track lost) detects at once. Detection and the matching of the new features are the frame
 * set's rare, large costs: taking turns keeps them from landing on the same frame set.
 *
 * Memory: rp_pipe_t holds RP_PIPE_MAX_TRACKERS trackers (each two pyramids, row rings and a
 * patch cache at the tracker's size limits: sizeof(rp_tracker_t) is 1.40 MB at the default
 * 640x480, 0.50 MB of it the cache, RP_TRACK_PATCH_CACHE_BYTES), each stereo pair's matcher and
 * scratch, and the estimator: 8.6 MB in all with double rp_real, 7.2 MB with float (sizeof at
 * the default limits). Allocate it statically
 * (`static rp_pipe_t pipe;`).
 *
 * Feature-level input: rp_pipe_step_feats runs the layout's estimator on a frame set built
 * elsewhere (a simulator, another tracker, a log), so a program with both kinds of source
 * keeps one estimator dispatch.
 */
#ifndef RP_PIPE_H
#define RP_PIPE_H

#include "rp_frame.h"
#include "rp_opts.h"
#include "rp_rc.h"
#include "rp_rig.h"
#include "rp_smatch.h"
#include "rp_status.h"
#include "rp_stereo.h"
#include "rp_track.h"
#include "rp_vo_gc.h"
#include "rp_vo_mono.h"
#include "rp_vo_stereo.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Trackers one pipeline runs (cameras of the largest layout: stereo4, gc, rc use 4). */
#ifndef RP_PIPE_MAX_TRACKERS
#define RP_PIPE_MAX_TRACKERS 4
#endif
RP_STATIC_ASSERT(RP_PIPE_MAX_TRACKERS >= 2 && RP_PIPE_MAX_TRACKERS <= RP_MAX_CAMS,
                 "RP_PIPE_MAX_TRACKERS: 2..RP_MAX_CAMS");

/* The layouts: the one list of them (the configuration file's estimator.method, the tools'
 * --methods, the daemon). The values are rigpose.pose_t's METHOD_* constants
 * (lcm_types/rigpose_pose_t.lcm), which the daemon checks at compile time; names as
 * rp_pipe_layout_name gives them. */
typedef enum {
    RP_PIPE_STEREO4 = 0,
    RP_PIPE_STEREO2 = 1,
    RP_PIPE_GC = 2,
    RP_PIPE_CAM1 = 3,
    RP_PIPE_CAM2 = 4,
    RP_PIPE_CAM3 = 5,
    RP_PIPE_CAM4 = 6,
    RP_PIPE_RC = 7,
    RP_PIPE_LAYOUT_COUNT_ /* number of layouts; not a layout */
} rp_pipe_layout_t;

typedef struct {
    rp_pipe_layout_t layout;
    rp_track_cfg_t track;     /* tracker settings of every camera (cfg.track.cam is set per
                               * camera by the pipeline) */
    rp_smatch_cfg_t smatch;   /* stereo matching (stereo layouts) */
    rp_vo_stereo_cfg_t stereo; /* stereo2 / stereo4: the estimator and its pairs */
    rp_vo_gc_cfg_t gc;        /* gc: the estimator and its cameras */
    rp_vo_mono_cfg_t mono;    /* cam1..cam4: the estimator and its camera; rc: the settings of
                               * its four single-camera estimators (mono.cam is overridden) */
    uint8_t rc_cams[RP_RC_MAX_CAMS]; /* rc: its cameras, rc_cams[0] the reference (cam1) */
    uint8_t rc_n;             /* rc: how many of rc_cams, 2..RP_RC_MAX_CAMS (default 4) */
    rp_rc_params_t rc;        /* rc: fusion parameters */
    uint8_t dormant_retired;  /* stereo layouts and gc: 1 (default): after each estimate the
                               * tracks the estimator retired go dormant in their pair's first
                               * tracker (gc: their camera's)
                               * (rp_track_set_dormant), so that they no longer fill its
                               * budget; 0: they count as any track. Front ends run as separate
                               * processes (rigpose-frontend) cannot see the estimator's retired
                               * tracks: their rig behaves as 0 */
} rp_pipe_cfg_t;

/* What happened to one camera's image in the last step. */
typedef enum {
    RP_PIPE_CAM_UNUSED = 0,   /* not a camera of the layout */
    RP_PIPE_CAM_OK,           /* tracked; features in the frame set */
    RP_PIPE_CAM_MISSING,      /* no image this time (NULL entry or beyond n): no features; the
                               * tracker keeps its last image and tracks from it next time */
    RP_PIPE_CAM_BLANK,        /* blank image (no contrast): ignored as if missing */
    RP_PIPE_CAM_BAD_IMAGE,    /* malformed image (truncated, stride < w, larger than the
                               * tracker's limits, smaller than its window) or of another size
                               * than the rig's calibration of the camera: ignored as if missing */
    RP_PIPE_CAM_NO_FEATURES   /* image accepted, but no feature survived or was found */
} rp_pipe_cam_state_t;

/* Report of the last rp_pipe_step, per rig camera and per stereo pair. */
typedef struct {
    uint32_t frame;                           /* frame sets processed, this one included */
    uint8_t cam_state[RP_MAX_CAMS];           /* rp_pipe_cam_state_t per rig camera */
    rp_status_t cam_status[RP_MAX_CAMS];      /* the tracker's (or image check's) status */
    rp_track_info_t track[RP_MAX_CAMS];       /* the tracker's events per rig camera */
    rp_smatch_stats_t match[RP_MAX_PAIRS];    /* this step's matching per pair (n_in = 0: no
                                               * new left features, matching not run) */
    rp_status_t est_status;                   /* the estimator's status (RP_OK if not run) */
} rp_pipe_info_t;

/* One stereo pair's matching state (its own, so that pairs may be matched concurrently). */
typedef struct {
    rp_smatch_t sm;
    rp_feat_t scratch_a[RP_MAX_FEATS_PER_CAM]; /* new left features to match */
    rp_feat_t scratch_b[RP_MAX_FEATS_PER_CAM]; /* their matches */
    uint32_t drop_ids[RP_MAX_FEATS_PER_CAM];  /* new left features left unmatched; in
                                               * rp_pipe_estimate, retired ones to make dormant */
    uint8_t done;                             /* matched in this step */
} rp_pipe_pairmatch_t;

/* Caller-owned pipeline state. Large: allocate it statically. Fields are read-only for callers
 * (use the accessors below). */
typedef struct {
    uint32_t magic;                           /* set by rp_pipe_init */
    const rp_rig_t *rig;
    rp_pipe_cfg_t cfg;
    uint8_t n_trk;                            /* trackers in use */
    uint8_t trk_cam[RP_PIPE_MAX_TRACKERS];    /* rig camera of each tracker */
    uint8_t trk_right[RP_PIPE_MAX_TRACKERS];  /* 1: second camera of a pair (no detection) */
    int8_t cam_trk[RP_MAX_CAMS];              /* tracker of each rig camera, -1: none */
    rp_tracker_t trk[RP_PIPE_MAX_TRACKERS];
    uint32_t born_k[RP_PIPE_MAX_TRACKERS];    /* left trackers: next_k before this step (ids at
                                               * or past it are new) */
    rp_stereo_pair_t pair[RP_MAX_PAIRS];
    rp_pipe_pairmatch_t pm[RP_MAX_PAIRS];     /* each pair's matcher and scratch */
    union {
        rp_vo_stereo_t stereo;
        rp_vo_gc_t gc;
        struct {
            rp_vo_mono_t mono[RP_RC_MAX_CAMS]; /* camK uses mono[0] */
            rp_real last_scale;               /* rc: last accepted scale S_j */
        } single;
    } est;
    rp_frameset_t fs;                         /* the last frame set of features */
    rp_estimate_t last;                       /* the last estimate */
    rp_real held_cov[36];                     /* pose covariance published while last held */
    rp_real anchor_cov[36];                   /* added to every published covariance: the
                                               * uncertainty of the structure rebuilt after
                                               * holds (rp_pipe.c, finish) */
    uint8_t was_held;                         /* the last held estimate is not yet followed by
                                               * an update */
    uint8_t turn_trk;                         /* the tracker whose top-up turn this step is
                                               * (n_trk: none) */
    uint8_t in_step;                          /* phased step: 0 none, 1 begun (tracking),
                                               * 2 matched (rp_pipe_begin .. rp_pipe_estimate) */
    rp_pipe_info_t info;
    int64_t last_utime;
} rp_pipe_t;

/* Name of a layout ("stereo4", "stereo2", "gc", "cam1".."cam4", "rc"); "?" if out of range. */
const char *rp_pipe_layout_name(rp_pipe_layout_t layout);

/* Layout from its name (as above). RP_E_ARG: NULL or unknown name. */
rp_status_t rp_pipe_layout_from_name(const char *name, rp_pipe_layout_t *layout);

/* Defaults for layout on the paper's rig as rigpose-sim numbers its cameras (0 cam1, 1 cam2,
 * 2 cam3, 3 cam4, 4 cam1's stereo partner, 5 cam3's): pairs (0,4) and (2,5); gc and rc over
 * 0..3; camK over camera K-1. Every other field is its component's *_default_cfg, unchanged
 * (the one source of defaults: config/README.md lists them per layout). A rig numbered
 * differently (e.g. a KITTI pair: 0 left, 1 right) sets the camera fields after this call.
 * RP_E_ARG: NULL or bad layout. */
rp_status_t rp_pipe_default_cfg(rp_pipe_layout_t layout, rp_pipe_cfg_t *cfg);

/* Set up pipe for rig (which must outlive it) with cfg (copied). Every camera of the layout
 * must have a calibration size within the tracker limits (RP_TRACK_MAX_W x RP_TRACK_MAX_H).
 * Returns RP_OK, RP_E_ARG (NULL, bad layout, a camera index out of the rig, a camera used
 * twice, a size over the limits, more cameras than RP_PIPE_MAX_TRACKERS), or the error of a
 * component's init (rp_track_init, rp_smatch_init, rp_stereo_pair_init, rp_vo_*_init). */
rp_status_t rp_pipe_init(rp_pipe_t *pipe, const rp_rig_t *rig, const rp_pipe_cfg_t *cfg);

/* Process one frame set: images[k] is rig camera k's image taken at utime (us), for
 * k < n (n <= RP_MAX_CAMS); a NULL entry, or k >= n, means camera k has no image this time
 * (the frame set flags it RP_FS_NO_IMAGE). Cameras not in the layout are ignored. est
 * (required) receives the estimate. Cameras with their own capture times: rp_pipe_step_timed.
 * Returns:
 *   RP_OK           the estimator ran and updated (est->flags: RP_EST_INITIALISING on the
 *                   first frame set, RP_EST_TRACKING, RP_EST_REINIT ...). A camera of the
 *                   layout without a usable image (missing, blank, malformed: see
 *                   rp_pipe_cam_state_t and rp_pipe_info) contributes no features and
 *                   sets RP_EST_DEGRADED; the others go on.
 *   RP_E_TOO_FEW    the estimator could not update (too few features): est is its prediction
 *                   with RP_EST_LOST; the next frame set tries to re-initialise (another
 *                   failure of the estimator's start or update, with the same outcome, keeps
 *                   its own code: RP_E_NO_CONVERGE, RP_E_SINGULAR, RP_E_NAN; rp_vo.h's
 *                   rp_vo_step_status)
 *   RP_E_DIVERGED   the estimator rejected its update and reset its covariance (prediction)
 *   RP_E_DEGENERATE no camera of the layout had a usable image: the estimator ran on no
 *                   features (its prediction to utime, RP_EST_LOST | RP_EST_DEGRADED)
 * A LOST estimate never carries RP_EST_TRACKING and its n_used are 0; with no update for
 * longer than the estimator's max_predict_s the pose is held (RP_EST_HELD, rp_ekf_predict);
 * after a hold the published covariance keeps the held one (rp_pipe.c, finish).
 *   RP_E_RANGE      utime not after the previous frame set's: nothing done, est = last
 *                   estimate with RP_EST_LOST
 *   RP_E_ARG        NULL pipe, images or est, n > RP_MAX_CAMS, or pipe not initialised:
 *                   nothing done (est, if given, zeroed with RP_EST_LOST)
 *   otherwise       an estimator's error (rp_vo_*_step), est as it filled it. */
rp_status_t rp_pipe_step(rp_pipe_t *pipe, const rp_image_t *const images[], uint8_t n,
                         int64_t utime, rp_estimate_t *est);

/* rp_pipe_step for cameras that are not simultaneous: cam_utime[k] (us) is camera k's own
 * capture time of images[k], for k < n; utime stays the set's time (the estimator's state
 * time; rp_frame.h). cam_utime NULL: every camera at utime, which is rp_pipe_step exactly.
 * Entries of cameras without an image (NULL, or k >= the rig's cameras) are not read. Each
 * camera's tracker gets its own time and the frame set carries cam_dt_us[k] = cam_utime[k] -
 * utime (rp_pipe_cam_time). Returns as rp_pipe_step, and
 *   RP_E_RANGE  a camera's time differs from utime by more than an int32_t of microseconds
 *               (35 min: a broken stamp), checked before anything else is done: est = last
 *               estimate with RP_EST_LOST, as for a utime not after the previous one. */
/* A camera's capture time relative to its set's: *dt_us = cam_utime - utime (us), computed
 * without overflow. RP_OK, RP_E_RANGE (does not fit an int32_t: *dt_us untouched) or RP_E_ARG
 * (dt_us NULL). What rp_pipe_cam_time and rp_pipe_step_timed check; for callers that build
 * frame sets themselves (rp_frameset_t.cam_dt_us). */
rp_status_t rp_pipe_cam_dt(int64_t cam_utime, int64_t utime, int32_t *dt_us);

rp_status_t rp_pipe_step_timed(rp_pipe_t *pipe, const rp_image_t *const images[],
                               const int64_t cam_utime[], uint8_t n, int64_t utime,
                               rp_estimate_t *est);

/* The same step in phases, for a caller that runs the cameras' trackers in parallel (one
 * thread per camera; core/ itself starts no thread). rp_pipe_step_timed is exactly
 *   rp_pipe_begin; rp_pipe_cam_time for each camera with an image (cam_utime not NULL);
 *   rp_pipe_track for t = 0 .. rp_pipe_n_trackers - 1; rp_pipe_match (which is
 *   rp_pipe_match_pair for k = 0 .. rp_pipe_n_pairs - 1); rp_pipe_estimate
 * and the result does not depend on the order or the threads the rp_pipe_track calls run on:
 * tracker t reads and writes only its own tracker and its camera's entries of the frame set
 * and of the report, so the calls for distinct t may run concurrently (each t once per step);
 * so may rp_pipe_match_pair for distinct pairs, and a pair's matching with the trackers of the
 * other cameras (it waits only for its own two: rp_pipe_pair_trackers).
 * Every other call, and every accessor, must not overlap any other call on the same pipe.
 *
 * rp_pipe_begin: checks and starts a step at utime. est may be NULL (a front end that does not
 *   estimate); if given it is filled on failure as rp_pipe_step says. Returns RP_OK, RP_E_RANGE
 *   (utime not after the previous step's: nothing started) or RP_E_ARG (NULL or not
 *   initialised). A step begun and never estimated is dropped by the next rp_pipe_begin (or
 *   rp_pipe_step, rp_pipe_step_feats); its trackers have moved on.
 * rp_pipe_cam_time: camera cam's own capture time utime_us (us) in the step begun (cameras
 *   that are not simultaneous; rp_pipe_step_timed): the frame set's cam_dt_us[cam] = utime_us -
 *   the step's utime. Call it before the camera's rp_pipe_track, whose tracker then gets that
 *   time (a later call still sets the frame set's entry, the tracker keeps the set's time); a
 *   camera without a call is at the step's utime. Returns RP_OK, RP_E_ARG (NULL, not
 *   initialised, no step begun or already estimated, cam not a camera of the rig) or
 *   RP_E_RANGE (the difference does not fit an int32_t: nothing changed).
 * rp_pipe_track: tracker t (0 .. rp_pipe_n_trackers - 1) on its camera's image in images (as
 *   rp_pipe_step takes them), at the camera's time (rp_pipe_cam_time). The outcome is in the
 *   camera's report (rp_pipe_info); the status is RP_OK, or RP_E_ARG (no step begun, t out of
 *   range, images NULL, n > RP_MAX_CAMS).
 * rp_pipe_match: stereo matching of the pairs' new features (stereo layouts; nothing for the
 *   others), of every pair not matched yet by rp_pipe_match_pair. After it rp_pipe_frameset
 *   holds the frame set the estimator will see. RP_E_ARG if no step is begun.
 * rp_pipe_match_pair: pair k's matching alone (k < rp_pipe_n_pairs), after the rp_pipe_track
 *   calls of its two trackers (rp_pipe_pair_trackers) have returned; it may run concurrently
 *   with the other trackers' rp_pipe_track and the other pairs' matching (a pair touches only
 *   its two cameras' trackers and entries, and its own matcher). RP_E_ARG: no step begun, not
 *   a stereo layout, k out of range. A pair matched twice in a step is matched once.
 * rp_pipe_estimate: the layout's estimator on the frame set (then, in the stereo layouts with
 *   cfg.dormant_retired, the retired tracks go dormant in the pairs' first trackers); returns
 *   as rp_pipe_step does, or RP_E_ARG (est NULL, or not matched) with est, if given, zeroed
 *   and LOST. */
rp_status_t rp_pipe_begin(rp_pipe_t *pipe, int64_t utime, rp_estimate_t *est);
rp_status_t rp_pipe_cam_time(rp_pipe_t *pipe, uint8_t cam, int64_t utime_us);
rp_status_t rp_pipe_track(rp_pipe_t *pipe, uint8_t t, const rp_image_t *const images[],
                          uint8_t n);
rp_status_t rp_pipe_match_pair(rp_pipe_t *pipe, uint8_t k);
rp_status_t rp_pipe_match(rp_pipe_t *pipe);
rp_status_t rp_pipe_estimate(rp_pipe_t *pipe, rp_estimate_t *est);

/* Trackers of the layout (0 for NULL or not initialised) and the rig camera of tracker t
 * (RP_E_ARG: NULL, not initialised, t out of range). */
uint8_t rp_pipe_n_trackers(const rp_pipe_t *pipe);
/* The tracker whose turn it is to top up in the step begun (its rp_pipe_track may detect: the
 * costliest of the step, so a caller spreading trackers over threads starts it first), or
 * rp_pipe_n_trackers when none, no step is begun or the pipe is NULL / not initialised. */
uint8_t rp_pipe_topup_tracker(const rp_pipe_t *pipe);
/* Stereo pairs of the layout (0 for the other layouts, NULL or not initialised). */
uint8_t rp_pipe_n_pairs(const rp_pipe_t *pipe);
rp_status_t rp_pipe_tracker_cam(const rp_pipe_t *pipe, uint8_t t, uint8_t *cam);
/* The trackers of stereo pair k's first (*ta) and second (*tb) camera. RP_E_ARG: NULL, not
 * initialised, not a stereo layout, k out of range. */
rp_status_t rp_pipe_pair_trackers(const rp_pipe_t *pipe, uint8_t k, uint8_t *ta, uint8_t *tb);

/* Feature-level input: run the layout's estimator on fs, a frame set of features built
 * elsewhere (rp_frame.h; ids shared between the cameras of a stereo pair), skipping the
 * trackers and the matcher. Feed one pipeline either images (rp_pipe_step) or frame sets
 * (this), not both: the trackers do not see the frame sets given here. est (required) receives
 * the estimate with the estimator's own flags. rp_pipe_frameset then returns a copy of fs, and
 * rp_pipe_info marks each camera of the layout RP_PIPE_CAM_OK (features) or
 * RP_PIPE_CAM_NO_FEATURES, with the estimator's status.
 * Returns the estimator's status as rp_pipe_step does (RP_OK, RP_E_TOO_FEW, RP_E_DIVERGED, its
 * RP_E_ARG for a malformed frame set), or:
 *   RP_E_RANGE  fs->utime not after the previous frame set's: nothing done, est = the last
 *               estimate with RP_EST_LOST
 *   RP_E_ARG    NULL pipe, fs or est, or pipe not initialised: nothing done (est, if given,
 *               zeroed with RP_EST_LOST). */
rp_status_t rp_pipe_step_feats(rp_pipe_t *pipe, const rp_frameset_t *fs, rp_estimate_t *est);

/* The last frame set of features (what the estimator received). RP_E_ARG: NULL or not
 * initialised. Before the first step: an empty frame set. */
rp_status_t rp_pipe_frameset(const rp_pipe_t *pipe, const rp_frameset_t **fs);

/* The report of the last step. RP_E_ARG: NULL or not initialised. */
rp_status_t rp_pipe_info(const rp_pipe_t *pipe, const rp_pipe_info_t **info);

/* Each rig camera's clock offset as the estimator holds it now (rp_ekf.h: capture = stamp +
 * off_s[k], s) and its standard deviation sigma_s[k] (s; 0: not estimated, the configured
 * value). gc and stereo estimate the offsets of their cameras but the first with
 * estimator.estimate_time_offsets; camK and rc hold the configured ones. RP_E_ARG: NULL or not
 * initialised. */
rp_status_t rp_pipe_time_offsets(const rp_pipe_t *pipe, rp_real off_s[RP_MAX_CAMS],
                                 rp_real sigma_s[RP_MAX_CAMS]);

#ifdef __cplusplus
}
#endif

#endif /* RP_PIPE_H */
