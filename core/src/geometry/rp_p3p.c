/*
 * rp_p3p.c - Lambda Twist P3P (Persson & Nordberg, ECCV 2018); the method and rigpose's choices
 * are described in rp_p3p.h. Written from the paper's equations; variable names follow it:
 * b_ij = y_i . y_j (cosines between the bearings), a_ij = |x_i - x_j|^2, L = (l1, l2, l3) the
 * depths along the bearings, M_ij the quadrics of its eq. (4).
 */
#include "rigpose/rp_p3p.h"

#include <stddef.h>

#include "priv/rp_math.h"

#if RP_REAL_IS_FLOAT
#define p3p_cbrt cbrtf
/* Sine of the smallest angle between two bearings / two triangle sides accepted. */
#define P3P_MIN_SIN RP_C(1e-4)
/* Residual of the three quadrics a solution must reach, relative to the largest a_ij or the
 * largest squared depth, whichever is larger. */
#define P3P_MAX_RESID RP_C(1e-3)
#else
#define p3p_cbrt cbrt
#define P3P_MIN_SIN RP_C(1e-9)
#define P3P_MAX_RESID RP_C(1e-7)
#endif

/* Verified Gauss-Newton steps on the depths (the paper: rarely better after 2; 5 as its code). */
#define P3P_GN_STEPS 5
/* Newton steps polishing each root of the cubic. */
#define P3P_CUBIC_NEWTON 3

static rp_real dot3(const rp_real a[3], const rp_real b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const rp_real a[3], const rp_real b[3], rp_real c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static void sub3(const rp_real a[3], const rp_real b[3], rp_real c[3])
{
    c[0] = a[0] - b[0];
    c[1] = a[1] - b[1];
    c[2] = a[2] - b[2];
}

/* v /= |v|; 0 if v is zero. */
static int normalize3(rp_real v[3])
{
    const rp_real n = rp_sqrt(dot3(v, v));
    if (!(n > RP_C(0.0))) {
        return 0;
    }
    for (int i = 0; i < 3; ++i) {
        v[i] /= n;
    }
    return 1;
}

/* x^T S y for a symmetric 3x3 S (row-major). */
static rp_real qform(const rp_real S[9], const rp_real x[3], const rp_real y[3])
{
    rp_real s = RP_C(0.0);
    for (int i = 0; i < 3; ++i) {
        s += x[i] * (S[3 * i] * y[0] + S[3 * i + 1] * y[1] + S[3 * i + 2] * y[2]);
    }
    return s;
}

/* det[u v w] = u . (v x w) for columns u, v, w taken from matrices A or B (sel bit i: column i
 * from B). Used for the coefficients of det(D1 + g D2). */
static rp_real det_cols(const rp_real A[9], const rp_real B[9], unsigned sel)
{
    rp_real c[3][3];
    for (int j = 0; j < 3; ++j) {
        const rp_real *S = (sel >> j) & 1u ? B : A;
        for (int i = 0; i < 3; ++i) {
            c[j][i] = S[3 * i + j];
        }
    }
    rp_real vw[3];
    cross3(c[1], c[2], vw);
    return dot3(c[0], vw);
}

/* Real roots of c[3] x^3 + c[2] x^2 + c[1] x + c[0] with c[3] != 0 (Cardano / trigonometric
 * form on the monic depressed cubic), each polished by Newton steps on the given polynomial.
 * Returns the count (1..3). */
static int cubic_roots(const rp_real c[4], rp_real x[3])
{
    const rp_real A = c[2] / c[3], B = c[1] / c[3], C = c[0] / c[3];
    const rp_real p = B - A * A / RP_C(3.0);
    const rp_real q = RP_C(2.0) * A * A * A / RP_C(27.0) - A * B / RP_C(3.0) + C;
    const rp_real disc = q * q / RP_C(4.0) + p * p * p / RP_C(27.0);
    int n;
    if (disc > RP_C(0.0)) {
        /* one real root: u = cbrt(-q/2 -+ sqrt(disc)) on the side without cancellation, and
         * v = -p / (3u) */
        const rp_real s = rp_sqrt(disc);
        const rp_real w = q > RP_C(0.0) ? -q / RP_C(2.0) - s : -q / RP_C(2.0) + s;
        const rp_real u = p3p_cbrt(w);
        x[0] = (u != RP_C(0.0) ? u - p / (RP_C(3.0) * u) : RP_C(0.0)) - A / RP_C(3.0);
        n = 1;
    } else if (p == RP_C(0.0)) {
        x[0] = -A / RP_C(3.0);
        n = 1;
    } else {
        /* three real roots: 2 sqrt(-p/3) cos(acos(3q/(2p) sqrt(-3/p)) / 3 - 2 pi k / 3) */
        const rp_real r = RP_C(2.0) * rp_sqrt(-p / RP_C(3.0));
        rp_real arg = RP_C(3.0) * q / (RP_C(2.0) * p) * rp_sqrt(RP_C(-3.0) / p);
        arg = arg > RP_C(1.0) ? RP_C(1.0) : (arg < RP_C(-1.0) ? RP_C(-1.0) : arg);
        const rp_real phi = rp_acos(arg) / RP_C(3.0);
        for (int k = 0; k < 3; ++k) {
            x[k] = r * rp_cos(phi - RP_C(2.0) * RP_PI * (rp_real)k / RP_C(3.0)) - A / RP_C(3.0);
        }
        n = 3;
    }
    for (int k = 0; k < n; ++k) {
        rp_real xk = x[k];
        rp_real f = ((c[3] * xk + c[2]) * xk + c[1]) * xk + c[0];
        for (int it = 0; it < P3P_CUBIC_NEWTON; ++it) {
            const rp_real fp = (RP_C(3.0) * c[3] * xk + RP_C(2.0) * c[2]) * xk + c[1];
            if (fp == RP_C(0.0)) {
                break;
            }
            const rp_real xn = xk - f / fp;
            const rp_real fn = ((c[3] * xn + c[2]) * xn + c[1]) * xn + c[0];
            if (!(rp_fabs(fn) < rp_fabs(f))) {
                break;
            }
            xk = xn;
            f = fn;
        }
        x[k] = xk;
    }
    return n;
}

/* A unit null vector of the symmetric 3x3 S of rank 2: the longest cross product of two of its
 * rows. 0 if every cross product is (relatively) zero. */
static int null_vector(const rp_real S[9], rp_real e[3])
{
    static const int pr[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    rp_real best = RP_C(0.0);
    for (int k = 0; k < 3; ++k) {
        rp_real c[3];
        cross3(&S[3 * pr[k][0]], &S[3 * pr[k][1]], c);
        const rp_real n2 = dot3(c, c);
        if (n2 > best) {
            best = n2;
            e[0] = c[0];
            e[1] = c[1];
            e[2] = c[2];
        }
    }
    rp_real smax = RP_C(0.0);
    for (int i = 0; i < 9; ++i) {
        smax = rp_fabs(S[i]) > smax ? rp_fabs(S[i]) : smax;
    }
    if (!(best > RP_REAL_EPS * RP_REAL_EPS * smax * smax * smax * smax)) {
        return 0;
    }
    return normalize3(e);
}

/* The two non-zero eigenvalues of a singular symmetric S: roots of s^2 - tr s + m2 with m2 the
 * sum of the principal 2x2 minors (= s1 s2). How well S splits into two real planes:
 * -s1 s2 / (s1^2 + s2^2), in (0, 1/2] for a real pair, <= 0 otherwise. */
static rp_real split_score(const rp_real S[9], rp_real *tr, rp_real *m2)
{
    *tr = S[0] + S[4] + S[8];
    *m2 = S[0] * S[4] - S[1] * S[3] + S[0] * S[8] - S[2] * S[6] + S[4] * S[8] - S[5] * S[7];
    const rp_real den = *tr * *tr - RP_C(2.0) * *m2;
    return den > RP_C(0.0) ? -*m2 / den : RP_C(-1.0);
}

/* The quadric residuals r_ij = L^T M_ij L - a_ij, order (12, 13, 23). */
static void quad_resid(const rp_real L[3], const rp_real b[3], const rp_real a[3], rp_real r[3])
{
    r[0] = L[0] * L[0] + L[1] * L[1] - RP_C(2.0) * b[0] * L[0] * L[1] - a[0];
    r[1] = L[0] * L[0] + L[2] * L[2] - RP_C(2.0) * b[1] * L[0] * L[2] - a[1];
    r[2] = L[1] * L[1] + L[2] * L[2] - RP_C(2.0) * b[2] * L[1] * L[2] - a[2];
}

/* Verified Gauss-Newton steps on the sum of squares of eq. (4): a step is kept only if it lowers
 * the residual. Returns the final squared residual. */
static rp_real refine_lambda(rp_real L[3], const rp_real b[3], const rp_real a[3])
{
    rp_real r[3];
    quad_resid(L, b, a, r);
    rp_real e = dot3(r, r);
    for (int it = 0; it < P3P_GN_STEPS && e > RP_C(0.0); ++it) {
        /* J = d r / d L (rows 12, 13, 23), solve J dl = -r by Cramer's rule */
        const rp_real J[9] = {
            RP_C(2.0) * (L[0] - b[0] * L[1]), RP_C(2.0) * (L[1] - b[0] * L[0]), RP_C(0.0),
            RP_C(2.0) * (L[0] - b[1] * L[2]), RP_C(0.0), RP_C(2.0) * (L[2] - b[1] * L[0]),
            RP_C(0.0), RP_C(2.0) * (L[1] - b[2] * L[2]), RP_C(2.0) * (L[2] - b[2] * L[1])};
        const rp_real c0[3] = {J[0], J[3], J[6]}, c1[3] = {J[1], J[4], J[7]},
                      c2[3] = {J[2], J[5], J[8]};
        rp_real t[3];
        cross3(c1, c2, t);
        const rp_real det = dot3(c0, t);
        if (det == RP_C(0.0) || !rp_finite(det)) {
            break;
        }
        const rp_real mr[3] = {-r[0], -r[1], -r[2]};
        rp_real dl[3];
        cross3(c1, c2, t);
        dl[0] = dot3(mr, t) / det;
        cross3(mr, c2, t);
        dl[1] = dot3(c0, t) / det;
        cross3(c1, mr, t);
        dl[2] = dot3(c0, t) / det;
        const rp_real Ln[3] = {L[0] + dl[0], L[1] + dl[1], L[2] + dl[2]};
        rp_real rn[3];
        quad_resid(Ln, b, a, rn);
        const rp_real en = dot3(rn, rn);
        if (!(en < e)) {
            break;
        }
        L[0] = Ln[0];
        L[1] = Ln[1];
        L[2] = Ln[2];
        e = en;
    }
    return e;
}

/* An orthonormal frame (columns f[0], f[1], f[2]) of the triangle p0 p1 p2 (Gram-Schmidt on its
 * two sides from p0). 0 if the triangle is degenerate. */
static int tri_frame(const rp_real p0[3], const rp_real p1[3], const rp_real p2[3],
                     rp_real f[3][3])
{
    rp_real s2[3];
    sub3(p1, p0, f[0]);
    sub3(p2, p0, s2);
    if (!normalize3(f[0])) {
        return 0;
    }
    for (int i = 0; i < 3; ++i) {
        f[1][i] = s2[i];
    }
    /* twice: one pass leaves f[1] orthogonal to f[0] only to eps / sin(angle at p0) */
    for (int pass = 0; pass < 2; ++pass) {
        const rp_real d = dot3(f[0], f[1]);
        for (int i = 0; i < 3; ++i) {
            f[1][i] -= d * f[0][i];
        }
        if (!normalize3(f[1])) {
            return 0;
        }
    }
    cross3(f[0], f[1], f[2]);
    return 1;
}

/* Pose from the depths: Xc_i = l_i y_i; R maps the world triangle's frame onto the camera
 * triangle's frame, t = mean(Xc) - R mean(X). 0 if a frame is degenerate. */
static int pose_from_depths(const rp_real y[3][3], const rp_real X[3][3], const rp_real L[3],
                            rp_p3p_pose_t *out)
{
    rp_real Y[3][3], fy[3][3], fx[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int c = 0; c < 3; ++c) {
            Y[i][c] = L[i] * y[i][c];
        }
    }
    if (!tri_frame(Y[0], Y[1], Y[2], fy) || !tri_frame(X[0], X[1], X[2], fx)) {
        return 0;
    }
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            out->R[3 * r + c] = fy[0][r] * fx[0][c] + fy[1][r] * fx[1][c] + fy[2][r] * fx[2][c];
        }
    }
    for (int r = 0; r < 3; ++r) {
        rp_real ym = RP_C(0.0), rx = RP_C(0.0);
        for (int i = 0; i < 3; ++i) {
            ym += Y[i][r];
            rx += out->R[3 * r] * X[i][0] + out->R[3 * r + 1] * X[i][1] + out->R[3 * r + 2] * X[i][2];
        }
        out->t[r] = (ym - rx) / RP_C(3.0);
    }
    return rp_all_finite(out->R, 9) && rp_all_finite(out->t, 3);
}

rp_status_t rp_p3p_solve(const rp_real y_in[3][3], const rp_real X[3][3],
                         rp_p3p_pose_t sol[RP_P3P_MAX_SOLS], uint8_t *n_sol)
{
    if (!y_in || !X || !sol || !n_sol) {
        return RP_E_ARG;
    }
    *n_sol = 0;
    if (!rp_all_finite(&y_in[0][0], 9) || !rp_all_finite(&X[0][0], 9)) {
        return RP_E_NAN;
    }
    rp_real y[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int c = 0; c < 3; ++c) {
            y[i][c] = y_in[i][c];
        }
        if (!normalize3(y[i])) {
            return RP_E_DEGENERATE;
        }
    }
    /* Degeneracy: two bearings along one ray; coincident or collinear world points. */
    static const int pr[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int k = 0; k < 3; ++k) {
        rp_real c[3];
        cross3(y[pr[k][0]], y[pr[k][1]], c);
        if (!(dot3(c, c) > P3P_MIN_SIN * P3P_MIN_SIN)) {
            return RP_E_DEGENERATE;
        }
    }
    rp_real d12[3], d13[3], d23[3], n123[3];
    sub3(X[0], X[1], d12);
    sub3(X[0], X[2], d13);
    sub3(X[1], X[2], d23);
    rp_real a[3] = {dot3(d12, d12), dot3(d13, d13), dot3(d23, d23)}; /* a12, a13, a23 */
    cross3(d12, d13, n123);
    if (!(a[0] > RP_C(0.0)) || !(a[1] > RP_C(0.0)) || !(a[2] > RP_C(0.0)) ||
        !(dot3(n123, n123) > P3P_MIN_SIN * P3P_MIN_SIN * a[0] * a[1])) {
        return RP_E_DEGENERATE;
    }
    /* Work with a_ij / max a_ij (depths in units of the longest side), scale back at the end. */
    const rp_real amax = a[0] > a[1] ? (a[0] > a[2] ? a[0] : a[2]) : (a[1] > a[2] ? a[1] : a[2]);
    for (int k = 0; k < 3; ++k) {
        a[k] /= amax;
    }
    const rp_real b[3] = {dot3(y[0], y[1]), dot3(y[0], y[2]), dot3(y[1], y[2])};

    /* The quadrics of eq. (4) and the two conics D1 = a23 M12 - a12 M23, D2 = a23 M13 - a13 M23. */
    const rp_real M12[9] = {1, -b[0], 0, -b[0], 1, 0, 0, 0, 0};
    const rp_real M13[9] = {1, 0, -b[1], 0, 0, 0, -b[1], 0, 1};
    const rp_real M23[9] = {0, 0, 0, 0, 1, -b[2], 0, -b[2], 1};
    rp_real D1[9], D2[9];
    for (int i = 0; i < 9; ++i) {
        D1[i] = a[2] * M12[i] - a[0] * M23[i];
        D2[i] = a[2] * M13[i] - a[1] * M23[i];
    }
    /* det(D1 + g D2) = c3 g^3 + c2 g^2 + c1 g + c0 (multilinear in the columns). */
    const rp_real c[4] = {det_cols(D1, D2, 0u),
                          det_cols(D1, D2, 1u) + det_cols(D1, D2, 2u) + det_cols(D1, D2, 4u),
                          det_cols(D1, D2, 6u) + det_cols(D1, D2, 5u) + det_cols(D1, D2, 3u),
                          det_cols(D1, D2, 7u)};
    /* Candidate degenerate conics D0 = w1 D1 + w2 D2, from the roots in g (D0 = D1 + g D2) or, if
     * the cubic is better conditioned reversed, in h = 1/g (D0 = h D1 + D2). */
    rp_real wts[3][2];
    int n_roots = 0;
    if (!rp_all_finite(c, 4)) {
        return RP_E_NAN;
    }
    if (rp_fabs(c[3]) >= rp_fabs(c[0])) {
        if (c[3] == RP_C(0.0)) {
            return RP_E_DEGENERATE; /* c0 = c3 = 0: both conics already degenerate */
        }
        rp_real g[3];
        n_roots = cubic_roots(c, g);
        for (int k = 0; k < n_roots; ++k) {
            wts[k][0] = RP_C(1.0);
            wts[k][1] = g[k];
        }
    } else {
        const rp_real cr[4] = {c[3], c[2], c[1], c[0]};
        rp_real h[3];
        n_roots = cubic_roots(cr, h);
        for (int k = 0; k < n_roots; ++k) {
            wts[k][0] = h[k];
            wts[k][1] = RP_C(1.0);
        }
    }
    /* The root whose D0 splits best into two real planes. */
    int best = -1;
    rp_real best_score = RP_C(0.0), D0[9], tr = RP_C(0.0), m2 = RP_C(0.0);
    for (int k = 0; k < n_roots; ++k) {
        rp_real S[9], smax = RP_C(0.0);
        for (int i = 0; i < 9; ++i) {
            S[i] = wts[k][0] * D1[i] + wts[k][1] * D2[i];
            smax = rp_fabs(S[i]) > smax ? rp_fabs(S[i]) : smax;
        }
        if (!(smax > RP_C(0.0)) || !rp_finite(smax)) {
            continue;
        }
        for (int i = 0; i < 9; ++i) {
            S[i] /= smax;
        }
        rp_real trk, m2k;
        const rp_real sc = split_score(S, &trk, &m2k);
        if (best < 0 || sc > best_score) {
            best = k;
            best_score = sc;
            tr = trk;
            m2 = m2k;
            for (int i = 0; i < 9; ++i) {
                D0[i] = S[i];
            }
        }
    }
    if (best < 0 || best_score < -RP_C(8.0) * RP_REAL_EPS) {
        return RP_OK; /* no real pair of planes: no real solution */
    }
    /* Eigen-decomposition of D0 with its known zero eigenvalue: s1 (largest |s|) and s2 of
     * opposite signs, D0 = s1 e1 e1^T + s2 e2 e2^T; the planes are
     * (sqrt|s1| e1 -+ sqrt|s2| e2) . L = 0. */
    rp_real disc = tr * tr - RP_C(4.0) * m2;
    disc = disc > RP_C(0.0) ? disc : RP_C(0.0);
    const rp_real sq = rp_sqrt(disc);
    rp_real s1 = (tr + sq) / RP_C(2.0), s2 = (tr - sq) / RP_C(2.0);
    if (rp_fabs(s2) > rp_fabs(s1)) {
        const rp_real tmp = s1;
        s1 = s2;
        s2 = tmp;
    }
    if (s1 * s2 > RP_C(0.0)) {
        s2 = RP_C(0.0); /* within rounding of a double plane */
    }
    rp_real e1[3], e2[3], e3[3], S[9];
    for (int i = 0; i < 9; ++i) {
        S[i] = D0[i] - (i % 4 == 0 ? s1 : RP_C(0.0));
    }
    if (!null_vector(S, e1)) {
        return RP_OK;
    }
    for (int i = 0; i < 9; ++i) {
        S[i] = D0[i] - (i % 4 == 0 ? s2 : RP_C(0.0));
    }
    if (s2 == RP_C(0.0) || !null_vector(S, e2)) {
        /* any unit vector orthogonal to e1: its coefficient sqrt|s2| is (nearly) zero */
        const rp_real ax[3] = {rp_fabs(e1[0]) < RP_C(0.6) ? RP_C(1.0) : RP_C(0.0),
                               rp_fabs(e1[0]) < RP_C(0.6) ? RP_C(0.0) : RP_C(1.0), RP_C(0.0)};
        cross3(e1, ax, e2);
    }
    const rp_real d = dot3(e1, e2);
    for (int i = 0; i < 3; ++i) {
        e2[i] -= d * e1[i];
    }
    if (!normalize3(e2)) {
        return RP_OK;
    }
    cross3(e1, e2, e3);
    /* The ratio equation independent of D0: L^T D2 L = 0 (a23 Q13 = a13 Q23) when D0 leans on
     * D1, L^T D1 L = 0 (a23 Q12 = a12 Q23) when it leans on D2. */
    const rp_real *E = rp_fabs(wts[best][0]) >= rp_fabs(wts[best][1]) ? D2 : D1;
    const rp_real r1 = rp_sqrt(rp_fabs(s1)), r2 = rp_sqrt(rp_fabs(s2));
    uint8_t ns = 0;
    for (int side = 0; side < 2; ++side) {
        if (side == 1 && r2 == RP_C(0.0)) {
            break; /* a double plane: one plane only */
        }
        rp_real n[3], w[3];
        for (int i = 0; i < 3; ++i) {
            n[i] = r1 * e1[i] + (side ? -r2 : r2) * e2[i];
        }
        /* the plane n.L = 0 is spanned by e3 (D0's null vector) and w = n x e3 */
        cross3(n, e3, w);
        if (!normalize3(w)) {
            continue;
        }
        /* L = x e3 + z w on the plane; the ratio equation: A x^2 + 2 B x z + C z^2 = 0 */
        const rp_real A = qform(E, e3, e3), B = qform(E, e3, w), C = qform(E, w, w);
        rp_real dq = B * B - A * C;
        if (dq < RP_C(0.0)) {
            if (dq < -RP_C(16.0) * RP_REAL_EPS * (B * B + rp_fabs(A * C))) {
                continue; /* the plane misses the ratio cone */
            }
            dq = RP_C(0.0);
        }
        const rp_real qq = -(B + (B >= RP_C(0.0) ? rp_sqrt(dq) : -rp_sqrt(dq)));
        const rp_real dir[2][2] = {{qq, A}, {C, qq}}; /* (x, z): the two roots, stable form */
        for (int k = 0; k < 2; ++k) {
            rp_real L[3];
            for (int i = 0; i < 3; ++i) {
                L[i] = dir[k][0] * e3[i] + dir[k][1] * w[i];
            }
            /* scale: sum of the three quadrics = sum of a_ij (a positive definite form unless
             * the points coincide) */
            rp_real r0[3];
            const rp_real zero[3] = {RP_C(0.0), RP_C(0.0), RP_C(0.0)};
            quad_resid(L, b, zero, r0);
            const rp_real qs = r0[0] + r0[1] + r0[2];
            if (!(qs > RP_C(0.0)) || !rp_finite(qs)) {
                continue;
            }
            rp_real sc = rp_sqrt((a[0] + a[1] + a[2]) / qs);
            if (L[0] + L[1] + L[2] < RP_C(0.0)) {
                sc = -sc;
            }
            for (int i = 0; i < 3; ++i) {
                L[i] *= sc;
            }
            if (!(L[0] > RP_C(0.0) && L[1] > RP_C(0.0) && L[2] > RP_C(0.0))) {
                continue;
            }
            /* the residual's rounding floor grows with l^2 (the quadrics cancel to a_ij) */
            const rp_real res = refine_lambda(L, b, a);
            rp_real l2max = L[0] * L[0] > L[1] * L[1] ? L[0] * L[0] : L[1] * L[1];
            l2max = L[2] * L[2] > l2max ? L[2] * L[2] : l2max;
            l2max = l2max > RP_C(1.0) ? l2max : RP_C(1.0);
            if (!(res < P3P_MAX_RESID * P3P_MAX_RESID * l2max * l2max) ||
                !(L[0] > RP_C(0.0) && L[1] > RP_C(0.0) && L[2] > RP_C(0.0))) {
                continue;
            }
            const rp_real sa = rp_sqrt(amax);
            for (int i = 0; i < 3; ++i) {
                L[i] *= sa;
            }
            if (ns < RP_P3P_MAX_SOLS && pose_from_depths(y, X, L, &sol[ns])) {
                ++ns;
            }
        }
    }
    *n_sol = ns;
    return RP_OK;
}
