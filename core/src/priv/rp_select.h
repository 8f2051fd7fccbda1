/*
 * rp_select.h - quickselect (Hoare's partition), one body for every key type: the layouts pick
 * the lowest values of a scratch array without sorting it (no heap).
 */
#ifndef RP_SELECT_H
#define RP_SELECT_H

#include <stdint.h>

/* Defines `static void name(T *h, uint16_t *idx, int n, int want)`: reorders h[0..n) (and
 * idx with it, when idx is not NULL) so that its `want` lowest values come first and
 * h[want - 1] is the want-th smallest (1 <= want <= n). */
#define RP_DEFINE_SELECT_LOWEST(name, T)                                                       \
    static void name(T *h, uint16_t *idx, int n, int want)                                     \
    {                                                                                          \
        int lo = 0, hi = n - 1;                                                                \
        const int k = want - 1;                                                                \
        while (lo < hi) {                                                                      \
            const T pivot = h[(lo + hi) / 2];                                                  \
            int i = lo, j = hi;                                                                \
            while (i <= j) {                                                                   \
                while (h[i] < pivot) {                                                         \
                    i++;                                                                       \
                }                                                                              \
                while (h[j] > pivot) {                                                         \
                    j--;                                                                       \
                }                                                                              \
                if (i <= j) {                                                                  \
                    const T th = h[i];                                                         \
                    h[i] = h[j];                                                               \
                    h[j] = th;                                                                 \
                    if (idx) {                                                                 \
                        const uint16_t ti = idx[i];                                            \
                        idx[i] = idx[j];                                                       \
                        idx[j] = ti;                                                           \
                    }                                                                          \
                    i++;                                                                       \
                    j--;                                                                       \
                }                                                                              \
            }                                                                                  \
            if (k <= j) {                                                                      \
                hi = j;                                                                        \
            } else if (k >= i) {                                                               \
                lo = i;                                                                        \
            } else {                                                                           \
                break;                                                                         \
            }                                                                                  \
        }                                                                                      \
    }

#endif /* RP_SELECT_H */
