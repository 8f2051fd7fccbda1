/*
 * rp_linalg.h - small dense linear algebra on caller-owned matrix views (CMSIS-DSP style).
 *
 * A view is {rows, cols, data}: row-major, contiguous (element (i,j) at data[i*cols + j]).
 * One operation per function; every function returns RP_OK or an error and never allocates.
 *
 * Two implementations exist and are always both compiled (so tests can hold them to each
 * other): rp_lac_* (plain C, rp_linalg_c.c) and rp_lae_* (thin C++ shim over Eigen fixed-size /
 * bounded-size matrices, rp_linalg_eigen.cpp, EIGEN_NO_MALLOC, no exceptions). The rp_la_* names
 * the rest of the core uses map to one of them at build time through RP_LINALG_EIGEN.
 *
 * Common errors: RP_E_ARG for a NULL view or data pointer, mismatched sizes, a decomposition
 * input with more than RP_LA_MAX_DIM rows or columns, or an output that aliases an input where
 * the function says it must not.
 */
#ifndef RP_LINALG_H
#define RP_LINALG_H

#include "rp_opts.h"
#include "rp_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint16_t rows;
    uint16_t cols;
    rp_real *data; /* rows*cols elements, row-major */
} rp_mat_t;

/* Build a view in an expression: rp_la_mul(&RP_MAT(3, 3, a), ...). */
#define RP_MAT(r, c, ptr) ((rp_mat_t){(uint16_t)(r), (uint16_t)(c), (ptr)})

/* The operations, declared once for each backend (PFX = rp_lac_ or rp_lae_). */
#define RP_LA_DECLARE(PFX)                                                                      \
    /* c = a b. c must not alias a or b. */                                                     \
    rp_status_t PFX##mul(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c);                    \
    /* c = a^T b. c must not alias a or b. */                                                   \
    rp_status_t PFX##mul_at_b(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c);               \
    /* c = a b^T. c must not alias a or b. */                                                   \
    rp_status_t PFX##mul_a_bt(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c);               \
    /* c = a + b; c may alias a or b. */                                                        \
    rp_status_t PFX##add(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c);                    \
    /* c = a - b; c may alias a or b. */                                                        \
    rp_status_t PFX##sub(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c);                    \
    /* c = s a; c may alias a. */                                                               \
    rp_status_t PFX##scale(const rp_mat_t *a, rp_real s, rp_mat_t *c);                          \
    /* c = a^T. c must not alias a. */                                                          \
    rp_status_t PFX##transpose(const rp_mat_t *a, rp_mat_t *c);                                 \
    /* Cholesky: a = l l^T, l lower triangular (upper part zeroed). a square, symmetric (only   \
     * its lower triangle is read). RP_E_SINGULAR if a is not positive definite. l may alias a.*/\
    rp_status_t PFX##chol(const rp_mat_t *a, rp_mat_t *l);                                      \
    /* Solve (l l^T) x = b for x given the Cholesky factor l; b may have several columns;      \
     * x may alias b. RP_E_SINGULAR on a zero diagonal. */                                      \
    rp_status_t PFX##chol_solve(const rp_mat_t *l, const rp_mat_t *b, rp_mat_t *x);             \
    /* ainv = a^-1 for symmetric positive definite a (result exactly symmetric).              \
     * RP_E_SINGULAR if a is not positive definite. ainv may alias a. */                        \
    rp_status_t PFX##inv_spd(const rp_mat_t *a, rp_mat_t *ainv);                                \
    /* Linear least squares min ||a x - b||_2 by Householder QR; a is m x n with m >= n,       \
     * b is m x k, x is n x k. RP_E_SINGULAR if a is rank deficient (|R_ii| <= 1e-10 *         \
     * max |R_jj| in double, 1e-5 in float). RP_E_TOO_FEW if m < n. */                          \
    rp_status_t PFX##lstsq(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *x);                  \
    /* Thin SVD a = u diag(s) v^T of an m x n matrix with m >= n: u m x n, s n x 1 (descending,\
     * non-negative), v n x n. u may be NULL when not wanted. RP_E_NO_CONVERGE if the          \
     * iteration does not converge. */                                                          \
    rp_status_t PFX##svd(const rp_mat_t *a, rp_mat_t *u, rp_mat_t *s, rp_mat_t *v);

RP_LA_DECLARE(rp_lac_)
RP_LA_DECLARE(rp_lae_)

#if RP_LINALG_EIGEN
#define RP_LA_PFX(name) rp_lae_##name
#else
#define RP_LA_PFX(name) rp_lac_##name
#endif

#define rp_la_mul       RP_LA_PFX(mul)
#define rp_la_mul_at_b  RP_LA_PFX(mul_at_b)
#define rp_la_mul_a_bt  RP_LA_PFX(mul_a_bt)
#define rp_la_add       RP_LA_PFX(add)
#define rp_la_sub       RP_LA_PFX(sub)
#define rp_la_scale     RP_LA_PFX(scale)
#define rp_la_transpose RP_LA_PFX(transpose)
#define rp_la_chol      RP_LA_PFX(chol)
#define rp_la_chol_solve RP_LA_PFX(chol_solve)
#define rp_la_inv_spd   RP_LA_PFX(inv_spd)
#define rp_la_lstsq     RP_LA_PFX(lstsq)
#define rp_la_svd       RP_LA_PFX(svd)

/* Double precision on every build (rp_linalg_d.c, one plain-C implementation), for solvers whose
 * normal equations need it whatever rp_real is (gc's window adjustment, rp_gcba.h says why).
 * A is n x n row-major, n <= RP_LA_D_MAX_DIM.
 * rp_la_chol_d: in-place Cholesky A = L L^T, the lower triangle read and overwritten by L (the
 *   upper left as it was). RP_E_SINGULAR if A is not positive definite (a pivot <= 0 or NaN),
 *   RP_E_ARG for NULL or n out of 1..RP_LA_D_MAX_DIM.
 * rp_la_chol_solve_d: x = (L L^T)^-1 b from rp_la_chol_d's L; x may alias b. RP_E_ARG as above. */
#define RP_LA_D_MAX_DIM 192
rp_status_t rp_la_chol_d(double *A, int n);
rp_status_t rp_la_chol_solve_d(const double *L, int n, const double *b, double *x);

#ifdef __cplusplus
}
#endif

#endif /* RP_LINALG_H */
