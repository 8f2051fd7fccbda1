/*
 * rp_lcm_image.h - decoding rigpose.image_t from untrusted bytes (an LCM log, the network).
 *
 * lcm-gen 1.3.1's C decoder allocates `size` bytes and copies `size` bytes without checking the
 * sign: an image_t whose size field is negative makes rigpose_image_t_decode call
 * memcpy(NULL, buf, (size_t)-1) (SIGSEGV), and size 0 calls memcpy(NULL, buf, 0) (undefined;
 * UBSan stops on it). The generated code is not ours to edit, so every tool decodes image_t
 * through rp_image_t_decode_checked: the size field is read from the bytes first and must lie in
 * 1..(bytes left after it), then the generated decoder runs (tests/fuzz/README.md).
 *
 * The field's place is found once by encoding a probe message (so a changed image_t cannot make
 * the check read the wrong bytes: then every message is refused, and the tools' tests notice).
 * Header-only, C99 and C++.
 */
#ifndef RP_LCM_IMAGE_H
#define RP_LCM_IMAGE_H

#include <stdint.h>
#include <string.h>

#include "rigpose_image_t.h"

/* Offset of image_t's size field in an encoded message (after the 8-byte fingerprint), or -1 if
 * the encoding is not the one this check knows (size last but for data). */
static inline int rp_image_t_size_offset(void)
{
    static int at = -2;
    if (at == -2) {
        uint8_t data[3] = {1, 2, 3}, buf[128];
        rigpose_image_t m;
        memset(&m, 0, sizeof m);
        m.size = 3;
        m.data = data;
        const int n = rigpose_image_t_encoded_size(&m);
        at = -1;
        if (n > 7 + 4 && n <= (int)sizeof buf && rigpose_image_t_encode(buf, 0, n, &m) == n &&
            buf[n - 7] == 0 && buf[n - 6] == 0 && buf[n - 5] == 0 && buf[n - 4] == 3 &&
            memcmp(buf + n - 3, data, 3) == 0) {
            at = n - 7;
        }
    }
    return at;
}

/* rigpose_image_t_decode(buf, 0, len, m) when the size field is in 1..(len - its end); -1
 * otherwise (m untouched). On success the caller calls rigpose_image_t_decode_cleanup(m). */
static inline int rp_image_t_decode_checked(const void *buf, int len, rigpose_image_t *m)
{
    const int at = rp_image_t_size_offset();
    const uint8_t *b = (const uint8_t *)buf;
    if (at < 0 || len < at + 4) {
        return -1;
    }
    const int32_t size = (int32_t)((uint32_t)b[at] << 24 | (uint32_t)b[at + 1] << 16 |
                                   (uint32_t)b[at + 2] << 8 | (uint32_t)b[at + 3]);
    if (size < 1 || size > len - (at + 4)) {
        return -1;
    }
    return rigpose_image_t_decode(buf, 0, len, m);
}

#endif /* RP_LCM_IMAGE_H */
