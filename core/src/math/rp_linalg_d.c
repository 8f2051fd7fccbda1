/*
 * rp_linalg_d.c - double-precision dense Cholesky on raw row-major arrays (rp_linalg.h), for the
 * core's solvers that need double whatever rp_real is. One implementation for both backends.
 */
#include <math.h>
#include <stddef.h>

#include "rigpose/rp_linalg.h"

rp_status_t rp_la_chol_d(double *A, int n)
{
    if (A == NULL || n < 1 || n > RP_LA_D_MAX_DIM) {
        return RP_E_ARG;
    }
    for (int j = 0; j < n; ++j) {
        double d = A[j * n + j];
        for (int k = 0; k < j; ++k) {
            d -= A[j * n + k] * A[j * n + k];
        }
        if (!(d > 0.0)) {
            return RP_E_SINGULAR;
        }
        d = sqrt(d);
        A[j * n + j] = d;
        for (int i = j + 1; i < n; ++i) {
            double s = A[i * n + j];
            for (int k = 0; k < j; ++k) {
                s -= A[i * n + k] * A[j * n + k];
            }
            A[i * n + j] = s / d;
        }
    }
    return RP_OK;
}

/* Forward substitution L y = b, then back substitution L^T x = y, in place in x. */
rp_status_t rp_la_chol_solve_d(const double *L, int n, const double *b, double *x)
{
    if (L == NULL || b == NULL || x == NULL || n < 1 || n > RP_LA_D_MAX_DIM) {
        return RP_E_ARG;
    }
    for (int i = 0; i < n; ++i) {
        double s = b[i];
        for (int k = 0; k < i; ++k) {
            s -= L[i * n + k] * x[k];
        }
        x[i] = s / L[i * n + i];
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = x[i];
        for (int k = i + 1; k < n; ++k) {
            s -= L[k * n + i] * x[k];
        }
        x[i] = s / L[i * n + i];
    }
    return RP_OK;
}
