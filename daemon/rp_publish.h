/*
 * rp_publish.h - the daemon's LCM messages without heap: each message is encoded with lcm-gen's
 * <type>_encode into a static buffer sized at compile time for the type's largest encoding,
 * then handed to lcm_publish. (lcm-gen's <type>_publish mallocs a buffer per message; the
 * per-frame path must not.) The buffers are the module's: one publishing thread.
 *
 * Encoded sizes (lcm_types/rigpose_*_t.lcm: 8 bytes of type hash, then the fields big-endian,
 * booleans as one byte): pose_t and status_t have fixed-size arrays only, so their size is a
 * constant; image_t carries data[size], at most RP_HAL_MAX_W x RP_HAL_MAX_H bytes.
 * test_publish checks the constants against <type>_encoded_size.
 *
 * Whatever LCM's provider does inside lcm_publish is LCM's (udpm sends from the caller's
 * buffer; memq:// queues a copy on the heap: an in-process test transport).
 */
#ifndef RP_PUBLISH_H
#define RP_PUBLISH_H

#include <lcm/lcm.h>
#include <stdint.h>

#include "rigpose/rp_frame.h"
#include "rigpose/rp_hal.h"
#include "rigpose/rp_status.h"
#include "rigpose_features_t.h"
#include "rigpose_image_t.h"
#include "rigpose_pose_t.h"
#include "rigpose_status_t.h"

typedef enum {
    RP_PUB_OK = 0,
    RP_PUB_E_ARG,    /* NULL argument, empty channel, an image inconsistent with its size */
    RP_PUB_E_SIZE,   /* the message is larger than its static buffer */
    RP_PUB_E_ENCODE, /* lcm-gen's encoder refused it */
    RP_PUB_E_LCM     /* lcm_publish failed (the transport) */
} rp_pub_status_t;

const char *rp_pub_status_str(rp_pub_status_t s);

/* Largest encodings, bytes. */
#define RP_PUB_HASH_BYTES 8
#define RP_PUB_INSTANCE_BYTES 32 /* pose_t.instance, status_t.instance */
#define RP_PUB_POSE_BYTES                                                                      \
    (RP_PUB_HASH_BYTES + 8 + 8 + 4 + 4 + 1 + 8 * (3 + 4 + 3 + 3 + 3 + 36) + 1 + 2 * 6 + 2 + 2 + \
     4 + 4 + 1 + 8 * 6 + RP_PUB_INSTANCE_BYTES)
#define RP_PUB_STATUS_BYTES                                                                    \
    (RP_PUB_HASH_BYTES + 8 + 4 + 4 + 1 + 1 + 4 + 1 + 6 + 4 * 6 + 4 * 6 + 4 * 6 + 2 * 6 +      \
     2 * 6 + 4 * 6 + 4 * 6 + 4 * 6 + 4 + 4 + 4 + 4 + 4 + 4 + 4 + 4 + 2 + 4 + 4 +              \
     RP_PUB_INSTANCE_BYTES + 4)
#define RP_PUB_IMAGE_HEAD_BYTES (RP_PUB_HASH_BYTES + 8 + 4 + 1 + 2 + 2 + 4)
#define RP_PUB_IMAGE_BYTES (RP_PUB_IMAGE_HEAD_BYTES + (RP_HAL_MAX_W) * (RP_HAL_MAX_H))
#define RP_PUB_FEATS_MAX 512 /* features_t's arrays */
#define RP_PUB_FEATS_BYTES                                                                     \
    (RP_PUB_HASH_BYTES + 8 + 4 + 1 + 1 + 4 + 2 + (4 + 8 + 8 + 1) * RP_PUB_FEATS_MAX +          \
     RP_PUB_INSTANCE_BYTES)

/* The pose message of one set: est (step status st) for set, pose counter seq, the rig's
 * n_cams and the method (pose_t.METHOD_*). publish_utime is left 0: the caller stamps it just
 * before rp_pub_pose. */
void rp_pub_fill_pose(rigpose_pose_t *m, const rp_hal_set_t *set, const rp_estimate_t *est,
                      rp_status_t st, int32_t seq, uint8_t n_cams, int8_t method);

/* Encode m into the type's static buffer and lcm_publish it on channel. */
rp_pub_status_t rp_pub_pose(lcm_t *lcm, const char *channel, const rigpose_pose_t *m);
rp_pub_status_t rp_pub_status(lcm_t *lcm, const char *channel, const rigpose_status_t *m);
rp_pub_status_t rp_pub_image(lcm_t *lcm, const char *channel, const rigpose_image_t *m);

/* Each present camera's image of set (rows packed, data[w*h]) on channel, tagged with seq.
 * Cameras without an image are skipped. Goes on after a failure; returns the first one and its
 * camera in *bad_cam (optional, -1 if none). */
rp_pub_status_t rp_pub_set_images(lcm_t *lcm, const char *channel, const rp_hal_set_t *set,
                                  int32_t seq, int *bad_cam);

/* One camera's features f[0..n-1] (cut at RP_PUB_FEATS_MAX) into m, the unused entries zero;
 * state, drops, flags[] and instance zero (a front end sets them). */
void rp_pub_fill_features(rigpose_features_t *m, uint8_t cam, int64_t utime, int32_t seq,
                          const rp_feat_t *f, uint16_t n);

/* Encode m into the type's static buffer and lcm_publish it on channel. */
rp_pub_status_t rp_pub_features(lcm_t *lcm, const char *channel, const rigpose_features_t *m);

/* The features of fs (the set the estimator used) as one rigpose_features_t per camera
 * 0..n_cams-1 on channel, tagged with seq; a camera's features past RP_PUB_FEATS_MAX are cut.
 * Goes on after a failure; returns the first one and its camera in *bad_cam (-1: none). */
rp_pub_status_t rp_pub_set_features(lcm_t *lcm, const char *channel, const rp_frameset_t *fs,
                                    uint8_t n_cams, int32_t seq, int *bad_cam);

#endif /* RP_PUBLISH_H */
