/* rp_status.c - status texts. */
#include "rigpose/rp_status.h"

const char *rp_status_str(rp_status_t s)
{
    static const char *const text[RP_E_COUNT_] = {
        [RP_OK] = "ok",
        [RP_E_ARG] = "bad argument",
        [RP_E_NAN] = "non-finite input",
        [RP_E_BEHIND] = "point behind camera",
        [RP_E_SINGULAR] = "singular matrix",
        [RP_E_NO_CONVERGE] = "did not converge",
        [RP_E_TOO_FEW] = "too few features",
        [RP_E_FULL] = "table full",
        [RP_E_DIVERGED] = "filter fault (reset)",
        [RP_E_RANGE] = "value out of range",
        [RP_E_OUTSIDE] = "outside the image",
        [RP_E_DEGENERATE] = "degenerate geometry",
        [RP_E_NOT_FOUND] = "not found",
    };
    if ((unsigned)s >= (unsigned)RP_E_COUNT_) {
        return "unknown status";
    }
    return text[s];
}
