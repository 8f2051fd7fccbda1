/*
 * rp_inv3.h - the inverse of a symmetric positive definite 3x3 by its adjugate, written once
 * for any scalar type: RP_DEFINE_INV3_SPD(name, T) defines
 *   static int name(const T A[9], T Ai[9])
 * (row-major), which returns 1, or 0 with Ai untouched when A is not positive definite (a
 * leading minor or the determinant not > 0) or the determinant is not finite. rp_struct uses it
 * in rp_real, rp_gcba in double.
 */
#ifndef RP_PRIV_INV3_H
#define RP_PRIV_INV3_H

#include <math.h>

#define RP_DEFINE_INV3_SPD(NAME, T)                                                            \
    static int NAME(const T A[9], T Ai[9])                                                     \
    {                                                                                          \
        const T c00 = A[4] * A[8] - A[5] * A[7];                                               \
        const T c01 = A[5] * A[6] - A[3] * A[8];                                               \
        const T c02 = A[3] * A[7] - A[4] * A[6];                                               \
        const T det = A[0] * c00 + A[1] * c01 + A[2] * c02;                                    \
        const T minor2 = A[0] * A[4] - A[1] * A[3];                                            \
        if (!(A[0] > (T)0) || !(minor2 > (T)0) || !(det > (T)0) || !isfinite(det)) {           \
            return 0;                                                                          \
        }                                                                                      \
        const T id = (T)1 / det;                                                               \
        Ai[0] = c00 * id;                                                                      \
        Ai[1] = (A[2] * A[7] - A[1] * A[8]) * id;                                              \
        Ai[2] = (A[1] * A[5] - A[2] * A[4]) * id;                                              \
        Ai[3] = c01 * id;                                                                      \
        Ai[4] = (A[0] * A[8] - A[2] * A[6]) * id;                                              \
        Ai[5] = (A[2] * A[3] - A[0] * A[5]) * id;                                              \
        Ai[6] = c02 * id;                                                                      \
        Ai[7] = (A[1] * A[6] - A[0] * A[7]) * id;                                              \
        Ai[8] = minor2 * id;                                                                   \
        return 1;                                                                              \
    }

#endif /* RP_PRIV_INV3_H */
