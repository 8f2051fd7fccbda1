/*
 * rp_linalg_eigen.cpp - Eigen 3 backend of rp_linalg.h (rp_lae_*), a thin extern "C" shim.
 *
 * Same conventions as the C backend (see rp_linalg_c.c): usable views have non-NULL data and
 * rows, cols >= 1; "may alias" means the same data pointer, a partial overlap is RP_E_ARG;
 * decompositions take at most RP_LA_MAX_DIM rows/cols, reject non-finite input with RP_E_NAN
 * and leave the outputs unchanged on error; lstsq uses column-pivoted Householder QR with the
 * rank test |R_ii| <= tol * max |R_jj| (tol 1e-10 double, 1e-5 float).
 *
 * No heap: the caller's arrays are used through Eigen::Map, and every work matrix has a bounded
 * size (Matrix<..., Dynamic, Dynamic, RowMajor, RP_LA_MAX_DIM, RP_LA_MAX_DIM>), so it lives on the
 * stack. That alone is not enough: Eigen's BLAS-like kernels (gemv, trsm, syrk, blocked
 * Householder) take scratch through ei_declare_aligned_stack_constructed_variable, whose
 * fallback calls malloc/free, so merely instantiating them puts malloc and free into this object
 * (and EIGEN_NO_MALLOC only asserts at run time). Hence:
 *   - products are lazyProduct (coefficient-based, no kernel);
 *   - Cholesky and the triangular solves are written with Eigen block expressions and dot
 *     products instead of LLT / triangularView::solve (LLT's panels use gemv and trsm);
 *   - QR is ColPivHouseholderQR (unblocked, bounded scratch) rather than HouseholderQR
 *     (blocked), and Q is applied reflector by reflector (applyHouseholderOnTheLeft) rather than
 *     through HouseholderSequence, whose blocked path allocates;
 *   - SVD is JacobiSVD<..., NoQRPreconditioner> of the square R of that QR (its built-in QR
 *     preconditioner forms Q through the blocked path).
 * The Makefile's check-nomalloc target verifies the result on every build variant.
 */
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "rigpose/rp_linalg.h"

namespace {

#if RP_REAL_IS_FLOAT
const rp_real kRankTol = 1e-5f;
#else
const rp_real kRankTol = 1e-10;
#endif

typedef Eigen::Index Index;
/* Only ever mapped over caller memory, never instantiated as storage. */
typedef Eigen::Matrix<rp_real, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> RowMat;
typedef Eigen::Map<RowMat> MatMap;
typedef Eigen::Map<const RowMat> CMatMap;
/* Bounded work storage: inline arrays of RP_LA_MAX_DIM^2 (resp. RP_LA_MAX_DIM) scalars. */
typedef Eigen::Matrix<rp_real, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor, RP_LA_MAX_DIM,
                      RP_LA_MAX_DIM>
    BMat;
typedef Eigen::Matrix<rp_real, Eigen::Dynamic, 1, Eigen::ColMajor, RP_LA_MAX_DIM, 1> BVec;

MatMap map(rp_mat_t *m) { return MatMap(m->data, m->rows, m->cols); }
CMatMap cmap(const rp_mat_t *m) { return CMatMap(m->data, m->rows, m->cols); }

bool usable(const rp_mat_t *m)
{
    return m != NULL && m->data != NULL && m->rows > 0 && m->cols > 0;
}

std::size_t count(const rp_mat_t *m) { return std::size_t(m->rows) * m->cols; }

bool same_shape(const rp_mat_t *a, const rp_mat_t *b)
{
    return a->rows == b->rows && a->cols == b->cols;
}

bool overlap(const rp_mat_t *a, const rp_mat_t *b)
{
    std::uintptr_t a0 = reinterpret_cast<std::uintptr_t>(a->data);
    std::uintptr_t a1 = reinterpret_cast<std::uintptr_t>(a->data + count(a));
    std::uintptr_t b0 = reinterpret_cast<std::uintptr_t>(b->data);
    std::uintptr_t b1 = reinterpret_cast<std::uintptr_t>(b->data + count(b));
    return a0 < b1 && b0 < a1;
}

bool bad_alias(const rp_mat_t *in, const rp_mat_t *out)
{
    return in->data != out->data && overlap(in, out);
}

bool decomp_size_ok(const rp_mat_t *m)
{
    return m->rows <= RP_LA_MAX_DIM && m->cols <= RP_LA_MAX_DIM;
}

template <typename M> bool lower_finite(const M &a)
{
    for (Index i = 0; i < a.rows(); ++i) {
        if (!a.row(i).head(i + 1).allFinite()) {
            return false;
        }
    }
    return true;
}

/* l l^T = a from a's lower triangle (l's upper part zero); false if a is not positive definite. */
bool chol_factor(const CMatMap &a, BMat &l)
{
    const Index n = a.rows();
    l.setZero(n, n);
    for (Index j = 0; j < n; ++j) {
        const rp_real d = a(j, j) - l.row(j).head(j).squaredNorm();
        if (!(d > rp_real(0))) {
            return false;
        }
        l(j, j) = std::sqrt(d);
        const Index below = n - j - 1;
        if (below > 0) {
            l.col(j).tail(below) =
                (a.col(j).tail(below) -
                 l.bottomLeftCorner(below, j).lazyProduct(l.row(j).head(j).transpose())) /
                l(j, j);
        }
    }
    return true;
}

/* y <- (l l^T)^-1 y: forward l z = y, then back l^T y = z. */
void chol_subst(const BMat &l, BVec &y)
{
    const Index n = l.rows();
    for (Index i = 0; i < n; ++i) {
        y(i) = (y(i) - l.row(i).head(i).dot(y.head(i))) / l(i, i);
    }
    for (Index i = n - 1; i >= 0; --i) {
        const Index t = n - 1 - i;
        y(i) = (y(i) - l.col(i).tail(t).dot(y.tail(t))) / l(i, i);
    }
}

/* y <- Q^T y for the Q of a ColPivHouseholderQR (m rows, n reflectors). */
void apply_qt(const Eigen::ColPivHouseholderQR<BMat> &qr, BVec &y)
{
    const BMat &h = qr.matrixQR();
    const Index m = h.rows(), n = h.cols();
    rp_real ws[RP_LA_MAX_DIM];
    for (Index j = 0; j < n; ++j) {
        y.tail(m - j).applyHouseholderOnTheLeft(h.col(j).tail(m - j - 1), qr.hCoeffs().coeff(j),
                                                ws);
    }
}

} // namespace

extern "C" {

rp_status_t rp_lae_mul(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    if (!usable(a) || !usable(b) || !usable(c) || a->cols != b->rows || c->rows != a->rows ||
        c->cols != b->cols || overlap(a, c) || overlap(b, c)) {
        return RP_E_ARG;
    }
    map(c).noalias() = cmap(a).lazyProduct(cmap(b));
    return RP_OK;
}

rp_status_t rp_lae_mul_at_b(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    if (!usable(a) || !usable(b) || !usable(c) || a->rows != b->rows || c->rows != a->cols ||
        c->cols != b->cols || overlap(a, c) || overlap(b, c)) {
        return RP_E_ARG;
    }
    map(c).noalias() = cmap(a).transpose().lazyProduct(cmap(b));
    return RP_OK;
}

rp_status_t rp_lae_mul_a_bt(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    if (!usable(a) || !usable(b) || !usable(c) || a->cols != b->cols || c->rows != a->rows ||
        c->cols != b->rows || overlap(a, c) || overlap(b, c)) {
        return RP_E_ARG;
    }
    map(c).noalias() = cmap(a).lazyProduct(cmap(b).transpose());
    return RP_OK;
}

rp_status_t rp_lae_add(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    if (!usable(a) || !usable(b) || !usable(c) || !same_shape(a, b) || !same_shape(a, c) ||
        bad_alias(a, c) || bad_alias(b, c)) {
        return RP_E_ARG;
    }
    map(c) = cmap(a) + cmap(b);
    return RP_OK;
}

rp_status_t rp_lae_sub(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *c)
{
    if (!usable(a) || !usable(b) || !usable(c) || !same_shape(a, b) || !same_shape(a, c) ||
        bad_alias(a, c) || bad_alias(b, c)) {
        return RP_E_ARG;
    }
    map(c) = cmap(a) - cmap(b);
    return RP_OK;
}

rp_status_t rp_lae_scale(const rp_mat_t *a, rp_real s, rp_mat_t *c)
{
    if (!usable(a) || !usable(c) || !same_shape(a, c) || bad_alias(a, c)) {
        return RP_E_ARG;
    }
    map(c) = s * cmap(a);
    return RP_OK;
}

rp_status_t rp_lae_transpose(const rp_mat_t *a, rp_mat_t *c)
{
    if (!usable(a) || !usable(c) || c->rows != a->cols || c->cols != a->rows || overlap(a, c)) {
        return RP_E_ARG;
    }
    map(c) = cmap(a).transpose();
    return RP_OK;
}

rp_status_t rp_lae_chol(const rp_mat_t *a, rp_mat_t *l)
{
    if (!usable(a) || !usable(l) || a->rows != a->cols || !same_shape(a, l) ||
        !decomp_size_ok(a)) {
        return RP_E_ARG;
    }
    if (!lower_finite(cmap(a))) {
        return RP_E_NAN;
    }
    BMat w;
    if (!chol_factor(cmap(a), w)) {
        return RP_E_SINGULAR;
    }
    map(l) = w;
    return RP_OK;
}

rp_status_t rp_lae_chol_solve(const rp_mat_t *l, const rp_mat_t *b, rp_mat_t *x)
{
    if (!usable(l) || !usable(b) || !usable(x) || l->rows != l->cols || b->rows != l->rows ||
        !same_shape(b, x) || !decomp_size_ok(l) || bad_alias(b, x)) {
        return RP_E_ARG;
    }
    if (!lower_finite(cmap(l)) || !cmap(b).allFinite()) {
        return RP_E_NAN;
    }
    BMat w = cmap(l).triangularView<Eigen::Lower>();
    if ((w.diagonal().array() == rp_real(0)).any()) {
        return RP_E_SINGULAR;
    }
    /* x may be b's storage: column c of x only overwrites column c of b, already read. */
    for (Index c = 0; c < b->cols; ++c) {
        BVec y = cmap(b).col(c);
        chol_subst(w, y);
        map(x).col(c) = y;
    }
    return RP_OK;
}

rp_status_t rp_lae_inv_spd(const rp_mat_t *a, rp_mat_t *ainv)
{
    if (!usable(a) || !usable(ainv) || a->rows != a->cols || !same_shape(a, ainv) ||
        !decomp_size_ok(a)) {
        return RP_E_ARG;
    }
    if (!lower_finite(cmap(a))) {
        return RP_E_NAN;
    }
    const Index n = a->rows;
    BMat l;
    if (!chol_factor(cmap(a), l)) {
        return RP_E_SINGULAR;
    }
    /* m = l^-1 column by column (forward substitution on I), then a^-1 = m^T m. */
    BMat m = BMat::Zero(n, n);
    for (Index c = 0; c < n; ++c) {
        m(c, c) = rp_real(1) / l(c, c);
        for (Index i = c + 1; i < n; ++i) {
            m(i, c) = -l.row(i).segment(c, i - c).dot(m.col(c).segment(c, i - c)) / l(i, i);
        }
    }
    BMat p(n, n);
    p.noalias() = m.transpose().lazyProduct(m);
    map(ainv) = (p + p.transpose()) * rp_real(0.5);
    return RP_OK;
}

rp_status_t rp_lae_lstsq(const rp_mat_t *a, const rp_mat_t *b, rp_mat_t *x)
{
    if (!usable(a) || !usable(b) || !usable(x) || b->rows != a->rows || x->rows != a->cols ||
        x->cols != b->cols || !decomp_size_ok(a) || bad_alias(b, x)) {
        return RP_E_ARG;
    }
    const Index m = a->rows, n = a->cols;
    if (m < n) {
        return RP_E_TOO_FEW;
    }
    if (!cmap(a).allFinite() || !cmap(b).allFinite()) {
        return RP_E_NAN;
    }
    const BMat am = cmap(a);
    const Eigen::ColPivHouseholderQR<BMat> qr(am); /* a P = Q R */
    const BMat &r = qr.matrixQR();
    const rp_real rmax = r.diagonal().cwiseAbs().maxCoeff();
    for (Index j = 0; j < n; ++j) {
        if (!(std::abs(r(j, j)) > kRankTol * rmax)) {
            return RP_E_SINGULAR;
        }
    }
    const auto &perm = qr.colsPermutation().indices();
    for (Index c = 0; c < b->cols; ++c) {
        BVec y = cmap(b).col(c);
        apply_qt(qr, y);
        for (Index i = n - 1; i >= 0; --i) {
            const Index t = n - 1 - i;
            y(i) = (y(i) - r.row(i).segment(i + 1, t).dot(y.segment(i + 1, t))) / r(i, i);
        }
        for (Index i = 0; i < n; ++i) {
            map(x)(perm(i), c) = y(i);
        }
    }
    return RP_OK;
}

rp_status_t rp_lae_svd(const rp_mat_t *a, rp_mat_t *u, rp_mat_t *s, rp_mat_t *v)
{
    if (!usable(a) || !usable(s) || !usable(v) || (u != NULL && !usable(u)) ||
        !decomp_size_ok(a) || a->rows < a->cols || s->rows != a->cols || s->cols != 1 ||
        v->rows != a->cols || v->cols != a->cols || (u != NULL && !same_shape(u, a)) ||
        overlap(s, v) || (u != NULL && (overlap(u, s) || overlap(u, v)))) {
        return RP_E_ARG;
    }
    if (!cmap(a).allFinite()) {
        return RP_E_NAN;
    }
    const Index m = a->rows, n = a->cols;
    /* a P = Q R, R = Ur S Vr^T, so a = (Q [Ur; 0]) S (P Vr)^T. */
    const BMat am = cmap(a);
    const Eigen::ColPivHouseholderQR<BMat> qr(am);
    const BMat r = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
    const unsigned opts = u != NULL ? Eigen::ComputeFullU | Eigen::ComputeFullV
                                    : unsigned(Eigen::ComputeFullV);
    const Eigen::JacobiSVD<BMat, Eigen::NoQRPreconditioner> svd(r, opts);
    const auto &perm = qr.colsPermutation().indices();
    map(s) = svd.singularValues();
    for (Index i = 0; i < n; ++i) {
        map(v).row(perm(i)) = svd.matrixV().row(i);
    }
    if (u != NULL) {
        BMat uw = BMat::Zero(m, n);
        uw.topRows(n) = svd.matrixU();
        const BMat &h = qr.matrixQR();
        rp_real ws[RP_LA_MAX_DIM];
        for (Index j = n - 1; j >= 0; --j) {
            uw.bottomRows(m - j).applyHouseholderOnTheLeft(h.col(j).tail(m - j - 1),
                                                           qr.hCoeffs().coeff(j), ws);
        }
        map(u) = uw;
    }
    return RP_OK;
}

} /* extern "C" */
