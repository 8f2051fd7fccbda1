/*
 * rp_hal_v4l2.h - the pure parts of the HAL's v4l2 source (no device needed), public so that
 * tests and tools can pin them down: pixel conversion to 8-bit grey, the per-camera sequence
 * tracker that counts dropped frames, and the grouping of the cameras' frames into one set.
 */
#ifndef RP_HAL_V4L2_H
#define RP_HAL_V4L2_H

#include <stddef.h>
#include <stdint.h>

#include "rigpose/rp_hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* YUYV 4:2:2 (Y0 U Y1 V per two pixels) to grey: the Y bytes. src_stride >= 2 * w, w even or
 * odd (an odd last pixel is the Y0 of a final pair). RP_HAL_E_ARG on NULL or a short stride. */
rp_hal_status_t rp_hal_yuyv_to_grey(const uint8_t *src, uint32_t src_stride, uint16_t w,
                                    uint16_t h, uint8_t *dst, uint32_t dst_stride);

/* UYVY (U Y0 V Y1): the same with the Y bytes at odd offsets. */
rp_hal_status_t rp_hal_uyvy_to_grey(const uint8_t *src, uint32_t src_stride, uint16_t w,
                                    uint16_t h, uint8_t *dst, uint32_t dst_stride);

/* One JPEG (MJPEG frame) of n bytes decoded to grey into dst (cap bytes, rows of w). The image
 * must be exactly w x h: RP_HAL_E_FORMAT for a corrupt or cut stream (any libjpeg warning) or another size. libjpeg decodes
 * straight to its luminance (no colour conversion); it allocates its work memory itself. */
rp_hal_status_t rp_hal_jpeg_to_grey(const uint8_t *jpg, size_t n, uint16_t w, uint16_t h,
                                    uint8_t *dst, size_t cap);

/* Sequence numbers of one camera (v4l2_buffer.sequence): counts the frames the driver skipped.
 * A repeat (same number) or a step back (the device was reopened, or the counter wrapped) is
 * not a drop: it restarts the count from that number. */
typedef struct {
    uint8_t have;  /* a number was seen */
    uint32_t last; /* the last number seen */
    uint32_t drops;   /* frames skipped so far */
    uint32_t repeats; /* repeated numbers so far */
} rp_hal_seq_t;

/* Feeds the next number; returns how many frames were skipped just before it (0 if none). */
uint32_t rp_hal_seq_update(rp_hal_seq_t *s, uint32_t seq);

/* mmap buffers per device, and how many of them may hold frames waiting for a set (the rest:
 * the one delivered in the last set and at least one with the driver). */
#ifndef RP_HAL_V4L2_NBUF
#define RP_HAL_V4L2_NBUF 6
#endif
#define RP_HAL_V4L2_HOLD (RP_HAL_V4L2_NBUF - 2)

/* Grouping by timestamp. t_us[i * stride + k], k < count[i]: the times of the frames camera i
 * holds, oldest first. A set is an anchor time a, one of the held frames, such that every camera
 * with need[i] holds a frame in [a - tol_us, a]; the newest such a wins, and every camera
 * (needed or not) takes its newest frame in that window: pick[i] = k, or -1. Returns how many
 * cameras were picked, 0 if there is no set (pick all -1, *anchor_us 0). With no camera needed
 * the anchor is the newest frame held. Holding several frames per camera lets a camera whose
 * frames arrive later than the others' (more than a frame period) still meet them. */
uint8_t rp_hal_group(const int64_t *t_us, const uint8_t *count, uint8_t n, uint8_t stride,
                     const uint8_t *need, int64_t tol_us, int8_t *pick, int64_t *anchor_us);

/* Free-running cameras (rp_hal_cfg_t.sets_latest): a set as soon as camera ref (ref < 0: any
 * camera) holds a frame; the anchor is its newest held frame (any camera's newest with ref < 0),
 * and every camera takes its newest held frame (pick[i] = count[i] - 1, or -1 for none; the
 * older ones are not used: a slow consumer skips frames rather than falls behind). Each frame
 * is delivered once, in the first set after it arrived, with its own time. Returns how many
 * cameras were picked, 0 if there is no set (ref holds nothing; pick all -1, *anchor_us 0). */
uint8_t rp_hal_group_latest(const int64_t *t_us, const uint8_t *count, uint8_t n, uint8_t stride,
                            int ref, int8_t *pick, int64_t *anchor_us);

/* How many of camera i's oldest held frames can never be in a set: a frame at t is hopeless
 * when some needed camera j != i holds frames that are all newer than t + tol_us (its later
 * frames are newer still). */
uint8_t rp_hal_group_hopeless(const int64_t *t_us, const uint8_t *count, uint8_t n,
                              uint8_t stride, const uint8_t *need, int64_t tol_us, uint8_t i);

/* What the open v4l2 source negotiated for camera cam, in words for logs, e.g.
 * "/dev/video0: GREY 640x480, 640 bytes/line, 4 mmap buffers"; RP_HAL_E_STATE if no v4l2
 * source is open, RP_HAL_E_ARG for a bad camera or buffer. */
rp_hal_status_t rp_hal_v4l2_describe(uint8_t cam, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif

#endif /* RP_HAL_V4L2_H */
