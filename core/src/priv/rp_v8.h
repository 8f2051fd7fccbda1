/*
 * rp_v8.h - 8-lane int16 vectors for the image kernels (private to core/src).
 */
#ifndef RP_PRIV_V8_H
#define RP_PRIV_V8_H

#include <stdint.h>
#include <string.h>

/* The image kernels of the front end (rp_track.c, rp_smatch.c) work on 8 int16 lanes at a time
 * through the few v8_* / v4_* operations here. With GCC or Clang on SSE2 (x86) or NEON (aarch64)
 * a lane group is a GCC vector (`vector_size(16)`), so the arithmetic compiles to single SIMD
 * instructions; elsewhere, or when RP_V8_SCALAR is defined, it is a struct of 8 int16 and each
 * operation a plain C loop. Every operation is exact integer arithmetic on values the callers
 * keep in range (no lane wraps), so both forms give bit-identical results (tests/unit/test_track.c
 * and test_smatch.c build their module again with RP_V8_SCALAR and compare). */
#if !defined(RP_V8_SCALAR) && (defined(__GNUC__) || defined(__clang__)) &&                      \
    (defined(__SSE2__) || (defined(__ARM_NEON) && defined(__aarch64__)))
#define RP_V8_VEC 1
#if defined(__SSE2__)
#include <emmintrin.h>
#else
#include <arm_neon.h>
#endif
typedef int16_t v8_t __attribute__((vector_size(16)));
typedef int32_t v4_t __attribute__((vector_size(16)));

static inline v8_t v8_set(int16_t x) { return (v8_t){x, x, x, x, x, x, x, x}; }
static inline v8_t v8_ld(const int16_t *p)
{
    v8_t a;
    memcpy(&a, p, sizeof(a));
    return a;
}
static inline void v8_st(int16_t *p, v8_t a) { memcpy(p, &a, sizeof(a)); }
static inline v8_t v8_add(v8_t a, v8_t b) { return a + b; }
static inline v8_t v8_sub(v8_t a, v8_t b) { return a - b; }
static inline v8_t v8_mul(v8_t a, v8_t b) { return a * b; }
static inline v8_t v8_and(v8_t a, v8_t b) { return a & b; }
static inline v8_t v8_xor(v8_t a, v8_t b) { return a ^ b; }
static inline v8_t v8_sra(v8_t a, int k) { return a >> k; }
/* 8 grey levels widened to int16 */
static inline v8_t v8_ld_u8(const uint8_t *p)
{
#if defined(__SSE2__)
    return (v8_t)_mm_unpacklo_epi8(_mm_loadl_epi64((const __m128i *)(const void *)p),
                                   _mm_setzero_si128());
#else
    return (v8_t)vreinterpretq_s16_u16(vmovl_u8(vld1_u8(p)));
#endif
}
/* lane pairs' products summed: r[i] = a[2i] b[2i] + a[2i+1] b[2i+1] (int32) */
static inline v4_t v8_madd(v8_t a, v8_t b)
{
#if defined(__SSE2__)
    return (v4_t)_mm_madd_epi16((__m128i)a, (__m128i)b);
#else
    return vpaddq_s32(vmull_s16(vget_low_s16((int16x8_t)a), vget_low_s16((int16x8_t)b)),
                      vmull_high_s16((int16x8_t)a, (int16x8_t)b));
#endif
}
/* the 8 int32 products a[i] b[i] into out[0..7] */
static inline void v8_mul_wide(v8_t a, v8_t b, int32_t *out)
{
#if defined(__SSE2__)
    const __m128i lo = _mm_mullo_epi16((__m128i)a, (__m128i)b);
    const __m128i hi = _mm_mulhi_epi16((__m128i)a, (__m128i)b);
    const __m128i p0 = _mm_unpacklo_epi16(lo, hi), p1 = _mm_unpackhi_epi16(lo, hi);
    memcpy(out, &p0, sizeof(p0));
    memcpy(out + 4, &p1, sizeof(p1));
#else
    const int32x4_t p0 = vmull_s16(vget_low_s16((int16x8_t)a), vget_low_s16((int16x8_t)b));
    const int32x4_t p1 = vmull_high_s16((int16x8_t)a, (int16x8_t)b);
    memcpy(out, &p0, sizeof(p0));
    memcpy(out + 4, &p1, sizeof(p1));
#endif
}
static inline v4_t v4_zero(void) { return (v4_t){0, 0, 0, 0}; }
static inline v4_t v4_ld(const int32_t *p)
{
    v4_t a;
    memcpy(&a, p, sizeof(a));
    return a;
}
static inline void v4_st(int32_t *p, v4_t a) { memcpy(p, &a, sizeof(a)); }
static inline v4_t v4_add(v4_t a, v4_t b) { return a + b; }
static inline int64_t v4_sum(v4_t a) { return (int64_t)a[0] + a[1] + a[2] + a[3]; }
#else
#define RP_V8_VEC 0
typedef struct {
    int16_t e[8];
} v8_t;
typedef struct {
    int32_t e[4];
} v4_t;

static inline v8_t v8_set(int16_t x)
{
    v8_t r;
    for (int i = 0; i < 8; ++i) {
        r.e[i] = x;
    }
    return r;
}
static inline v8_t v8_ld(const int16_t *p)
{
    v8_t r;
    memcpy(r.e, p, sizeof(r.e));
    return r;
}
static inline void v8_st(int16_t *p, v8_t a) { memcpy(p, a.e, sizeof(a.e)); }
/* Lane-wise a OP b, wrapping to int16 like the vector instructions. */
#define RP_V8_BINOP(name, OP)                                                                  \
    static inline v8_t name(v8_t a, v8_t b)                                                    \
    {                                                                                          \
        for (int i = 0; i < 8; ++i) {                                                          \
            a.e[i] = (int16_t)(a.e[i] OP b.e[i]);                                              \
        }                                                                                      \
        return a;                                                                              \
    }
RP_V8_BINOP(v8_add, +)
RP_V8_BINOP(v8_sub, -)
RP_V8_BINOP(v8_mul, *)
RP_V8_BINOP(v8_and, &)
RP_V8_BINOP(v8_xor, ^)
#undef RP_V8_BINOP
static inline v8_t v8_sra(v8_t a, int k)
{
    for (int i = 0; i < 8; ++i) {
        a.e[i] = (int16_t)(a.e[i] >> k);
    }
    return a;
}
static inline v8_t v8_ld_u8(const uint8_t *p)
{
    v8_t r;
    for (int i = 0; i < 8; ++i) {
        r.e[i] = p[i];
    }
    return r;
}
static inline v4_t v8_madd(v8_t a, v8_t b)
{
    v4_t r;
    for (int i = 0; i < 4; ++i) {
        r.e[i] = a.e[2 * i] * b.e[2 * i] + a.e[2 * i + 1] * b.e[2 * i + 1];
    }
    return r;
}
static inline void v8_mul_wide(v8_t a, v8_t b, int32_t *out)
{
    for (int i = 0; i < 8; ++i) {
        out[i] = a.e[i] * b.e[i];
    }
}
static inline v4_t v4_zero(void)
{
    v4_t r = {{0, 0, 0, 0}};
    return r;
}
static inline v4_t v4_ld(const int32_t *p)
{
    v4_t r;
    memcpy(r.e, p, sizeof(r.e));
    return r;
}
static inline void v4_st(int32_t *p, v4_t a) { memcpy(p, a.e, sizeof(a.e)); }
static inline v4_t v4_add(v4_t a, v4_t b)
{
    for (int i = 0; i < 4; ++i) {
        a.e[i] += b.e[i];
    }
    return a;
}
static inline int64_t v4_sum(v4_t a) { return (int64_t)a.e[0] + a.e[1] + a.e[2] + a.e[3]; }
#endif

/* |a| per lane (a > -32768) */
static inline v8_t v8_abs(v8_t a)
{
    const v8_t s = v8_sra(a, 15); /* -1 where negative */
    return v8_sub(v8_xor(a, s), s);
}

#endif /* RP_PRIV_V8_H */
