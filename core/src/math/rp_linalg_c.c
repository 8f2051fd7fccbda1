/*
 * rp_linalg_c.c - plain-C backend of rp_linalg.h (rp_lac_*).
 *
 * Conventions shared with the Eigen backend (rp_linalg_eigen.cpp), so that the two agree:
 * - A view is usable when the pointer and its data are non-NULL and rows, cols >= 1; anything
 *   else is RP_E_ARG.
 * - "May alias" means the very same data pointer; a partial overlap is always RP_E_ARG.
 * - Decompositions (chol, chol_solve, inv_spd, lstsq, svd) accept at most RP_LA_MAX_DIM rows and
 *   columns in the matrix they factor, work in fixed-size stack arrays, and reject non-finite
 *   input with RP_E_NAN. Their right-hand sides (b in chol_solve, lstsq) may have any number of
 *   columns: they are processed one column at a time.
 * - On any error the outputs are left unchanged.
 * - lstsq factors a with column-pivoted Householder QR, a P = Q R, and calls a rank deficient
 *   when |R_ii| <= tol * max_j |R_jj| (tol = 1e-10 double, 1e-5 float; with pivoting the max is
 *   |R_00|).
 * - svd is one-sided (Hestenes) Jacobi: column pairs of a are rotated until all are orthogonal;
 *   the column norms are the singular values.
 */
#include <stddef.h>
#include <stdint.h>

#include "priv/rp_math.h"
#include "rigpose/rp_linalg.h"

#if RP_REAL_IS_FLOAT
#define LAC_RANK_TOL RP_C(1e-5)
#else
#define LAC_RANK_TOL RP_C(1e-10)
#endif

/* Sweeps of one-sided Jacobi before RP_E_NO_CONVERGE; n <= 16 converges in well under 20. */
#define LAC_SVD_MAX_SWEEPS 60

#define LAC_WS (RP_LA_MAX_DIM * RP_LA_MAX_DIM)

/* ---- view checks ------------------------------------------------------------------------- */

static int lac_usable(const rp_mat_t *m)
{
    return m != NULL && m->data != NULL && m->rows > 0 && m->cols > 0;
}

static size_t lac_count(const rp_mat_t *m) { return (size_t)m->rows * m->cols; }

static int lac_same_shape(const rp_mat_t *a, const rp_mat_t *b)
{
    return a->rows == b->rows && a->cols == b->cols;
}

/* 1 if the element ranges of a and b share memory. */
static int lac_overlap(const rp_mat_t *a, const rp_mat_t *b)
{
    uintptr_t a0 = (uintptr_t)a->data, a1 = (uintptr_t)(a->data + lac_count(a));
    uintptr_t b0 = (uintptr_t)b->data, b1 = (uintptr_t)(b->data + lac_count(b));
    return a0 < b1 && b0 < a1;
}

/* 1 if out overlaps in other than by being exactly the same storage. */
static int lac_bad_alias(const rp_mat_t *in, const rp_mat_t *out)
{
    return in->data != out->data && lac_overlap(in, out);
}

static int lac_decomp_size_ok(const rp_mat_t *m)
{
    return m->rows <= RP_LA_MAX_DIM && m->cols <= RP_LA_MAX_DIM;
}

/* 1 if every element of the lower triangle (diagonal included) of the n x n matrix is finite. */
static int lac_lower_finite(const rp_real *a, unsigned n)
{
    for (unsigned i = 0; i < n; ++i) {
        if (!rp_all_finite(a + (size_t)i * n, i + 1)) {
            return 0;
        }
    }
    return 1;
}

/* Euclidean norm of n values spaced by stride, scaled by the largest so it cannot overflow. */
static rp_real lac_norm(const rp_real *x, unsigned n, unsigned stride)
{
    rp_real amax = RP_C(0);
    for (unsigned i = 0; i < n; ++i) {
        rp_real v = rp_fabs(x[(size_t)i * stride]);
        if (v > amax) {
            amax = v;
        }
    }
    if (amax == RP_C(0)) {
        return RP_C(0);
    }
    rp_real ss = RP_C(0);
    for (unsigned i = 0; i < n; ++i) {
        rp_real v = x[(size_t)i * stride] / amax;
        ss += v * v;
    }
    return amax * rp_sqrt(ss);
}

/* ---- products and element-wise ops --------------------------------------------------------- */

rp_status_t rp_lac_mul(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    if (!lac_usable(a) || !lac_usable(b) || !lac_usable(c) || a->cols != b->rows ||
        c->rows != a->rows || c->cols != b->cols || lac_overlap(a, c) || lac_overlap(b, c)) {
        return RP_E_ARG;
    }
    const unsigned m = a->rows, n = a->cols, p = b->cols;
    for (unsigned i = 0; i < m; ++i) {
        for (unsigned j = 0; j < p; ++j) {
            rp_real acc = RP_C(0);
            for (unsigned k = 0; k < n; ++k) {
                acc += a->data[(size_t)i * n + k] * b->data[(size_t)k * p + j];
            }
            c->data[(size_t)i * p + j] = acc;
        }
    }
    return RP_OK;
}

rp_status_t rp_lac_mul_at_b(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    if (!lac_usable(a) || !lac_usable(b) || !lac_usable(c) || a->rows != b->rows ||
        c->rows != a->cols || c->cols != b->cols || lac_overlap(a, c) || lac_overlap(b, c)) {
        return RP_E_ARG;
    }
    const unsigned n = a->rows, m = a->cols, p = b->cols;
    for (unsigned i = 0; i < m; ++i) {
        for (unsigned j = 0; j < p; ++j) {
            rp_real acc = RP_C(0);
            for (unsigned k = 0; k < n; ++k) {
                acc += a->data[(size_t)k * m + i] * b->data[(size_t)k * p + j];
            }
            c->data[(size_t)i * p + j] = acc;
        }
    }
    return RP_OK;
}

rp_status_t rp_lac_mul_a_bt(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    if (!lac_usable(a) || !lac_usable(b) || !lac_usable(c) || a->cols != b->cols ||
        c->rows != a->rows || c->cols != b->rows || lac_overlap(a, c) || lac_overlap(b, c)) {
        return RP_E_ARG;
    }
    const unsigned m = a->rows, n = a->cols, p = b->rows;
    for (unsigned i = 0; i < m; ++i) {
        const rp_real *ai = a->data + (size_t)i * n;
        for (unsigned j = 0; j < p; ++j) {
            const rp_real *bj = b->data + (size_t)j * n;
            rp_real acc = RP_C(0);
            for (unsigned k = 0; k < n; ++k) {
                acc += ai[k] * bj[k];
            }
            c->data[(size_t)i * p + j] = acc;
        }
    }
    return RP_OK;
}

static rp_status_t lac_addsub(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c, rp_real sign)
{
    if (!lac_usable(a) || !lac_usable(b) || !lac_usable(c) || !lac_same_shape(a, b) ||
        !lac_same_shape(a, c) || lac_bad_alias(a, c) || lac_bad_alias(b, c)) {
        return RP_E_ARG;
    }
    const size_t n = lac_count(a);
    for (size_t i = 0; i < n; ++i) {
        c->data[i] = a->data[i] + sign * b->data[i];
    }
    return RP_OK;
}

rp_status_t rp_lac_add(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    return lac_addsub(a, b, c, RP_C(1));
}

rp_status_t rp_lac_sub(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    return lac_addsub(a, b, c, RP_C(-1));
}

rp_status_t rp_lac_scale(const rp_mat_t *a, rp_real s, rp_mat_t *c)
{
    if (!lac_usable(a) || !lac_usable(c) || !lac_same_shape(a, c) || lac_bad_alias(a, c)) {
        return RP_E_ARG;
    }
    const size_t n = lac_count(a);
    for (size_t i = 0; i < n; ++i) {
        c->data[i] = s * a->data[i];
    }
    return RP_OK;
}

rp_status_t rp_lac_transpose(const rp_mat_t *a, rp_mat_t *c)
{
    if (!lac_usable(a) || !lac_usable(c) || c->rows != a->cols || c->cols != a->rows ||
        lac_overlap(a, c)) {
        return RP_E_ARG;
    }
    const unsigned m = a->rows, n = a->cols;
    for (unsigned i = 0; i < m; ++i) {
        for (unsigned j = 0; j < n; ++j) {
            c->data[(size_t)j * m + i] = a->data[(size_t)i * n + j];
        }
    }
    return RP_OK;
}

/* ---- Cholesky -------------------------------------------------------------------------------- */

/*
 * Cholesky-Crout on the lower triangle of the n x n matrix a (row stride n) into l (same
 * layout; only the lower triangle is written):
 *   l_jj = sqrt(a_jj - sum_{k<j} l_jk^2),  l_ij = (a_ij - sum_{k<j} l_ik l_jk) / l_jj  (i > j).
 * RP_E_SINGULAR when a pivot is not > 0 (a not positive definite).
 */
static rp_status_t lac_chol_factor(const rp_real *a, unsigned n, rp_real *l)
{
    for (unsigned j = 0; j < n; ++j) {
        rp_real d = a[(size_t)j * n + j];
        for (unsigned k = 0; k < j; ++k) {
            d -= l[(size_t)j * n + k] * l[(size_t)j * n + k];
        }
        if (!(d > RP_C(0))) {
            return RP_E_SINGULAR;
        }
        const rp_real ljj = rp_sqrt(d);
        l[(size_t)j * n + j] = ljj;
        for (unsigned i = j + 1; i < n; ++i) {
            rp_real s = a[(size_t)i * n + j];
            for (unsigned k = 0; k < j; ++k) {
                s -= l[(size_t)i * n + k] * l[(size_t)j * n + k];
            }
            l[(size_t)i * n + j] = s / ljj;
        }
    }
    return RP_OK;
}

/* Solve (l l^T) y = y in place: forward l z = y, then back l^T y = z. Diagonal must be != 0. */
static void lac_chol_subst(const rp_real *l, unsigned n, rp_real *y)
{
    for (unsigned i = 0; i < n; ++i) {
        rp_real s = y[i];
        for (unsigned k = 0; k < i; ++k) {
            s -= l[(size_t)i * n + k] * y[k];
        }
        y[i] = s / l[(size_t)i * n + i];
    }
    for (unsigned i = n; i-- > 0;) {
        rp_real s = y[i];
        for (unsigned k = i + 1; k < n; ++k) {
            s -= l[(size_t)k * n + i] * y[k];
        }
        y[i] = s / l[(size_t)i * n + i];
    }
}

rp_status_t rp_lac_chol(const rp_mat_t *a, rp_mat_t *l)
{
    if (!lac_usable(a) || !lac_usable(l) || a->rows != a->cols || !lac_same_shape(a, l) ||
        !lac_decomp_size_ok(a)) {
        return RP_E_ARG;
    }
    const unsigned n = a->rows;
    if (!lac_lower_finite(a->data, n)) {
        return RP_E_NAN;
    }
    rp_real w[LAC_WS];
    rp_status_t st = lac_chol_factor(a->data, n, w);
    if (st != RP_OK) {
        return st;
    }
    for (unsigned i = 0; i < n; ++i) {
        for (unsigned j = 0; j < n; ++j) {
            l->data[(size_t)i * n + j] = j <= i ? w[(size_t)i * n + j] : RP_C(0);
        }
    }
    return RP_OK;
}

rp_status_t rp_lac_chol_solve(const rp_mat_t *l, const rp_mat_t *b, rp_mat_t *x)
{
    if (!lac_usable(l) || !lac_usable(b) || !lac_usable(x) || l->rows != l->cols ||
        b->rows != l->rows || !lac_same_shape(b, x) || !lac_decomp_size_ok(l) ||
        lac_bad_alias(b, x)) {
        return RP_E_ARG;
    }
    const unsigned n = l->rows, k = b->cols;
    if (!lac_lower_finite(l->data, n) || !rp_all_finite(b->data, (unsigned)lac_count(b))) {
        return RP_E_NAN;
    }
    rp_real w[LAC_WS];
    for (unsigned i = 0; i < n; ++i) {
        for (unsigned j = 0; j <= i; ++j) {
            w[(size_t)i * n + j] = l->data[(size_t)i * n + j];
        }
        if (w[(size_t)i * n + i] == RP_C(0)) {
            return RP_E_SINGULAR;
        }
    }
    /* x may be b's storage: column c of x only overwrites column c of b, already read. */
    for (unsigned c = 0; c < k; ++c) {
        rp_real y[RP_LA_MAX_DIM];
        for (unsigned i = 0; i < n; ++i) {
            y[i] = b->data[(size_t)i * k + c];
        }
        lac_chol_subst(w, n, y);
        for (unsigned i = 0; i < n; ++i) {
            x->data[(size_t)i * k + c] = y[i];
        }
    }
    return RP_OK;
}

rp_status_t rp_lac_inv_spd(const rp_mat_t *a, rp_mat_t *ainv)
{
    if (!lac_usable(a) || !lac_usable(ainv) || a->rows != a->cols || !lac_same_shape(a, ainv) ||
        !lac_decomp_size_ok(a)) {
        return RP_E_ARG;
    }
    const unsigned n = a->rows;
    if (!lac_lower_finite(a->data, n)) {
        return RP_E_NAN;
    }
    rp_real l[LAC_WS];
    rp_status_t st = lac_chol_factor(a->data, n, l);
    if (st != RP_OK) {
        return st;
    }
    /* m = l^-1 (lower triangular) by forward substitution on the columns of I. */
    rp_real m[LAC_WS];
    for (unsigned c = 0; c < n; ++c) {
        for (unsigned i = 0; i < c; ++i) {
            m[(size_t)i * n + c] = RP_C(0);
        }
        for (unsigned i = c; i < n; ++i) {
            rp_real s = i == c ? RP_C(1) : RP_C(0);
            for (unsigned q = c; q < i; ++q) {
                s -= l[(size_t)i * n + q] * m[(size_t)q * n + c];
            }
            m[(size_t)i * n + c] = s / l[(size_t)i * n + i];
        }
    }
    /* a^-1 = l^-T l^-1: (i, j) = sum_{q >= max(i,j)} m_qi m_qj; lower half, mirrored. */
    for (unsigned i = 0; i < n; ++i) {
        for (unsigned j = 0; j <= i; ++j) {
            rp_real s = RP_C(0);
            for (unsigned q = i; q < n; ++q) {
                s += m[(size_t)q * n + i] * m[(size_t)q * n + j];
            }
            ainv->data[(size_t)i * n + j] = s;
            ainv->data[(size_t)j * n + i] = s;
        }
    }
    return RP_OK;
}

/* ---- least squares ----------------------------------------------------------------------- */

/*
 * Householder reflector H = I - tau v v^T with v_0 = 1 that maps x (n values, stride s) onto
 * beta e_0, beta = -sign(x_0) ||x||. The essential part v_1.. overwrites x_1.., beta goes to x_0.
 * A zero tail gives tau = 0 (H = I) and beta = x_0.
 */
static rp_real lac_householder(rp_real *x, unsigned n, unsigned s)
{
    const rp_real x0 = x[0];
    const rp_real tail = n > 1 ? lac_norm(x + s, n - 1, s) : RP_C(0);
    if (tail == RP_C(0)) {
        return RP_C(0);
    }
    rp_real beta = lac_norm(x, n, s);
    if (x0 >= RP_C(0)) {
        beta = -beta;
    }
    const rp_real inv = RP_C(1) / (x0 - beta);
    for (unsigned i = 1; i < n; ++i) {
        x[(size_t)i * s] *= inv;
    }
    x[0] = beta;
    return (beta - x0) / beta;
}

/* y <- H y for the reflector (v, tau) of lac_householder; v_0 = 1 implied, y and v n long. */
static void lac_reflect(const rp_real *v, unsigned vs, rp_real tau, rp_real *y, unsigned ys,
                        unsigned n)
{
    if (tau == RP_C(0)) {
        return;
    }
    rp_real d = y[0];
    for (unsigned i = 1; i < n; ++i) {
        d += v[(size_t)i * vs] * y[(size_t)i * ys];
    }
    d *= tau;
    y[0] -= d;
    for (unsigned i = 1; i < n; ++i) {
        y[(size_t)i * ys] -= d * v[(size_t)i * vs];
    }
}

rp_status_t rp_lac_lstsq(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *x)
{
    if (!lac_usable(a) || !lac_usable(b) || !lac_usable(x) || b->rows != a->rows ||
        x->rows != a->cols || x->cols != b->cols || !lac_decomp_size_ok(a) ||
        lac_bad_alias(b, x)) {
        return RP_E_ARG;
    }
    const unsigned m = a->rows, n = a->cols, k = b->cols;
    if (m < n) {
        return RP_E_TOO_FEW;
    }
    if (!rp_all_finite(a->data, (unsigned)lac_count(a)) ||
        !rp_all_finite(b->data, (unsigned)lac_count(b))) {
        return RP_E_NAN;
    }
    /* a P = Q R, Q = H_0 .. H_{n-1}; reflector j below the diagonal of column j of w. */
    rp_real w[LAC_WS], tau[RP_LA_MAX_DIM];
    unsigned perm[RP_LA_MAX_DIM];
    for (size_t i = 0; i < lac_count(a); ++i) {
        w[i] = a->data[i];
    }
    for (unsigned j = 0; j < n; ++j) {
        perm[j] = j;
    }
    for (unsigned j = 0; j < n; ++j) {
        /* Pivot: the remaining column with the largest norm below row j (first one on ties). */
        unsigned best = j;
        rp_real best_norm = RP_C(-1);
        for (unsigned c = j; c < n; ++c) {
            rp_real nc = lac_norm(w + (size_t)j * n + c, m - j, n);
            if (nc > best_norm) {
                best_norm = nc;
                best = c;
            }
        }
        if (best != j) {
            for (unsigned i = 0; i < m; ++i) {
                rp_real t = w[(size_t)i * n + j];
                w[(size_t)i * n + j] = w[(size_t)i * n + best];
                w[(size_t)i * n + best] = t;
            }
            unsigned tp = perm[j];
            perm[j] = perm[best];
            perm[best] = tp;
        }
        rp_real *col = w + (size_t)j * n + j;
        tau[j] = lac_householder(col, m - j, n);
        for (unsigned c = j + 1; c < n; ++c) {
            lac_reflect(col, n, tau[j], w + (size_t)j * n + c, n, m - j);
        }
    }
    rp_real rmax = RP_C(0);
    for (unsigned j = 0; j < n; ++j) {
        rp_real r = rp_fabs(w[(size_t)j * n + j]);
        rmax = r > rmax ? r : rmax;
    }
    for (unsigned j = 0; j < n; ++j) {
        if (!(rp_fabs(w[(size_t)j * n + j]) > LAC_RANK_TOL * rmax)) {
            return RP_E_SINGULAR;
        }
    }
    /* Per column of b: y = Q^T b, then R z = y_0..n-1 by back substitution, x = P z. */
    for (unsigned c = 0; c < k; ++c) {
        rp_real y[RP_LA_MAX_DIM];
        for (unsigned i = 0; i < m; ++i) {
            y[i] = b->data[(size_t)i * k + c];
        }
        for (unsigned j = 0; j < n; ++j) {
            lac_reflect(w + (size_t)j * n + j, n, tau[j], y + j, 1, m - j);
        }
        for (unsigned i = n; i-- > 0;) {
            rp_real s = y[i];
            for (unsigned q = i + 1; q < n; ++q) {
                s -= w[(size_t)i * n + q] * y[q];
            }
            y[i] = s / w[(size_t)i * n + i];
        }
        for (unsigned i = 0; i < n; ++i) {
            x->data[(size_t)perm[i] * k + c] = y[i];
        }
    }
    return RP_OK;
}

/* ---- SVD ----------------------------------------------------------------------------------- */

/* Make column c of the m x n matrix u (stride n) a unit vector orthogonal to its columns
 * listed in done[0..nd): the standard basis vector with the largest component left after two
 * Gram-Schmidt passes. Completes u where a singular value is (numerically) zero. */
static void lac_complete_column(rp_real *u, unsigned m, unsigned n, unsigned c,
                                const unsigned *done, unsigned nd)
{
    rp_real best[RP_LA_MAX_DIM];
    rp_real best_norm = RP_C(-1);
    for (unsigned r = 0; r < m; ++r) {
        rp_real e[RP_LA_MAX_DIM];
        for (unsigned i = 0; i < m; ++i) {
            e[i] = i == r ? RP_C(1) : RP_C(0);
        }
        for (unsigned pass = 0; pass < 2; ++pass) {
            for (unsigned q = 0; q < nd; ++q) {
                rp_real d = RP_C(0);
                for (unsigned i = 0; i < m; ++i) {
                    d += u[(size_t)i * n + done[q]] * e[i];
                }
                for (unsigned i = 0; i < m; ++i) {
                    e[i] -= d * u[(size_t)i * n + done[q]];
                }
            }
        }
        rp_real en = lac_norm(e, m, 1);
        if (en > best_norm) {
            best_norm = en;
            for (unsigned i = 0; i < m; ++i) {
                best[i] = e[i] / en;
            }
        }
    }
    for (unsigned i = 0; i < m; ++i) {
        u[(size_t)i * n + c] = best[i];
    }
}

rp_status_t rp_lac_svd(const rp_mat_t *a, rp_mat_t *u, rp_mat_t *s, rp_mat_t *v)
{
    if (!lac_usable(a) || !lac_usable(s) || !lac_usable(v) || (u != NULL && !lac_usable(u)) ||
        !lac_decomp_size_ok(a) || a->rows < a->cols || s->rows != a->cols || s->cols != 1 ||
        v->rows != a->cols || v->cols != a->cols ||
        (u != NULL && !lac_same_shape(u, a)) || lac_overlap(s, v) ||
        (u != NULL && (lac_overlap(u, s) || lac_overlap(u, v)))) {
        return RP_E_ARG;
    }
    const unsigned m = a->rows, n = a->cols;
    if (!rp_all_finite(a->data, (unsigned)lac_count(a))) {
        return RP_E_NAN;
    }
    /* w = a / amax, so that column sums of squares cannot overflow; v starts at I. */
    rp_real w[LAC_WS], vw[LAC_WS];
    rp_real amax = RP_C(0);
    for (size_t i = 0; i < lac_count(a); ++i) {
        rp_real t = rp_fabs(a->data[i]);
        amax = t > amax ? t : amax;
    }
    const rp_real inv_amax = amax > RP_C(0) ? RP_C(1) / amax : RP_C(1);
    for (size_t i = 0; i < lac_count(a); ++i) {
        w[i] = a->data[i] * inv_amax;
    }
    for (unsigned i = 0; i < n; ++i) {
        for (unsigned j = 0; j < n; ++j) {
            vw[(size_t)i * n + j] = i == j ? RP_C(1) : RP_C(0);
        }
    }
    /*
     * Sweep over column pairs (p, q) with alpha = |w_p|^2, beta = |w_q|^2, gamma = w_p . w_q;
     * the rotation [c s; -s c] with zeta = (beta - alpha) / (2 gamma),
     * t = sign(zeta) / (|zeta| + sqrt(1 + zeta^2)), c = 1 / sqrt(1 + t^2), s = c t
     * makes w_p, w_q orthogonal; v accumulates the same rotations (a v = w).
     */
    const rp_real tol = RP_REAL_EPS * (rp_real)m;
    int converged = 0;
    for (unsigned sweep = 0; sweep < LAC_SVD_MAX_SWEEPS && !converged; ++sweep) {
        converged = 1;
        for (unsigned p = 0; p + 1 < n; ++p) {
            for (unsigned q = p + 1; q < n; ++q) {
                rp_real alpha = RP_C(0), beta = RP_C(0), gamma = RP_C(0);
                for (unsigned i = 0; i < m; ++i) {
                    const rp_real wp = w[(size_t)i * n + p], wq = w[(size_t)i * n + q];
                    alpha += wp * wp;
                    beta += wq * wq;
                    gamma += wp * wq;
                }
                /* sqrt(alpha) sqrt(beta): the product alpha beta can underflow in float. */
                if (!(rp_fabs(gamma) > tol * rp_sqrt(alpha) * rp_sqrt(beta))) {
                    continue;
                }
                converged = 0;
                const rp_real zeta = (beta - alpha) / (RP_C(2) * gamma);
                const rp_real az = rp_fabs(zeta);
                /* sqrt(1 + zeta^2) written so that zeta^2 cannot overflow. */
                const rp_real root =
                    az > RP_C(1) ? az * rp_sqrt(RP_C(1) + (RP_C(1) / az) * (RP_C(1) / az))
                                 : rp_sqrt(RP_C(1) + az * az);
                const rp_real t = (zeta >= RP_C(0) ? RP_C(1) : RP_C(-1)) / (az + root);
                const rp_real cs = RP_C(1) / rp_sqrt(RP_C(1) + t * t);
                const rp_real sn = cs * t;
                for (unsigned i = 0; i < m; ++i) {
                    const rp_real wp = w[(size_t)i * n + p], wq = w[(size_t)i * n + q];
                    w[(size_t)i * n + p] = cs * wp - sn * wq;
                    w[(size_t)i * n + q] = sn * wp + cs * wq;
                }
                for (unsigned i = 0; i < n; ++i) {
                    const rp_real vp = vw[(size_t)i * n + p], vq = vw[(size_t)i * n + q];
                    vw[(size_t)i * n + p] = cs * vp - sn * vq;
                    vw[(size_t)i * n + q] = sn * vp + cs * vq;
                }
            }
        }
    }
    if (!converged) {
        return RP_E_NO_CONVERGE;
    }
    /* Singular values (of the scaled matrix) = column norms; order columns by descending value. */
    rp_real sv[RP_LA_MAX_DIM];
    unsigned order[RP_LA_MAX_DIM];
    for (unsigned j = 0; j < n; ++j) {
        sv[j] = lac_norm(w + j, m, n);
        order[j] = j;
    }
    for (unsigned i = 0; i + 1 < n; ++i) {
        unsigned best = i;
        for (unsigned j = i + 1; j < n; ++j) {
            if (sv[order[j]] > sv[order[best]]) {
                best = j;
            }
        }
        unsigned t = order[i];
        order[i] = order[best];
        order[best] = t;
    }
    for (unsigned i = 0; i < n; ++i) {
        s->data[i] = sv[order[i]] * amax;
        for (unsigned r = 0; r < n; ++r) {
            v->data[(size_t)r * n + i] = vw[(size_t)r * n + order[i]];
        }
    }
    if (u == NULL) {
        return RP_OK;
    }
    /* u_i = w_i / s_i; where s_i is zero to working precision, an orthonormal completion. */
    const rp_real tiny = sv[order[0]] * tol;
    unsigned done[RP_LA_MAX_DIM], nd = 0;
    for (unsigned i = 0; i < n; ++i) {
        const unsigned c = order[i];
        if (sv[c] > tiny && sv[c] > RP_C(0)) {
            for (unsigned r = 0; r < m; ++r) {
                u->data[(size_t)r * n + i] = w[(size_t)r * n + c] / sv[c];
            }
            done[nd++] = i;
        }
    }
    for (unsigned i = 0; i < n; ++i) {
        const unsigned c = order[i];
        if (!(sv[c] > tiny && sv[c] > RP_C(0))) {
            lac_complete_column(u->data, m, n, i, done, nd);
            done[nd++] = i;
        }
    }
    return RP_OK;
}
