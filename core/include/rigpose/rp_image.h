/*
 * rp_image.h - the image type every stage that reads pixels shares (the HAL's sources, the
 * tracker, the pipeline): an 8-bit grey image owned by the caller. No functions: a plain view.
 */
#ifndef RP_IMAGE_H
#define RP_IMAGE_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A caller-owned 8-bit grey image, row-major: pixel (u, v) is data[v * stride + u].
 * size is the number of readable bytes at data: an image is truncated (rejected) when
 * size < stride * (h - 1) + w. */
typedef struct {
    const uint8_t *data;
    uint16_t w, h;   /* pixels */
    uint32_t stride; /* bytes between rows, >= w */
    uint32_t size;   /* readable bytes at data */
} rp_image_t;

#ifdef __cplusplus
}
#endif

#endif /* RP_IMAGE_H */
