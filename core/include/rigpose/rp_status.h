/*
 * rp_status.h - the one status type of rigpose. 0 is success; each failure has its own value.
 * Every public core function that can fail returns an rp_status_t; outputs go through pointers.
 */
#ifndef RP_STATUS_H
#define RP_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    RP_OK = 0,
    RP_E_ARG,         /* null pointer, size out of range, index out of range, bad option value */
    RP_E_NAN,         /* an input (pixel, point, state) is not finite */
    RP_E_BEHIND,      /* a point lies at or behind the camera (depth < RP_MIN_DEPTH) */
    RP_E_SINGULAR,    /* matrix singular / not positive definite / rank deficient */
    RP_E_NO_CONVERGE, /* an iteration did not converge within its limit */
    RP_E_TOO_FEW,     /* too few features / measurements / equations for the job */
    RP_E_FULL,        /* a fixed-capacity table is full; the item was not stored */
    RP_E_DIVERGED,    /* a filter fault: covariance not SPD or state non-finite; state was reset */
    RP_E_RANGE,       /* a value outside its accepted range (e.g. triangulated depth) */
    RP_E_OUTSIDE,     /* a point projects outside the image */
    RP_E_DEGENERATE,  /* geometry that does not determine the answer (e.g. zero baseline) */
    RP_E_NOT_FOUND,   /* a looked-up key (e.g. a feature id) is not held */
    RP_E_COUNT_       /* number of codes; not a status */
} rp_status_t;

/* Short constant text for a status ("ok", "bad argument", ...); never NULL. */
const char *rp_status_str(rp_status_t s);

#ifdef __cplusplus
}
#endif

#endif /* RP_STATUS_H */
