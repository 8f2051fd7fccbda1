/*
 * rp_hal.h - the platform HAL: one camera-source interface (open, start, grab a synchronised
 * frame set, stop, close) with three sources, plus clock and sleep.
 *
 *   v4l2    Linux video devices (platform/src/rp_hal_v4l2.c): format negotiation, GREY / YUYV /
 *           MJPEG to 8-bit grey, mmap streaming of all devices, kernel timestamps, grouping by
 *           timestamp within a tolerance, drop detection, vanished / stalled devices retried.
 *   replay  image sequences with timestamps (platform/src/rp_hal_replay.c): rigpose-render output
 *           and the real data in ../shared/data/.
 *   sim     the simulated rig (platform/src/rp_hal_sim.c): the feature-level simulation of
 *           rigpose-sim, so the daemon runs with no hardware; delivers features and the truth.
 *
 * All three go through the same calls (one const table of functions per source). A set carries
 * either images or features (rp_hal_payload_t, in set->payload and rp_hal_payload(src)).
 *
 * Not core code: sources may use the OS (open, ioctl, mmap, files) but keep their buffers in the
 * source object or in fixed-size arrays; grab never blocks longer than cfg.timeout_ms.
 * Every function returns an rp_hal_status_t the caller can act on.
 */
#ifndef RP_HAL_H
#define RP_HAL_H

#include <stdint.h>

#include "rigpose/rp_frame.h"
#include "rigpose/rp_opts.h"
#include "rigpose/rp_image.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    RP_HAL_OK = 0,
    RP_HAL_E_ARG,       /* bad argument or configuration */
    RP_HAL_E_OPEN,      /* a device or file could not be opened */
    RP_HAL_E_FORMAT,    /* no usable pixel format / size, or a malformed image file */
    RP_HAL_E_IO,        /* an ioctl / read failed */
    RP_HAL_E_TIMEOUT,   /* no complete set within timeout_ms (some cameras may still be in it) */
    RP_HAL_E_END,       /* replay / sim: no more frames */
    RP_HAL_E_STATE      /* call out of order (grab before start, ...) */
} rp_hal_status_t;

const char *rp_hal_status_str(rp_hal_status_t s);

/* RP_HAL_SRC_LCM: feature messages of rigpose-frontend processes over LCM. Not a HAL source
 * (the HAL does not link LCM; rp_hal_open refuses it): the daemon's own (daemon/rp_lcmsrc.h),
 * named here so that the configuration and the status channel know it. */
typedef enum {
    RP_HAL_SRC_V4L2 = 0,
    RP_HAL_SRC_REPLAY,
    RP_HAL_SRC_SIM,
    RP_HAL_SRC_LCM
} rp_hal_kind_t;

/* rp_hal_cfg_t.realtime */
enum {
    RP_HAL_PACE_FAST = 0, /* replay / sim: sets as fast as they are asked for */
    RP_HAL_PACE_SPACED,   /* at their recorded spacing, the first set at once */
    RP_HAL_PACE_LIVE      /* replay: the recorded times are HAL clock times (rp_hal_now_us): each
                           * set comes at its time, like a camera's frame; a set whose time
                           * passed more than timeout_ms ago is skipped (a process started late
                           * joins the others' present). sim: as SPACED */
};

/* What a source's sets carry. */
typedef enum {
    RP_HAL_PAYLOAD_IMAGES = 0, /* each camera's 8-bit grey image (v4l2, replay) */
    RP_HAL_PAYLOAD_FEATS       /* one frame set of tracked features, no images (sim) */
} rp_hal_payload_t;

struct rp_hal_sim_opts; /* rp_hal_sim.h */

#define RP_HAL_PATH_MAX 256

/* Largest image a source delivers (each camera's grey buffer is this big, statically). */
#ifndef RP_HAL_MAX_W
#define RP_HAL_MAX_W RP_TRACK_MAX_W
#endif
#ifndef RP_HAL_MAX_H
#define RP_HAL_MAX_H RP_TRACK_MAX_H
#endif

/* One camera of the source. */
typedef struct {
    char device[RP_HAL_PATH_MAX]; /* v4l2: /dev/videoN; replay: its column in frames.csv ("" =
                                   * the i-th image column); sim: unused */
    uint16_t w, h;                /* wanted size, px; 0 = any. v4l2 asks for it and refuses a
                                   * different one; replay checks every image against it */
    uint16_t fps;                 /* wanted rate (v4l2) */
} rp_hal_cam_cfg_t;

/* A way to run jobs in parallel, given by the caller (the daemon's rp_pool_run): runs
 * fn(arg, j) for j = 0 .. n_jobs - 1, possibly on several threads at once, and returns once
 * all have returned (0), or fails having run none (non-zero). Sources that decode or convert
 * images (replay: PNG / PGM files; v4l2: MJPEG / YUYV / UYVY) then decode each camera's image
 * in a job of its own, the cameras' jobs touching only their camera's buffers; the set
 * delivered is the same as without it (NULL: one camera after the other, on the grabbing
 * thread). */
typedef int (*rp_hal_jobs_fn_t)(void *ctx, unsigned n_jobs, void (*fn)(void *arg, unsigned job),
                                void *arg);

typedef struct {
    rp_hal_kind_t kind;
    uint8_t n_cams;                      /* 1..RP_MAX_CAMS */
    rp_hal_cam_cfg_t cam[RP_MAX_CAMS];
    int64_t sync_tol_us;                 /* v4l2: frames within this of the set time group */
    uint32_t timeout_ms;                 /* grab gives up after this */
    uint32_t retry_ms;                   /* v4l2: reopen a vanished device this often */
    char replay_index[RP_HAL_PATH_MAX];  /* replay: frames.csv, or the folder holding it */
    uint32_t sim_seed;                   /* sim: run seed (Table 1 protocol) */
    uint32_t sim_frames;                 /* sim: frames in the run (0 = the protocol's 100) */
    uint8_t sim_layout;                  /* sim: 0 = both stereo pairs (4 cams), 1 = four singles */
    uint8_t realtime;                    /* replay / sim: RP_HAL_PACE_* (0: fast) */
    uint8_t partial_sets;                /* replay: a row whose image cannot be read for some
                                          * cameras comes as a set with those cameras MISSING
                                          * (RP_HAL_OK, the reason in rp_hal_errmsg) - the
                                          * daemon; 0: the row fails with its first camera's
                                          * error (a recorder wants whole sets) */
    const struct rp_hal_sim_opts *sim_opts; /* sim: pixel noise, a vanishing camera
                                             * (rp_hal_sim.h); NULL: the protocol's defaults.
                                             * Read by rp_hal_open only */
    rp_hal_jobs_fn_t run_jobs;           /* optional: how to run one job per camera (below) */
    void *run_jobs_ctx;
} rp_hal_cfg_t;

/* Per-camera state in one set. */
enum {
    RP_HAL_CAM_OK      = 0,
    RP_HAL_CAM_MISSING = 1u << 0, /* no frame in this set (stalled, vanished, out of tolerance) */
    RP_HAL_CAM_GONE    = 1u << 1, /* device vanished; being retried every retry_ms */
    RP_HAL_CAM_DROPPED = 1u << 2  /* the driver's sequence skipped frames before this one */
};

typedef struct {
    rp_image_t img;    /* 8-bit grey, valid until the next grab (img.data NULL if missing) */
    int64_t utime;     /* capture time, microseconds, CLOCK_MONOTONIC (v4l2: kernel stamp) */
    uint32_t seq;      /* the driver's / file's sequence number */
    uint32_t flags;    /* RP_HAL_CAM_* */
    uint32_t drops;    /* frames dropped so far by this camera */
} rp_hal_frame_t;

typedef struct {
    int64_t utime;     /* time of the set (the first camera's present frame), microseconds */
    uint32_t seq;      /* set counter since start, +1 per grab that returned RP_HAL_OK */
    uint8_t n_cams;
    rp_hal_frame_t cam[RP_MAX_CAMS];
    /* What the set carries: RP_HAL_PAYLOAD_IMAGES, cam[k].img; RP_HAL_PAYLOAD_FEATS, the
     * features of all cameras in *feats (valid until the next grab; NULL for images). */
    rp_hal_payload_t payload;
    const rp_frameset_t *feats;
    /* Sources that know the truth (sim, replay with ground truth): pose of cam1 in the world,
     * [tx ty tz alpha beta gamma] as in rp_estimate_t. */
    uint8_t has_truth;
    rp_real truth[6];
} rp_hal_set_t;

typedef struct rp_hal_source rp_hal_source_t; /* defined by each source */

/* Creates the source for cfg->kind. Sources are few and long-lived: one per process. */
rp_hal_status_t rp_hal_open(rp_hal_source_t **src, const rp_hal_cfg_t *cfg);
rp_hal_status_t rp_hal_start(rp_hal_source_t *src);
/* Blocks until a synchronised set is ready or timeout_ms passes. On RP_HAL_E_TIMEOUT the set
 * still describes which cameras were missing. */
rp_hal_status_t rp_hal_grab(rp_hal_source_t *src, rp_hal_set_t *set);
rp_hal_status_t rp_hal_stop(rp_hal_source_t *src);
void rp_hal_close(rp_hal_source_t *src);

/* What the open source's sets carry (the same in every set); RP_HAL_PAYLOAD_IMAGES for NULL. */
rp_hal_payload_t rp_hal_payload(const rp_hal_source_t *src);

/* What went wrong in the source's last failing call, in words naming the device or file (and
 * line, camera), e.g. "rec/frames.csv:7: want utime_us and 4 image paths"; "" if nothing
 * failed. After a grab that returned RP_HAL_OK it is "" unless the set is degraded: then why its
 * cameras are missing (a v4l2 camera lost, a replay image unreadable with partial_sets). Control
 * characters and invalid UTF-8 echoed from files come escaped as \xNN. src NULL: why the last
 * rp_hal_open failed. Never NULL. */
const char *rp_hal_errmsg(const rp_hal_source_t *src);

/* Clock (CLOCK_MONOTONIC, microseconds) and sleep. */
int64_t rp_hal_now_us(void);
void rp_hal_sleep_us(int64_t us);

#ifdef __cplusplus
}
#endif

#endif /* RP_HAL_H */
