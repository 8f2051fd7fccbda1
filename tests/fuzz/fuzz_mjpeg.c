/*
 * fuzz_mjpeg.c - libFuzzer target: the V4L2 source's MJPEG decoder, rp_hal_jpeg_to_grey
 * (platform/src/rp_hal_v4l2.c, libjpeg), as cam_image calls it on a driver's buffer. The first
 * four bytes are the configured width and height (big-endian uint16 each, at most
 * RP_HAL_MAX_W x RP_HAL_MAX_H), the rest is the frame. The output buffer is exactly w * h bytes
 * on the heap, so ASan sees any write past the image.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "rigpose/rp_hal.h"
#include "rigpose/rp_hal_v4l2.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 4) {
        return 0;
    }
    const uint16_t w = (uint16_t)(data[0] << 8 | data[1]), h = (uint16_t)(data[2] << 8 | data[3]);
    if (w == 0 || h == 0 || w > RP_HAL_MAX_W || h > RP_HAL_MAX_H) {
        return 0;
    }
    const size_t cap = (size_t)w * h;
    uint8_t *dst = malloc(cap);
    if (dst == NULL) {
        return 0;
    }
    const rp_hal_status_t st = rp_hal_jpeg_to_grey(data + 4, size - 4, w, h, dst, cap);
    if (st != RP_HAL_OK && st != RP_HAL_E_FORMAT && st != RP_HAL_E_ARG) {
        __builtin_trap();
    }
    free(dst);
    return 0;
}
