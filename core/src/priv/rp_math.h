/*
 * priv/rp_math.h - libm for the build's scalar type (sinf in float builds, sin in double), so
 * that no expression of the estimator is silently promoted to double. Core-internal.
 */
#ifndef RP_PRIV_MATH_H
#define RP_PRIV_MATH_H

#include <math.h>

#include "rigpose/rp_opts.h"

#if RP_REAL_IS_FLOAT
#define rp_sin   sinf
#define rp_cos   cosf
#define rp_tan   tanf
#define rp_asin  asinf
#define rp_acos  acosf
#define rp_atan2 atan2f
#define rp_sqrt  sqrtf
#define rp_fabs  fabsf
#define rp_floor floorf
#define rp_exp   expf
#define rp_log   logf
#else
#define rp_sin   sin
#define rp_cos   cos
#define rp_tan   tan
#define rp_asin  asin
#define rp_acos  acos
#define rp_atan2 atan2
#define rp_sqrt  sqrt
#define rp_fabs  fabs
#define rp_floor floor
#define rp_exp   exp
#define rp_log   log
#endif

#define RP_PI RP_C(3.14159265358979323846)

/* 1 if x is finite (not NaN, not +-inf). */
static inline int rp_finite(rp_real x) { return isfinite(x); }

/* 1 if all n values are finite. */
static inline int rp_all_finite(const rp_real *x, unsigned n)
{
    for (unsigned i = 0; i < n; ++i) {
        if (!isfinite(x[i])) {
            return 0;
        }
    }
    return 1;
}

#endif /* RP_PRIV_MATH_H */
