/*
 * rp_lcmsrc.h - the daemon's source kind `lcm`: frame sets assembled from the rigpose.features_t
 * messages of rigpose-frontend processes (one per camera image, on each camera's features
 * channel, rp_feats.h), handed to the loop as the sim source's are (RP_HAL_PAYLOAD_FEATS), so
 * the daemon runs them through rp_est_step.
 *
 * Not a HAL source (the HAL library does not link LCM); the same shape of calls: open, grab (a
 * set, or RP_HAL_E_TIMEOUT after cfg.hal.timeout_ms), errmsg, close. One per process.
 *
 * Assembly (`sets: matched`, the default). A message joins the pending set whose utime is within cfg.hal.sync_tol_us of its
 * own, else opens one (at most RP_LSRC_PENDING at once). The oldest pending set goes out when
 * each camera of the layout (rp_feats_layout_cams) is in it, or has sent a later frame, or is
 * absent; or when the set has waited timeout_ms since its first message. A camera is absent
 * when nothing came from it for timeout_ms (never heard: once a set has waited timeout_ms for
 * it): sets no longer wait for it, and its state in every set is MISSING | GONE (the status
 * channel's CAM_GONE) until its front end sends again, when it is back in the next set (a
 * restarted front end rejoins). A late message does not count as heard (a restarted front end
 * catching up does not hold the sets back). Sets go out in time order; a message for a time at or before a set already out
 * is late and dropped (counted).
 *
 * Assembly with `sets: latest` (cfg.hal.sets_latest; free-running cameras at their own rates,
 * as the v4l2 source's rp_hal_group_latest): no grouping by sync_tol_us and no waiting. Each
 * camera's newest image not yet delivered is held (a newer one replaces it: n_skipped); an
 * image of the set camera (cfg.hal.set_cam, or the layout's first camera if that one is not
 * the layout's: the source hears no other; any camera with `any`, or while the set camera is
 * absent) for a time after the last set's makes the set, with every camera's held image at
 * its own time, the set's time that image's, the others MISSING (not an error: rp_lsrc_errmsg
 * names only cameras never heard or gone). Before the set goes out the messages already
 * queued are read, so a slow estimator gets the newest frames and skips the rest. When the
 * set camera turns absent while images are held, the newest of them makes a set. An image
 * not after the last one its camera delivered or holds is late; a message saying the camera
 * had no image (MISSING, as a multi-camera front end sends) only counts as heard. A camera
 * never heard is absent timeout_ms after rp_lsrc_open.
 *
 * Times (with `sets: latest` the set's time is the image that made it, above). Each message's utime is its camera's own capture time (rigpose-frontend stamps each
 * camera's image with the HAL's per-camera stamp). The set's time (set->utime, feats->utime)
 * is, as the v4l2 HAL's, the capture time of the lowest-index camera of the set that delivered
 * an image (a message without features_t.state's MISSING bit); if none did, or if that time is
 * not after the previous set's (cameras spread over more than sync_tol_us), the set's first
 * message's time, which always is. So the set's time does not depend on the order the
 * messages arrived in. feats->cam_dt_us[k] is camera k's time minus the set's (within
 * 2 sync_tol_us: sync_tol_us is at most 1 s; with sets: latest a camera's frame more than 35
 * min from the set's time is left out, counted bad) and set->cam[k].utime camera k's time; a camera
 * of the layout without a message in the set, or whose message says MISSING, is flagged
 * RP_FS_NO_IMAGE (as the in-process pipeline flags a camera without an image).
 *
 * Track ids. A front end restarted (a new instance in its messages) starts its trackers' serials
 * again from 0, which would give new tracks the ids of landmarks the estimator still holds: the
 * source adds, per id camera (rp_track_id_cam), an offset that continues after the highest
 * serial seen from that camera before. The offset is 0 until a restart, so ids are the front
 * ends' own (and the frame sets those of the in-process pipeline) until then.
 *
 * No heap: the pending sets are the object's (0.5 MB with double rp_real: keep it static).
 */
#ifndef RP_LCMSRC_H
#define RP_LCMSRC_H

#include <lcm/lcm.h>
#include <stdint.h>

#include "rigpose/rp_config.h"
#include "rigpose/rp_frame.h"
#include "rigpose/rp_hal.h"
#include "rigpose_features_t.h"

#define RP_LSRC_PENDING 8   /* frame sets being assembled at once */
#define RP_LSRC_ERR_MAX 320
#define RP_LSRC_ID_CAMS 16  /* rp_track_id_cam's range */
#define RP_LSRC_DRAIN_MAX 1024 /* sets: latest: queued messages read at most before a set goes
                                * out (the subscriptions' queues hold 120 per camera) */

typedef struct {
    uint8_t used;
    int64_t utime;                     /* us, the first message's (the set's grouping time) */
    int64_t cam_utime[RP_MAX_CAMS];    /* us, each camera's message's (its capture time) */
    int64_t first_rx_us;               /* HAL clock when its first message came */
    uint8_t have[RP_MAX_CAMS];
    uint8_t state[RP_MAX_CAMS];        /* features_t.state */
    int32_t seq[RP_MAX_CAMS];
    int32_t drops[RP_MAX_CAMS];
    rp_frameset_t fs;
} rp_lsrc_pending_t;

typedef struct {
    uint8_t seen;                      /* a message came since open */
    int8_t instance[32];               /* its front end, as in the last message */
    int64_t last_rx_us;                /* HAL clock of the last message */
    int64_t last_utime;                /* latest frame time from this camera, us */
    uint8_t out_any;                   /* a frame of it went out in a set (latest) */
    int64_t out_utime;                 /* the time of the last one, us */
} rp_lsrc_cam_t;

typedef struct rp_lsrc rp_lsrc_t;
typedef struct {
    rp_lsrc_t *src;
    uint8_t cam;
} rp_lsrc_hook_t;

struct rp_lsrc {
    lcm_t *lcm;
    uint8_t n_cams;
    uint8_t want[RP_MAX_CAMS];         /* cameras of the layout */
    int64_t tol_us, timeout_us;
    uint8_t latest;                    /* cfg.hal.sets_latest (Assembly, sets: latest) */
    int8_t set_cam;                    /* cfg.hal.set_cam: the set camera, -1 any */
    uint8_t trigger;                   /* latest: pend[0] is ready, its time anchor, the */
    int64_t anchor;                    /*   time of camera anchor_cam's frame in it */
    uint8_t anchor_cam;
    int64_t open_us;                   /* HAL clock at rp_lsrc_open */
    uint8_t any_out;
    int64_t last_out_utime;            /* grouping time of the last set out (late messages) */
    int64_t last_set_utime;            /* its set time (rp_lcmsrc.h, Times) */
    uint32_t set_seq;
    rp_lsrc_cam_t cam[RP_MAX_CAMS];
    rp_lsrc_pending_t pend[RP_LSRC_PENDING];
    /* id remapping per id camera */
    uint8_t id_known[RP_LSRC_ID_CAMS];
    int8_t id_inst[RP_LSRC_ID_CAMS][32];
    uint32_t id_off[RP_LSRC_ID_CAMS], id_hi[RP_LSRC_ID_CAMS];
    uint8_t id_hi_set[RP_LSRC_ID_CAMS];
    rp_lsrc_hook_t hook[RP_MAX_CAMS];
    lcm_subscription_t *sub[RP_MAX_CAMS];
    rigpose_features_t msg;            /* decoding buffer */
    rp_frameset_t out;                 /* the set handed out by the last grab */
    char err[RP_LSRC_ERR_MAX];
    uint32_t n_waited;                 /* sets that went out after waiting timeout_ms */
    uint32_t n_msgs, n_late, n_bad, n_full, n_restarts;
    uint32_t n_skipped;                /* latest: frames replaced by a newer one before a set */
};

/* Largest sync_tol_us the source takes (the configuration's limit): camera times of a set then
 * differ by at most 2 s, so cam_dt_us fits its int32_t. */
#define RP_LSRC_TOL_MAX_US 1000000

/* Subscribe on lcm to the features channel of each camera of cfg's layout (cfg must outlive s).
 * RP_HAL_OK; RP_HAL_E_ARG (NULL, a layout without cameras, a channel name too long, sync_tol_us
 * outside 0..RP_LSRC_TOL_MAX_US, with sets: latest a set camera outside the rig) or
 * RP_HAL_E_OPEN (lcm_subscribe failed), the reason in rp_lsrc_errmsg. */
rp_hal_status_t rp_lsrc_open(rp_lsrc_t *s, lcm_t *lcm, const rp_config_t *cfg);

/* The next frame set (payload RP_HAL_PAYLOAD_FEATS: set->feats valid until the next grab),
 * handling LCM until one is ready, at most timeout_ms: RP_HAL_OK, or RP_HAL_E_TIMEOUT (set then
 * says which cameras are gone), RP_HAL_E_IO (lcm_handle failed), RP_HAL_E_ARG. After RP_HAL_OK
 * rp_lsrc_errmsg is "" unless cameras of the layout are missing from the set. */
rp_hal_status_t rp_lsrc_grab(rp_lsrc_t *s, rp_hal_set_t *set);

/* What went wrong last, or why the last set lacks cameras; "" if nothing. Never NULL. */
const char *rp_lsrc_errmsg(const rp_lsrc_t *s);

/* Unsubscribe. */
void rp_lsrc_close(rp_lsrc_t *s);

#endif /* RP_LCMSRC_H */
