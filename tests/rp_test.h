/*
 * rp_test.h - what every rigpose test file shares: cmocka, and tolerances per scalar type.
 */
#ifndef RP_TEST_H
#define RP_TEST_H

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <cmocka.h>

#include "rigpose/rp_opts.h"
#include "rigpose/rp_status.h"
#include "rp_sim.h"

/* Uniform in [a, b) from the simulator's generator, seeded once per test program (tests are
 * deterministic). */
static inline double rp_test_urand(double a, double b)
{
    static rp_rng_t rng;
    static int seeded = 0;
    if (!seeded) {
        rp_rng_seed(&rng, 0x5eedu);
        seeded = 1;
    }
    return a + (b - a) * rp_rng_uniform(&rng);
}

/* Tolerance that means "exact up to rounding" for this build's scalar type. */
#if RP_REAL_IS_FLOAT
#define RP_TOL_TIGHT 1e-4
#define RP_TOL_LOOSE 1e-2
#else
#define RP_TOL_TIGHT 1e-9
#define RP_TOL_LOOSE 1e-6
#endif

/* Pick a tolerance per scalar type: RP_TOL(1e-9, 1e-4). */
#if RP_REAL_IS_FLOAT
#define RP_TOL(d, f) (f)
#else
#define RP_TOL(d, f) (d)
#endif

#define assert_status(expr, want)                                                              \
    do {                                                                                       \
        rp_status_t st_ = (expr);                                                              \
        if (st_ != (want)) {                                                                   \
            fail_msg("%s returned %s (%d), wanted %s", #expr, rp_status_str(st_), (int)st_,     \
                     rp_status_str(want));                                                     \
        }                                                                                      \
    } while (0)

#define assert_ok(expr) assert_status((expr), RP_OK)

/* |a - b| <= tol, with the values in the message. */
#define assert_near(a, b, tol)                                                                 \
    do {                                                                                       \
        double a_ = (double)(a), b_ = (double)(b), t_ = (double)(tol);                         \
        if (!(fabs(a_ - b_) <= t_)) {                                                          \
            fail_msg("%s = %.12g, %s = %.12g, |diff| %.3g > %.3g", #a, a_, #b, b_,             \
                     fabs(a_ - b_), t_);                                                       \
        }                                                                                      \
    } while (0)

#endif /* RP_TEST_H */
