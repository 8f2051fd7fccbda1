/*
 * rp_sym3.h - a symmetric 3x3 (a point's covariance) between its packed form
 * c = [xx xy xz yy yz zz] (rp_point3_t.C) and the full row-major 3x3; packing averages the two
 * off-diagonal halves, so a product that lost symmetry to rounding is stored symmetric.
 */
#ifndef RP_PRIV_SYM3_H
#define RP_PRIV_SYM3_H

#include "rigpose/rp_opts.h"

static inline void rp_sym3_unpack(const rp_real c[6], rp_real C[9])
{
    C[0] = c[0]; C[1] = c[1]; C[2] = c[2];
    C[3] = c[1]; C[4] = c[3]; C[5] = c[4];
    C[6] = c[2]; C[7] = c[4]; C[8] = c[5];
}

static inline void rp_sym3_pack(const rp_real C[9], rp_real c[6])
{
    c[0] = C[0];
    c[1] = RP_C(0.5) * (C[1] + C[3]);
    c[2] = RP_C(0.5) * (C[2] + C[6]);
    c[3] = C[4];
    c[4] = RP_C(0.5) * (C[5] + C[7]);
    c[5] = C[8];
}

#endif /* RP_PRIV_SYM3_H */
