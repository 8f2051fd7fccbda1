/*
 * rp_esc.h - messages that cannot move a terminal: the HAL's and the configuration
 * parser's messages echo values read from files (paths in frames.csv, YAML scalars), so every
 * message passes through rp_esc_text before anyone prints it.
 */
#ifndef RP_ESC_H
#define RP_ESC_H

#include <stddef.h>

/* Length of the valid UTF-8 sequence at s that is not a C1 control (U+0080..U+009F), else 0. */
static inline size_t rp_esc_utf8_len(const unsigned char *s)
{
    const unsigned char b = s[0];
    size_t n;
    unsigned char lo = 0x80, hi = 0xBF; /* allowed range of the first continuation byte */
    if (b >= 0xC2 && b <= 0xDF) {
        n = 2;
        lo = b == 0xC2 ? 0xA0 : 0x80; /* C2 80..C2 9F are the C1 controls */
    } else if (b >= 0xE0 && b <= 0xEF) {
        n = 3;
        lo = b == 0xE0 ? 0xA0 : 0x80; /* no overlong forms */
        hi = b == 0xED ? 0x9F : 0xBF; /* no surrogates */
    } else if (b >= 0xF0 && b <= 0xF4) {
        n = 4;
        lo = b == 0xF0 ? 0x90 : 0x80;
        hi = b == 0xF4 ? 0x8F : 0xBF;
    } else {
        return 0;
    }
    if (s[1] < lo || s[1] > hi) {
        return 0;
    }
    for (size_t k = 2; k < n; ++k) {
        if (s[k] < 0x80 || s[k] > 0xBF) {
            return 0;
        }
    }
    return n;
}

/* src into dst (cap > 0 bytes, always NUL-terminated, cut at a whole character) with every byte
 * that a terminal could act on written as \xNN: C0 controls (newline, tab, escape...), DEL, the
 * C1 controls in UTF-8 and bytes that are not valid UTF-8. Printable ASCII and valid UTF-8 text
 * are copied as they are. */
static inline void rp_esc_text(char *dst, size_t cap, const char *src)
{
    static const char hex[] = "0123456789abcdef";
    const unsigned char *s = (const unsigned char *)src;
    size_t o = 0;
    while (*s != '\0') {
        if (*s >= 0x20 && *s < 0x7F) {
            if (o + 1 >= cap) {
                break;
            }
            dst[o++] = (char)*s++;
            continue;
        }
        const size_t n = *s >= 0x80 ? rp_esc_utf8_len(s) : 0;
        if (n > 0) {
            if (o + n >= cap) {
                break;
            }
            for (size_t k = 0; k < n; ++k) {
                dst[o++] = (char)*s++;
            }
            continue;
        }
        if (o + 4 >= cap) {
            break;
        }
        dst[o++] = '\\';
        dst[o++] = 'x';
        dst[o++] = hex[*s >> 4];
        dst[o++] = hex[*s & 15];
        s++;
    }
    dst[o] = '\0';
}

#endif /* RP_ESC_H */
