/*
 * test_linalg.c - rp_linalg: known values and error codes for both backends (rp_lac_*, plain C,
 * and rp_lae_*, Eigen), reconstruction checks, and the two backends held to each other on
 * seeded random matrices.
 */
#include <string.h>

#include "rp_test.h"
#include "rigpose/rp_linalg.h"

/* ---- the two backends behind one table, so every behaviour test runs on both ------------- */

typedef rp_status_t (*la_bin_fn)(const rp_mat_t *, const rp_mat_t *, rp_mat_t *);

typedef struct {
    la_bin_fn mul, mul_at_b, mul_a_bt, add, sub;
    rp_status_t (*scale)(const rp_mat_t *, rp_real, rp_mat_t *);
    rp_status_t (*transpose)(const rp_mat_t *, rp_mat_t *);
    rp_status_t (*chol)(const rp_mat_t *, rp_mat_t *);
    la_bin_fn chol_solve;
    rp_status_t (*inv_spd)(const rp_mat_t *, rp_mat_t *);
    la_bin_fn lstsq;
    rp_status_t (*svd)(const rp_mat_t *, rp_mat_t *, rp_mat_t *, rp_mat_t *);
} la_t;

static const la_t lac = {rp_lac_mul,      rp_lac_mul_at_b, rp_lac_mul_a_bt, rp_lac_add,
                         rp_lac_sub,      rp_lac_scale,    rp_lac_transpose, rp_lac_chol,
                         rp_lac_chol_solve, rp_lac_inv_spd, rp_lac_lstsq,    rp_lac_svd};
static const la_t lae = {rp_lae_mul,      rp_lae_mul_at_b, rp_lae_mul_a_bt, rp_lae_add,
                         rp_lae_sub,      rp_lae_scale,    rp_lae_transpose, rp_lae_chol,
                         rp_lae_chol_solve, rp_lae_inv_spd, rp_lae_lstsq,    rp_lae_svd};

#define LA(state) ((const la_t *)*(state))

#define N_MAX RP_LA_MAX_DIM

static void assert_all_near(const rp_real *got, const double *want, size_t n, double tol)
{
    for (size_t i = 0; i < n; ++i) {
        assert_near(got[i], want[i], tol);
    }
}

/* ---- random matrices (rp_test_urand: seeded once per program, so deterministic) ---------- */

static void fill_random(rp_real *x, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        x[i] = (rp_real)rp_test_urand(-1.0, 1.0);
    }
}

/* a = m m^T + n I for a random n x n m: symmetric, eigenvalues >= n. */
static void random_spd(rp_real *a, unsigned n)
{
    rp_real m[N_MAX * N_MAX];
    fill_random(m, (size_t)n * n);
    for (unsigned i = 0; i < n; ++i) {
        for (unsigned j = 0; j < n; ++j) {
            double s = i == j ? (double)n : 0.0;
            for (unsigned k = 0; k < n; ++k) {
                s += (double)m[i * n + k] * (double)m[j * n + k];
            }
            a[i * n + j] = (rp_real)s;
        }
    }
}

static double max_abs(const rp_real *x, size_t n)
{
    double r = 0.0;
    for (size_t i = 0; i < n; ++i) {
        r = fabs((double)x[i]) > r ? fabs((double)x[i]) : r;
    }
    return r;
}

static double max_abs_diff(const rp_real *x, const rp_real *y, size_t n)
{
    double r = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double d = fabs((double)x[i] - (double)y[i]);
        r = d > r ? d : r;
    }
    return r;
}

/* max |(x^T y)_ij - [i == j]| for m x n matrices x, y (columns orthonormal when x == y). */
static double gram_error(const rp_real *x, const rp_real *y, unsigned m, unsigned n)
{
    double r = 0.0;
    for (unsigned i = 0; i < n; ++i) {
        for (unsigned j = 0; j < n; ++j) {
            double s = 0.0;
            for (unsigned k = 0; k < m; ++k) {
                s += (double)x[k * n + i] * (double)y[k * n + j];
            }
            double d = fabs(s - (i == j ? 1.0 : 0.0));
            r = d > r ? d : r;
        }
    }
    return r;
}

/* ---- products and element-wise ops --------------------------------------------------------- */

static void test_mul_gives_known_product(void **state)
{
    rp_real a[] = {1, 2, 3, 4, 5, 6};   /* 2 x 3 */
    rp_real b[] = {7, 8, 9, 10, 11, 12}; /* 3 x 2 */
    rp_real c[4];
    assert_ok(LA(state)->mul(&RP_MAT(2, 3, a), &RP_MAT(3, 2, b), &RP_MAT(2, 2, c)));
    const double want[] = {58, 64, 139, 154};
    assert_all_near(c, want, 4, 0.0);
}

static void test_mul_at_b_multiplies_by_the_transpose_of_a(void **state)
{
    rp_real a[] = {1, 2, 3, 4, 5, 6}; /* 3 x 2, a^T = [1 3 5; 2 4 6] */
    rp_real b[] = {1, 0, 1, 1, 0, 2}; /* 3 x 2 */
    rp_real c[4];
    assert_ok(LA(state)->mul_at_b(&RP_MAT(3, 2, a), &RP_MAT(3, 2, b), &RP_MAT(2, 2, c)));
    const double want[] = {4, 13, 6, 16};
    assert_all_near(c, want, 4, 0.0);
}

static void test_mul_a_bt_multiplies_by_the_transpose_of_b(void **state)
{
    rp_real a[] = {1, 2, 3, 4, 5, 6}; /* 2 x 3 */
    rp_real b[] = {1, 0, 1, 0, 1, 0}; /* 2 x 3 */
    rp_real c[4];
    assert_ok(LA(state)->mul_a_bt(&RP_MAT(2, 3, a), &RP_MAT(2, 3, b), &RP_MAT(2, 2, c)));
    const double want[] = {4, 2, 10, 5};
    assert_all_near(c, want, 4, 0.0);
}

static void test_products_accept_sizes_beyond_the_decomposition_limit(void **state)
{
    enum { M = N_MAX + 9, K = 2 * N_MAX + 1 };
    static rp_real a[M * K], b[K * M], c[M * M];
    for (unsigned i = 0; i < M * K; ++i) {
        a[i] = 1;
        b[i] = 2;
    }
    assert_ok(LA(state)->mul(&RP_MAT(M, K, a), &RP_MAT(K, M, b), &RP_MAT(M, M, c)));
    assert_near(c[0], 2.0 * K, 0.0);
    assert_near(c[M * M - 1], 2.0 * K, 0.0);
}

static void test_add_sub_scale_work_in_place(void **state)
{
    rp_real a[] = {1, 2, 3, 4};
    rp_real b[] = {10, 20, 30, 40};
    rp_mat_t va = RP_MAT(2, 2, a), vb = RP_MAT(2, 2, b);
    assert_ok(LA(state)->add(&va, &vb, &va));
    const double sum[] = {11, 22, 33, 44};
    assert_all_near(a, sum, 4, 0.0);
    assert_ok(LA(state)->sub(&va, &vb, &vb));
    const double diff[] = {1, 2, 3, 4};
    assert_all_near(b, diff, 4, 0.0);
    assert_ok(LA(state)->scale(&va, RP_C(-0.5), &va));
    const double half[] = {-5.5, -11, -16.5, -22};
    assert_all_near(a, half, 4, 0.0);
}

static void test_transpose_swaps_rows_and_columns(void **state)
{
    rp_real a[] = {1, 2, 3, 4, 5, 6}; /* 2 x 3 */
    rp_real c[6];
    assert_ok(LA(state)->transpose(&RP_MAT(2, 3, a), &RP_MAT(3, 2, c)));
    const double want[] = {1, 4, 2, 5, 3, 6};
    assert_all_near(c, want, 6, 0.0);
}

/* ---- Cholesky, solve, inverse ---------------------------------------------------------------- */

/* a = l l^T with l = [2 0 0; 6 1 0; -8 5 3]. */
static const double chol_a[] = {4, 12, -16, 12, 37, -43, -16, -43, 98};
static const double chol_l[] = {2, 0, 0, 6, 1, 0, -8, 5, 3};

static void load(rp_real *dst, const double *src, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        dst[i] = (rp_real)src[i];
    }
}

static void test_chol_gives_known_factor_in_place(void **state)
{
    rp_real a[9];
    load(a, chol_a, 9);
    rp_mat_t va = RP_MAT(3, 3, a);
    assert_ok(LA(state)->chol(&va, &va));
    assert_all_near(a, chol_l, 9, RP_TOL(1e-14, 1e-6));
}

static void test_chol_reads_only_the_lower_triangle(void **state)
{
    rp_real a[9], l[9];
    load(a, chol_a, 9);
    a[1] = NAN;
    a[2] = 1e30f;
    a[5] = -7;
    assert_ok(LA(state)->chol(&RP_MAT(3, 3, a), &RP_MAT(3, 3, l)));
    assert_all_near(l, chol_l, 9, RP_TOL(1e-14, 1e-6));
}

static void test_chol_solve_recovers_known_solution_in_place(void **state)
{
    rp_real l[9];
    load(l, chol_l, 9);
    /* columns x1 = (1, 2, 3), x2 = (-1, 0, 0.5); b = a x. */
    rp_real b[6];
    const double xs[] = {1, -1, 2, 0, 3, 0.5};
    for (unsigned i = 0; i < 3; ++i) {
        for (unsigned c = 0; c < 2; ++c) {
            double s = 0;
            for (unsigned k = 0; k < 3; ++k) {
                s += chol_a[i * 3 + k] * xs[k * 2 + c];
            }
            b[i * 2 + c] = (rp_real)s;
        }
    }
    rp_mat_t vb = RP_MAT(3, 2, b);
    assert_ok(LA(state)->chol_solve(&RP_MAT(3, 3, l), &vb, &vb));
    assert_all_near(b, xs, 6, RP_TOL(1e-12, 1e-4));
}

static void test_inv_spd_gives_known_symmetric_inverse_in_place(void **state)
{
    rp_real a[] = {4, 2, 2, 3}; /* inverse (1/8) [3 -2; -2 4] */
    rp_mat_t va = RP_MAT(2, 2, a);
    assert_ok(LA(state)->inv_spd(&va, &va));
    const double want[] = {0.375, -0.25, -0.25, 0.5};
    assert_all_near(a, want, 4, RP_TOL(1e-15, 1e-7));
    assert_true(a[1] == a[2]);
}

/* ---- least squares ----------------------------------------------------------------------- */

static void test_lstsq_fits_known_line(void **state)
{
    /* y = x0 + x1 t through (0, 1), (1, 2), (2, 4): normal equations give x = (5/6, 3/2). */
    rp_real a[] = {1, 0, 1, 1, 1, 2};
    rp_real b[] = {1, 2, 4};
    rp_real x[2];
    assert_ok(LA(state)->lstsq(&RP_MAT(3, 2, a), &RP_MAT(3, 1, b), &RP_MAT(2, 1, x)));
    const double want[] = {5.0 / 6.0, 1.5};
    assert_all_near(x, want, 2, RP_TOL(1e-13, 1e-5));
}

static void test_lstsq_solves_square_system_with_columns_of_unequal_scale(void **state)
{
    /* Column 2 is 100x the others, so the pivoted QR reorders the columns. */
    rp_real a[] = {1, 2, 300, 0, 1, 400, 5, 6, 0};
    const double xs[] = {1, -2, 0.01, 2, 0, -0.02}; /* two right-hand sides */
    rp_real b[6], x[6];
    for (unsigned i = 0; i < 3; ++i) {
        for (unsigned c = 0; c < 2; ++c) {
            double s = 0;
            for (unsigned k = 0; k < 3; ++k) {
                s += (double)a[i * 3 + k] * xs[k * 2 + c];
            }
            b[i * 2 + c] = (rp_real)s;
        }
    }
    assert_ok(LA(state)->lstsq(&RP_MAT(3, 3, a), &RP_MAT(3, 2, b), &RP_MAT(3, 2, x)));
    assert_all_near(x, xs, 6, RP_TOL(1e-12, 1e-4));
}

static void test_lstsq_writes_over_b_when_x_shares_its_storage(void **state)
{
    rp_real a[] = {2, 0, 0, 4};
    rp_real b[] = {2, 8};
    rp_mat_t vb = RP_MAT(2, 1, b);
    assert_ok(LA(state)->lstsq(&RP_MAT(2, 2, a), &vb, &vb));
    const double want[] = {1, 2};
    assert_all_near(b, want, 2, RP_TOL(1e-15, 1e-6));
}

/* ---- SVD ----------------------------------------------------------------------------------- */

static void test_svd_of_scaled_permutation_gives_sorted_values(void **state)
{
    rp_real a[] = {3, 0, 0, -5, 0, 0}; /* 3 x 2 */
    rp_real u[6], s[2], v[4];
    assert_ok(LA(state)->svd(&RP_MAT(3, 2, a), &RP_MAT(3, 2, u), &RP_MAT(2, 1, s),
                             &RP_MAT(2, 2, v)));
    const double want[] = {5, 3};
    assert_all_near(s, want, 2, RP_TOL(1e-14, 1e-6));
    /* v's first column is +-e2, u's first column +-(-e2): u_0 s_0 v_0^T = a's -5 entry. */
    assert_near(fabs((double)v[2]), 1.0, RP_TOL(1e-14, 1e-6));
    assert_near((double)u[2] * (double)s[0] * (double)v[2], -5.0, RP_TOL(1e-13, 1e-5));
}

static void test_svd_of_rank_one_matrix_has_zero_value_and_orthonormal_u(void **state)
{
    rp_real a[] = {1, 2, 2, 4, 3, 6}; /* (1, 2, 3)^T (1, 2): s = (sqrt(14) sqrt(5), 0) */
    rp_real u[6], s[2], v[4];
    assert_ok(LA(state)->svd(&RP_MAT(3, 2, a), &RP_MAT(3, 2, u), &RP_MAT(2, 1, s),
                             &RP_MAT(2, 2, v)));
    assert_near(s[0], sqrt(70.0), RP_TOL(1e-13, 1e-5));
    assert_near(s[1], 0.0, RP_TOL(1e-13, 1e-5));
    assert_true(gram_error(u, u, 3, 2) <= RP_TOL(1e-13, 1e-5));
    assert_true(gram_error(v, v, 2, 2) <= RP_TOL(1e-13, 1e-5));
}

static void test_svd_without_u_gives_the_same_values(void **state)
{
    rp_real a[] = {2, 1, 1, 3, 0, 1, 1, 1}; /* 4 x 2 */
    rp_real u[8], s1[2], v1[4], s2[2], v2[4];
    assert_ok(LA(state)->svd(&RP_MAT(4, 2, a), &RP_MAT(4, 2, u), &RP_MAT(2, 1, s1),
                             &RP_MAT(2, 2, v1)));
    assert_ok(LA(state)->svd(&RP_MAT(4, 2, a), NULL, &RP_MAT(2, 1, s2), &RP_MAT(2, 2, v2)));
    assert_true(max_abs_diff(s1, s2, 2) <= RP_TOL(1e-14, 1e-6));
    assert_true(max_abs_diff(v1, v2, 4) <= RP_TOL(1e-14, 1e-6));
}

/* ---- errors -------------------------------------------------------------------------------- */

static void test_null_view_or_data_is_rejected(void **state)
{
    const la_t *la = LA(state);
    rp_real d[4] = {1, 0, 0, 1};
    rp_mat_t ok = RP_MAT(2, 2, d), nodata = RP_MAT(2, 2, NULL), empty = RP_MAT(0, 2, d);
    rp_real e[4], f[2], g[4];
    rp_mat_t out = RP_MAT(2, 2, e), s = RP_MAT(2, 1, f), v = RP_MAT(2, 2, g);
    assert_status(la->mul(NULL, &ok, &out), RP_E_ARG);
    assert_status(la->mul(&ok, &nodata, &out), RP_E_ARG);
    assert_status(la->mul_at_b(&ok, &ok, NULL), RP_E_ARG);
    assert_status(la->mul_a_bt(&empty, &ok, &out), RP_E_ARG);
    assert_status(la->add(&ok, NULL, &out), RP_E_ARG);
    assert_status(la->sub(&nodata, &ok, &out), RP_E_ARG);
    assert_status(la->scale(NULL, RP_C(1), &out), RP_E_ARG);
    assert_status(la->transpose(&ok, &nodata), RP_E_ARG);
    assert_status(la->chol(&nodata, &out), RP_E_ARG);
    assert_status(la->chol_solve(&ok, NULL, &out), RP_E_ARG);
    assert_status(la->inv_spd(&ok, NULL), RP_E_ARG);
    assert_status(la->lstsq(&ok, &ok, &nodata), RP_E_ARG);
    assert_status(la->svd(&ok, NULL, NULL, &v), RP_E_ARG);
    assert_status(la->svd(NULL, NULL, &s, &v), RP_E_ARG);
}

static void test_mismatched_sizes_are_rejected(void **state)
{
    const la_t *la = LA(state);
    rp_real a[16] = {0}, b[16] = {0}, c[16] = {0}, d[16] = {0};
    assert_status(la->mul(&RP_MAT(2, 3, a), &RP_MAT(2, 3, b), &RP_MAT(2, 3, c)), RP_E_ARG);
    assert_status(la->mul(&RP_MAT(2, 3, a), &RP_MAT(3, 2, b), &RP_MAT(2, 3, c)), RP_E_ARG);
    assert_status(la->mul_at_b(&RP_MAT(2, 3, a), &RP_MAT(3, 2, b), &RP_MAT(3, 2, c)), RP_E_ARG);
    assert_status(la->mul_a_bt(&RP_MAT(2, 3, a), &RP_MAT(3, 2, b), &RP_MAT(2, 3, c)), RP_E_ARG);
    assert_status(la->add(&RP_MAT(2, 2, a), &RP_MAT(2, 3, b), &RP_MAT(2, 2, c)), RP_E_ARG);
    assert_status(la->sub(&RP_MAT(2, 2, a), &RP_MAT(2, 2, b), &RP_MAT(4, 1, c)), RP_E_ARG);
    assert_status(la->scale(&RP_MAT(2, 2, a), RP_C(2), &RP_MAT(1, 4, c)), RP_E_ARG);
    assert_status(la->transpose(&RP_MAT(2, 3, a), &RP_MAT(2, 3, c)), RP_E_ARG);
    assert_status(la->chol(&RP_MAT(2, 3, a), &RP_MAT(2, 3, c)), RP_E_ARG);
    assert_status(la->chol(&RP_MAT(3, 3, a), &RP_MAT(2, 2, c)), RP_E_ARG);
    assert_status(la->chol_solve(&RP_MAT(3, 3, a), &RP_MAT(2, 1, b), &RP_MAT(2, 1, c)),
                  RP_E_ARG);
    assert_status(la->inv_spd(&RP_MAT(3, 3, a), &RP_MAT(3, 2, c)), RP_E_ARG);
    assert_status(la->lstsq(&RP_MAT(4, 2, a), &RP_MAT(3, 1, b), &RP_MAT(2, 1, c)), RP_E_ARG);
    assert_status(la->lstsq(&RP_MAT(4, 2, a), &RP_MAT(4, 1, b), &RP_MAT(2, 2, c)), RP_E_ARG);
    assert_status(la->svd(&RP_MAT(4, 2, a), NULL, &RP_MAT(1, 2, c), &RP_MAT(2, 2, d)), RP_E_ARG);
    assert_status(la->svd(&RP_MAT(4, 2, a), &RP_MAT(4, 4, b), &RP_MAT(2, 1, c),
                          &RP_MAT(2, 2, d)),
                  RP_E_ARG);
    assert_status(la->svd(&RP_MAT(2, 4, a), NULL, &RP_MAT(4, 1, c), &RP_MAT(4, 4, d)), RP_E_ARG);
}

static void test_decompositions_beyond_the_limit_are_rejected(void **state)
{
    const la_t *la = LA(state);
    enum { N = N_MAX + 1 };
    static rp_real a[N * N], b[N * N], c[N * N];
    for (unsigned i = 0; i < N; ++i) {
        a[i * N + i] = 1;
    }
    assert_status(la->chol(&RP_MAT(N, N, a), &RP_MAT(N, N, c)), RP_E_ARG);
    assert_status(la->chol_solve(&RP_MAT(N, N, a), &RP_MAT(N, 1, b), &RP_MAT(N, 1, c)),
                  RP_E_ARG);
    assert_status(la->inv_spd(&RP_MAT(N, N, a), &RP_MAT(N, N, c)), RP_E_ARG);
    assert_status(la->lstsq(&RP_MAT(N, 2, a), &RP_MAT(N, 1, b), &RP_MAT(2, 1, c)), RP_E_ARG);
    assert_status(la->svd(&RP_MAT(N, 2, a), NULL, &RP_MAT(2, 1, b), &RP_MAT(2, 2, c)),
                  RP_E_ARG);
}

static void test_forbidden_aliasing_is_rejected(void **state)
{
    const la_t *la = LA(state);
    rp_real a[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    rp_mat_t sq = RP_MAT(2, 2, a), shifted = RP_MAT(2, 2, a + 1);
    assert_status(la->mul(&sq, &sq, &sq), RP_E_ARG);
    assert_status(la->mul_at_b(&sq, &RP_MAT(2, 2, a + 4), &shifted), RP_E_ARG);
    assert_status(la->mul_a_bt(&RP_MAT(2, 2, a + 4), &sq, &shifted), RP_E_ARG);
    assert_status(la->transpose(&sq, &sq), RP_E_ARG);
    assert_status(la->add(&sq, &sq, &shifted), RP_E_ARG);
    assert_status(la->scale(&sq, RP_C(2), &shifted), RP_E_ARG);
    assert_status(la->lstsq(&RP_MAT(2, 2, a + 4), &RP_MAT(2, 1, a), &RP_MAT(2, 1, a + 1)),
                  RP_E_ARG);
    assert_status(la->svd(&RP_MAT(2, 2, a + 4), NULL, &RP_MAT(2, 1, a), &RP_MAT(2, 2, a + 1)),
                  RP_E_ARG);
    const double untouched[] = {1, 2, 3, 4, 5, 6, 7, 8};
    assert_all_near(a, untouched, 8, 0.0);
}

static void test_non_positive_definite_is_singular_and_output_untouched(void **state)
{
    const la_t *la = LA(state);
    rp_real indef[] = {1, 2, 2, 1}; /* eigenvalues 3, -1 */
    rp_real semi[] = {1, 1, 1, 1};  /* eigenvalues 2, 0 */
    rp_real out[4] = {9, 9, 9, 9};
    assert_status(la->chol(&RP_MAT(2, 2, indef), &RP_MAT(2, 2, out)), RP_E_SINGULAR);
    assert_status(la->chol(&RP_MAT(2, 2, semi), &RP_MAT(2, 2, out)), RP_E_SINGULAR);
    assert_status(la->inv_spd(&RP_MAT(2, 2, indef), &RP_MAT(2, 2, out)), RP_E_SINGULAR);
    assert_status(la->inv_spd(&RP_MAT(2, 2, semi), &RP_MAT(2, 2, out)), RP_E_SINGULAR);
    const double nines[] = {9, 9, 9, 9};
    assert_all_near(out, nines, 4, 0.0);
}

static void test_chol_solve_with_zero_diagonal_is_singular(void **state)
{
    rp_real l[] = {1, 0, 3, 0};
    rp_real b[] = {1, 1}, x[2];
    assert_status(LA(state)->chol_solve(&RP_MAT(2, 2, l), &RP_MAT(2, 1, b), &RP_MAT(2, 1, x)),
                  RP_E_SINGULAR);
}

static void test_lstsq_rank_deficient_is_singular(void **state)
{
    const la_t *la = LA(state);
    rp_real dup[] = {1, 2, 1, 3, 4, 3, 5, 6, 5, 7, 8, 7}; /* column 2 = column 0 */
    rp_real zero_col[] = {1, 0, 2, 0, 3, 0};
    rp_real b[] = {1, 2, 3, 4}, x[3] = {9, 9, 9};
    assert_status(la->lstsq(&RP_MAT(4, 3, dup), &RP_MAT(4, 1, b), &RP_MAT(3, 1, x)),
                  RP_E_SINGULAR);
    assert_status(la->lstsq(&RP_MAT(3, 2, zero_col), &RP_MAT(3, 1, b), &RP_MAT(2, 1, x)),
                  RP_E_SINGULAR);
    /* Nearly dependent: column 1 = column 0 + 1e-3 e_0 is well above the tolerance. */
    rp_real near_dep[] = {1.001, 1, 2, 2, 3, 3};
    assert_ok(la->lstsq(&RP_MAT(3, 2, near_dep), &RP_MAT(3, 1, b), &RP_MAT(2, 1, x)));
}

static void test_lstsq_underdetermined_is_too_few(void **state)
{
    rp_real a[6] = {1, 0, 0, 0, 1, 0};
    rp_real b[2] = {1, 2}, x[3];
    assert_status(LA(state)->lstsq(&RP_MAT(2, 3, a), &RP_MAT(2, 1, b), &RP_MAT(3, 1, x)),
                  RP_E_TOO_FEW);
}

static void test_non_finite_input_to_decompositions_is_nan(void **state)
{
    const la_t *la = LA(state);
    rp_real spd[] = {4, 1, 1, 3};
    rp_real b[] = {1, 2}, out[4], s[2];
    spd[2] = NAN;
    assert_status(la->chol(&RP_MAT(2, 2, spd), &RP_MAT(2, 2, out)), RP_E_NAN);
    assert_status(la->inv_spd(&RP_MAT(2, 2, spd), &RP_MAT(2, 2, out)), RP_E_NAN);
    assert_status(la->chol_solve(&RP_MAT(2, 2, spd), &RP_MAT(2, 1, b), &RP_MAT(2, 1, out)),
                  RP_E_NAN);
    assert_status(la->lstsq(&RP_MAT(2, 2, spd), &RP_MAT(2, 1, b), &RP_MAT(2, 1, out)),
                  RP_E_NAN);
    assert_status(la->svd(&RP_MAT(2, 2, spd), NULL, &RP_MAT(2, 1, s), &RP_MAT(2, 2, out)),
                  RP_E_NAN);
    spd[2] = 1;
    b[1] = INFINITY;
    assert_status(la->chol_solve(&RP_MAT(2, 2, spd), &RP_MAT(2, 1, b), &RP_MAT(2, 1, out)),
                  RP_E_NAN);
    assert_status(la->lstsq(&RP_MAT(2, 2, spd), &RP_MAT(2, 1, b), &RP_MAT(2, 1, out)),
                  RP_E_NAN);
    spd[3] = -INFINITY;
    assert_status(la->svd(&RP_MAT(2, 2, spd), NULL, &RP_MAT(2, 1, s), &RP_MAT(2, 2, out)),
                  RP_E_NAN);
}

/* ---- the two backends against each other, with reconstruction checks ---------------------- */

static const unsigned sizes[] = {1, 2, 3, 5, 8, 12, N_MAX};
#define N_SIZES (sizeof sizes / sizeof sizes[0])

/* The double-precision Cholesky (rp_la_chol_d, rp_la_chol_solve_d) on random SPD systems up to
 * 48 x 48 (gc's window at 8 keyframes is 42): A x = b solved to 1e-10 relative in every build,
 * whatever rp_real is; an indefinite matrix is singular; bad sizes and NULL refused. */
static void test_double_cholesky_solves_spd_systems(void **state)
{
    (void)state;
    static double A[48 * 48], L[48 * 48], b[48], x[48], m[48 * 48];
    for (int n = 1; n <= 48; n += 7) {
        for (int i = 0; i < n * n; ++i) {
            m[i] = rp_test_urand(-1.0, 1.0);
        }
        for (int i = 0; i < n; ++i) {
            for (int j = 0; j < n; ++j) {
                double s = i == j ? (double)n : 0.0;
                for (int k = 0; k < n; ++k) {
                    s += m[i * n + k] * m[j * n + k];
                }
                A[i * n + j] = L[i * n + j] = s;
            }
            b[i] = rp_test_urand(-1.0, 1.0);
        }
        assert_int_equal(rp_la_chol_d(L, n), RP_OK);
        assert_int_equal(rp_la_chol_solve_d(L, n, b, x), RP_OK);
        double worst = 0.0, bmax = 0.0;
        for (int i = 0; i < n; ++i) {
            double r = -b[i];
            for (int j = 0; j < n; ++j) {
                r += A[i * n + j] * x[j];
            }
            worst = fmax(worst, fabs(r));
            bmax = fmax(bmax, fabs(b[i]));
        }
        assert_true(worst <= 1e-10 * (double)n * bmax);
    }
    double indef[4] = {1.0, 2.0, 2.0, 1.0};
    assert_int_equal(rp_la_chol_d(indef, 2), RP_E_SINGULAR);
    double nan_m[1] = {NAN};
    assert_int_equal(rp_la_chol_d(nan_m, 1), RP_E_SINGULAR);
    assert_int_equal(rp_la_chol_d(NULL, 2), RP_E_ARG);
    assert_int_equal(rp_la_chol_d(A, 0), RP_E_ARG);
    assert_int_equal(rp_la_chol_d(A, RP_LA_D_MAX_DIM + 1), RP_E_ARG);
    assert_int_equal(rp_la_chol_solve_d(L, 2, NULL, x), RP_E_ARG);
}

static void test_backends_agree_on_products(void **state)
{
    (void)state;
    enum { M = 2 * N_MAX + 3 };
    static rp_real a[M * M], b[M * M], c1[M * M], c2[M * M];
    const unsigned dims[][3] = {{1, 1, 1}, {3, 4, 2}, {7, 5, 9}, {N_MAX, N_MAX, N_MAX}, {M, 20, 11}};
    for (unsigned t = 0; t < sizeof dims / sizeof dims[0]; ++t) {
        const unsigned m = dims[t][0], k = dims[t][1], n = dims[t][2];
        const double tol = RP_TOL(1e-14, 1e-6) * k;
        fill_random(a, (size_t)m * k);
        fill_random(b, (size_t)k * n);
        assert_ok(lac.mul(&RP_MAT(m, k, a), &RP_MAT(k, n, b), &RP_MAT(m, n, c1)));
        assert_ok(lae.mul(&RP_MAT(m, k, a), &RP_MAT(k, n, b), &RP_MAT(m, n, c2)));
        assert_true(max_abs_diff(c1, c2, (size_t)m * n) <= tol);
        assert_ok(lac.mul_at_b(&RP_MAT(k, m, a), &RP_MAT(k, n, b), &RP_MAT(m, n, c1)));
        assert_ok(lae.mul_at_b(&RP_MAT(k, m, a), &RP_MAT(k, n, b), &RP_MAT(m, n, c2)));
        assert_true(max_abs_diff(c1, c2, (size_t)m * n) <= tol);
        assert_ok(lac.mul_a_bt(&RP_MAT(m, k, a), &RP_MAT(n, k, b), &RP_MAT(m, n, c1)));
        assert_ok(lae.mul_a_bt(&RP_MAT(m, k, a), &RP_MAT(n, k, b), &RP_MAT(m, n, c2)));
        assert_true(max_abs_diff(c1, c2, (size_t)m * n) <= tol);
        assert_ok(lac.transpose(&RP_MAT(m, k, a), &RP_MAT(k, m, c1)));
        assert_ok(lae.transpose(&RP_MAT(m, k, a), &RP_MAT(k, m, c2)));
        assert_true(max_abs_diff(c1, c2, (size_t)m * k) == 0.0);
        assert_ok(lac.sub(&RP_MAT(m, k, a), &RP_MAT(m, k, b), &RP_MAT(m, k, c1)));
        assert_ok(lae.sub(&RP_MAT(m, k, a), &RP_MAT(m, k, b), &RP_MAT(m, k, c2)));
        assert_true(max_abs_diff(c1, c2, (size_t)m * k) == 0.0);
    }
}

static void test_backends_agree_on_cholesky_solve_and_inverse(void **state)
{
    (void)state;
    for (unsigned t = 0; t < N_SIZES; ++t) {
        const unsigned n = sizes[t], nn = n * n;
        rp_real a[N_MAX * N_MAX], l1[N_MAX * N_MAX], l2[N_MAX * N_MAX];
        rp_real b[N_MAX * 3], x1[N_MAX * 3], x2[N_MAX * 3];
        rp_real i1[N_MAX * N_MAX], i2[N_MAX * N_MAX];
        random_spd(a, n);
        fill_random(b, (size_t)n * 3);
        const double scale = max_abs(a, nn);

        assert_ok(lac.chol(&RP_MAT(n, n, a), &RP_MAT(n, n, l1)));
        assert_ok(lae.chol(&RP_MAT(n, n, a), &RP_MAT(n, n, l2)));
        assert_true(max_abs_diff(l1, l2, nn) <= RP_TOL(1e-13, 1e-5) * sqrt(scale));
        /* l l^T = a, upper part of l zero */
        for (unsigned i = 0; i < n; ++i) {
            for (unsigned j = 0; j < n; ++j) {
                double s = 0;
                for (unsigned k = 0; k < n; ++k) {
                    s += (double)l1[i * n + k] * (double)l1[j * n + k];
                }
                assert_near(s, a[i * n + j], RP_TOL(1e-13, 1e-5) * scale);
                if (j > i) {
                    assert_true(l1[i * n + j] == 0 && l2[i * n + j] == 0);
                }
            }
        }

        assert_ok(lac.chol_solve(&RP_MAT(n, n, l1), &RP_MAT(n, 3, b), &RP_MAT(n, 3, x1)));
        assert_ok(lae.chol_solve(&RP_MAT(n, n, l2), &RP_MAT(n, 3, b), &RP_MAT(n, 3, x2)));
        assert_true(max_abs_diff(x1, x2, (size_t)n * 3) <= RP_TOL(1e-13, 1e-5));

        assert_ok(lac.inv_spd(&RP_MAT(n, n, a), &RP_MAT(n, n, i1)));
        assert_ok(lae.inv_spd(&RP_MAT(n, n, a), &RP_MAT(n, n, i2)));
        assert_true(max_abs_diff(i1, i2, nn) <= RP_TOL(1e-13, 1e-5));
        /* a a^-1 = I, a^-1 exactly symmetric */
        for (unsigned i = 0; i < n; ++i) {
            for (unsigned j = 0; j < n; ++j) {
                double s = 0;
                for (unsigned k = 0; k < n; ++k) {
                    s += (double)a[i * n + k] * (double)i1[k * n + j];
                }
                assert_near(s, i == j ? 1.0 : 0.0, RP_TOL(1e-12, 1e-4));
                assert_true(i1[i * n + j] == i1[j * n + i] && i2[i * n + j] == i2[j * n + i]);
            }
        }
    }
}

static void test_backends_agree_on_least_squares(void **state)
{
    (void)state;
    for (unsigned t = 0; t < N_SIZES; ++t) {
        const unsigned n = sizes[t];
        for (unsigned m = n; m <= N_MAX; m += (N_MAX - n) / 2 + 1) {
            rp_real a[N_MAX * N_MAX], b[N_MAX * 2], x1[N_MAX * 2], x2[N_MAX * 2];
            fill_random(a, (size_t)m * n);
            for (unsigned i = 0; i < n; ++i) {
                a[i * n + i] += RP_C(2); /* keep the condition number moderate */
            }
            fill_random(b, (size_t)m * 2);
            assert_ok(lac.lstsq(&RP_MAT(m, n, a), &RP_MAT(m, 2, b), &RP_MAT(n, 2, x1)));
            assert_ok(lae.lstsq(&RP_MAT(m, n, a), &RP_MAT(m, 2, b), &RP_MAT(n, 2, x2)));
            assert_true(max_abs_diff(x1, x2, (size_t)n * 2) <=
                        RP_TOL(1e-12, 1e-4) * (1.0 + max_abs(x1, (size_t)n * 2)));
            /* optimality: a^T (a x - b) = 0 */
            for (unsigned c = 0; c < 2; ++c) {
                double r[N_MAX];
                for (unsigned i = 0; i < m; ++i) {
                    r[i] = -(double)b[i * 2 + c];
                    for (unsigned k = 0; k < n; ++k) {
                        r[i] += (double)a[i * n + k] * (double)x1[k * 2 + c];
                    }
                }
                for (unsigned k = 0; k < n; ++k) {
                    double g = 0;
                    for (unsigned i = 0; i < m; ++i) {
                        g += (double)a[i * n + k] * r[i];
                    }
                    assert_near(g, 0.0, RP_TOL(1e-12, 1e-4) * m);
                }
            }
        }
    }
}

/* Checks u diag(s) v^T = a, u and v orthonormal, s descending and non-negative. */
static void check_svd(const rp_real *a, const rp_real *u, const rp_real *s, const rp_real *v,
                      unsigned m, unsigned n)
{
    const double scale = max_abs(a, (size_t)m * n) + 1e-30;
    for (unsigned i = 0; i < n; ++i) {
        assert_true(s[i] >= 0);
        if (i > 0) {
            assert_true(s[i] <= s[i - 1]);
        }
    }
    for (unsigned i = 0; i < m; ++i) {
        for (unsigned j = 0; j < n; ++j) {
            double r = 0;
            for (unsigned k = 0; k < n; ++k) {
                r += (double)u[i * n + k] * (double)s[k] * (double)v[j * n + k];
            }
            assert_near(r, a[i * n + j], RP_TOL(1e-12, 1e-5) * scale * n);
        }
    }
    assert_true(gram_error(u, u, m, n) <= RP_TOL(1e-12, 1e-5) * n);
    assert_true(gram_error(v, v, n, n) <= RP_TOL(1e-12, 1e-5) * n);
}

static void test_backends_agree_on_singular_values(void **state)
{
    (void)state;
    for (unsigned t = 0; t < N_SIZES; ++t) {
        const unsigned n = sizes[t];
        for (unsigned m = n; m <= N_MAX; m += (N_MAX - n) / 2 + 1) {
            rp_real a[N_MAX * N_MAX], u1[N_MAX * N_MAX], u2[N_MAX * N_MAX];
            rp_real s1[N_MAX], s2[N_MAX], v1[N_MAX * N_MAX], v2[N_MAX * N_MAX];
            fill_random(a, (size_t)m * n);
            if (n >= 3) {
                /* make it rank deficient: last column = sum of the first two */
                for (unsigned i = 0; i < m; ++i) {
                    a[i * n + n - 1] = a[i * n] + a[i * n + 1];
                }
            }
            assert_ok(lac.svd(&RP_MAT(m, n, a), &RP_MAT(m, n, u1), &RP_MAT(n, 1, s1),
                              &RP_MAT(n, n, v1)));
            assert_ok(lae.svd(&RP_MAT(m, n, a), &RP_MAT(m, n, u2), &RP_MAT(n, 1, s2),
                              &RP_MAT(n, n, v2)));
            assert_true(max_abs_diff(s1, s2, n) <= RP_TOL(1e-12, 1e-5) * (1.0 + s1[0]));
            check_svd(a, u1, s1, v1, m, n);
            check_svd(a, u2, s2, v2, m, n);
            if (n >= 3) {
                assert_near(s1[n - 1], 0.0, RP_TOL(1e-12, 1e-5) * s1[0]);
            }
        }
    }
}

static void test_svd_of_zero_matrix_is_zero_with_orthonormal_factors(void **state)
{
    rp_real a[12] = {0}, u[12], s[3], v[9];
    assert_ok(LA(state)->svd(&RP_MAT(4, 3, a), &RP_MAT(4, 3, u), &RP_MAT(3, 1, s),
                             &RP_MAT(3, 3, v)));
    check_svd(a, u, s, v, 4, 3);
    assert_true(s[0] == 0);
}

/* ---- runner ---------------------------------------------------------------------------------- */

#define BOTH(f)                                                                                \
    {#f " [c]", f, NULL, NULL, (void *)&lac}, { #f " [eigen]", f, NULL, NULL, (void *)&lae }

int main(void)
{
    const struct CMUnitTest tests[] = {
        BOTH(test_mul_gives_known_product),
        BOTH(test_mul_at_b_multiplies_by_the_transpose_of_a),
        BOTH(test_mul_a_bt_multiplies_by_the_transpose_of_b),
        BOTH(test_products_accept_sizes_beyond_the_decomposition_limit),
        BOTH(test_add_sub_scale_work_in_place),
        BOTH(test_transpose_swaps_rows_and_columns),
        BOTH(test_chol_gives_known_factor_in_place),
        BOTH(test_chol_reads_only_the_lower_triangle),
        BOTH(test_chol_solve_recovers_known_solution_in_place),
        BOTH(test_inv_spd_gives_known_symmetric_inverse_in_place),
        BOTH(test_lstsq_fits_known_line),
        BOTH(test_lstsq_solves_square_system_with_columns_of_unequal_scale),
        BOTH(test_lstsq_writes_over_b_when_x_shares_its_storage),
        BOTH(test_svd_of_scaled_permutation_gives_sorted_values),
        BOTH(test_svd_of_rank_one_matrix_has_zero_value_and_orthonormal_u),
        BOTH(test_svd_without_u_gives_the_same_values),
        BOTH(test_svd_of_zero_matrix_is_zero_with_orthonormal_factors),
        BOTH(test_null_view_or_data_is_rejected),
        BOTH(test_mismatched_sizes_are_rejected),
        BOTH(test_decompositions_beyond_the_limit_are_rejected),
        BOTH(test_forbidden_aliasing_is_rejected),
        BOTH(test_non_positive_definite_is_singular_and_output_untouched),
        BOTH(test_chol_solve_with_zero_diagonal_is_singular),
        BOTH(test_lstsq_rank_deficient_is_singular),
        BOTH(test_lstsq_underdetermined_is_too_few),
        BOTH(test_non_finite_input_to_decompositions_is_nan),
        cmocka_unit_test(test_double_cholesky_solves_spd_systems),
        cmocka_unit_test(test_backends_agree_on_products),
        cmocka_unit_test(test_backends_agree_on_cholesky_solve_and_inverse),
        cmocka_unit_test(test_backends_agree_on_least_squares),
        cmocka_unit_test(test_backends_agree_on_singular_values),
    };
    return cmocka_run_group_tests_name("linalg", tests, NULL, NULL);
}
