/*
 * rp_rot.c - rotations: the paper's fixed-axis angles, quaternions, exp/log, small 3x3 products.
 *
 * With ca = cos(alpha), sa = sin(alpha) and so on, R = Rz(gamma) Ry(beta) Rx(alpha) is
 *   [ cg cb   cg sb sa - sg ca   cg sb ca + sg sa ]
 *   [ sg cb   sg sb sa + cg ca   sg sb ca - cg sa ]
 *   [ -sb     cb sa              cb ca            ]
 */
#include "rigpose/rp_rot.h"

#include "priv/rp_math.h"

#if RP_REAL_IS_FLOAT
#define GIMBAL_COS   RP_C(1e-5) /* rp_rot_to_angles: |cos beta| below this is gimbal lock */
#define QUAT_MIN     RP_C(1e-6) /* rp_rot_from_quat: smallest accepted |q| */
#define EXP_TAYLOR   RP_C(1e-2) /* rp_rot_exp: below this angle, series for the coefficients */
#else
#define GIMBAL_COS   RP_C(1e-9)
#define QUAT_MIN     RP_C(1e-12)
#define EXP_TAYLOR   RP_C(1e-4)
#endif

#define TWO_PI (RP_C(2.0) * RP_PI)

/* Angle in (-pi, pi]: atan2 may give -pi (for -0 sines), which the API excludes. */
static rp_real half_open(rp_real a)
{
    return (a <= -RP_PI) ? a + TWO_PI : a;
}

void rp_rot_from_angles(const rp_real abg[3], rp_real R[9])
{
    const rp_real ca = rp_cos(abg[0]), sa = rp_sin(abg[0]);
    const rp_real cb = rp_cos(abg[1]), sb = rp_sin(abg[1]);
    const rp_real cg = rp_cos(abg[2]), sg = rp_sin(abg[2]);
    R[0] = cg * cb;
    R[1] = cg * sb * sa - sg * ca;
    R[2] = cg * sb * ca + sg * sa;
    R[3] = sg * cb;
    R[4] = sg * sb * sa + cg * ca;
    R[5] = sg * sb * ca - cg * sa;
    R[6] = -sb;
    R[7] = cb * sa;
    R[8] = cb * ca;
}

rp_status_t rp_rot_to_angles(const rp_real R[9], rp_real abg[3])
{
    if (!rp_all_finite(R, 9)) {
        return RP_E_NAN;
    }
    const rp_real cb = rp_sqrt(R[0] * R[0] + R[3] * R[3]); /* |cos beta| */
    abg[1] = rp_atan2(-R[6], cb);
    if (cb < GIMBAL_COS) {
        /* sin beta = +1: R[1] = sin(alpha - gamma), R[4] = cos(alpha - gamma); sin beta = -1:
         * R[1] = -sin(alpha + gamma), R[4] = cos(alpha + gamma). With alpha = 0 both read
         * (-sin gamma, cos gamma). */
        abg[0] = RP_C(0.0);
        abg[2] = half_open(rp_atan2(-R[1], R[4]));
    } else {
        /* gamma from column 0; alpha from row 1 of Rz(gamma)^T R = Ry Rx, i.e. (0, ca, -sa),
         * which uses elements of size 1 rather than R[7], R[8] (of size cos beta), so that
         * near gimbal lock an error in gamma is compensated in alpha and R is reproduced. */
        const rp_real g = rp_atan2(R[3], R[0]);
        const rp_real cg = rp_cos(g), sg = rp_sin(g);
        abg[0] = half_open(rp_atan2(sg * R[2] - cg * R[5], cg * R[4] - sg * R[1]));
        abg[2] = half_open(g);
    }
    return RP_OK;
}

rp_status_t rp_angles_plus(const rp_real abg[3], const rp_real w[3], rp_real out[3])
{
    if (!rp_all_finite(abg, 3) || !rp_all_finite(w, 3)) {
        return RP_E_NAN;
    }
    rp_real R[9], E[9];
    rp_rot_from_angles(abg, R);
    rp_rot_exp(w, E);
    rp_rot_mul(E, R, R);
    return rp_rot_to_angles(R, out);
}

void rp_angles_minus(const rp_real a[3], const rp_real b[3], rp_real w[3])
{
    rp_real Ra[9], Rb[9];
    rp_rot_from_angles(a, Ra);
    rp_rot_from_angles(b, Rb);
    rp_rot_mul_a_bt(Ra, Rb, Ra);
    rp_rot_log(Ra, w);
}

/* dR/dalpha = R [e_x]x, dR/dbeta = Rz dRy Rx, dR/dgamma = [e_z]x R. */
void rp_rot_angle_derivs(const rp_real abg[3], rp_real dR[3][9])
{
    const rp_real ca = rp_cos(abg[0]), sa = rp_sin(abg[0]);
    const rp_real cb = rp_cos(abg[1]), sb = rp_sin(abg[1]);
    const rp_real cg = rp_cos(abg[2]), sg = rp_sin(abg[2]);
    rp_real *da = dR[0], *db = dR[1], *dg = dR[2];

    da[0] = RP_C(0.0);
    da[1] = cg * sb * ca + sg * sa;
    da[2] = -cg * sb * sa + sg * ca;
    da[3] = RP_C(0.0);
    da[4] = sg * sb * ca - cg * sa;
    da[5] = -sg * sb * sa - cg * ca;
    da[6] = RP_C(0.0);
    da[7] = cb * ca;
    da[8] = -cb * sa;

    db[0] = -cg * sb;
    db[1] = cg * cb * sa;
    db[2] = cg * cb * ca;
    db[3] = -sg * sb;
    db[4] = sg * cb * sa;
    db[5] = sg * cb * ca;
    db[6] = -cb;
    db[7] = -sb * sa;
    db[8] = -sb * ca;

    dg[0] = -sg * cb;
    dg[1] = -sg * sb * sa - cg * ca;
    dg[2] = -sg * sb * ca + cg * sa;
    dg[3] = cg * cb;
    dg[4] = cg * sb * sa - sg * ca;
    dg[5] = cg * sb * ca + sg * sa;
    dg[6] = RP_C(0.0);
    dg[7] = RP_C(0.0);
    dg[8] = RP_C(0.0);
}

/* Shepperd: take the largest of 4w^2, 4x^2, 4y^2, 4z^2 (from the trace and the diagonal) as
 * the pivot, so the division below is by at least 1/2 of |q| = 1. */
void rp_rot_to_quat(const rp_real R[9], rp_real q[4])
{
    const rp_real tr = R[0] + R[4] + R[8];
    rp_real w, x, y, z;
    if (tr >= R[0] && tr >= R[4] && tr >= R[8]) {
        const rp_real s = rp_sqrt(RP_C(1.0) + tr) * RP_C(2.0); /* 4 w */
        w = RP_C(0.25) * s;
        x = (R[7] - R[5]) / s;
        y = (R[2] - R[6]) / s;
        z = (R[3] - R[1]) / s;
    } else if (R[0] >= R[4] && R[0] >= R[8]) {
        const rp_real s = rp_sqrt(RP_C(1.0) + R[0] - R[4] - R[8]) * RP_C(2.0); /* 4 x */
        w = (R[7] - R[5]) / s;
        x = RP_C(0.25) * s;
        y = (R[1] + R[3]) / s;
        z = (R[2] + R[6]) / s;
    } else if (R[4] >= R[8]) {
        const rp_real s = rp_sqrt(RP_C(1.0) - R[0] + R[4] - R[8]) * RP_C(2.0); /* 4 y */
        w = (R[2] - R[6]) / s;
        x = (R[1] + R[3]) / s;
        y = RP_C(0.25) * s;
        z = (R[5] + R[7]) / s;
    } else {
        const rp_real s = rp_sqrt(RP_C(1.0) - R[0] - R[4] + R[8]) * RP_C(2.0); /* 4 z */
        w = (R[3] - R[1]) / s;
        x = (R[2] + R[6]) / s;
        y = (R[5] + R[7]) / s;
        z = RP_C(0.25) * s;
    }
    rp_real n = rp_sqrt(w * w + x * x + y * y + z * z);
    if (w < RP_C(0.0)) {
        n = -n;
    }
    q[0] = w / n;
    q[1] = x / n;
    q[2] = y / n;
    q[3] = z / n;
}

rp_status_t rp_rot_from_quat(const rp_real q[4], rp_real R[9])
{
    if (!rp_all_finite(q, 4)) {
        return RP_E_NAN;
    }
    const rp_real n = rp_sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(n >= QUAT_MIN)) {
        return RP_E_ARG;
    }
    const rp_real w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    R[0] = RP_C(1.0) - RP_C(2.0) * (y * y + z * z);
    R[1] = RP_C(2.0) * (x * y - w * z);
    R[2] = RP_C(2.0) * (x * z + w * y);
    R[3] = RP_C(2.0) * (x * y + w * z);
    R[4] = RP_C(1.0) - RP_C(2.0) * (x * x + z * z);
    R[5] = RP_C(2.0) * (y * z - w * x);
    R[6] = RP_C(2.0) * (x * z - w * y);
    R[7] = RP_C(2.0) * (y * z + w * x);
    R[8] = RP_C(1.0) - RP_C(2.0) * (x * x + y * y);
    return RP_OK;
}

/* R = I + a K + b K^2, K = [w]x, a = sin t / t, b = (1 - cos t) / t^2, t = |w|. */
void rp_rot_exp(const rp_real w[3], rp_real R[9])
{
    const rp_real t2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    const rp_real t = rp_sqrt(t2);
    rp_real a, b;
    if (t < EXP_TAYLOR) {
        a = RP_C(1.0) - t2 / RP_C(6.0) + t2 * t2 / RP_C(120.0);
        b = RP_C(0.5) - t2 / RP_C(24.0) + t2 * t2 / RP_C(720.0);
    } else {
        const rp_real sh = rp_sin(RP_C(0.5) * t);
        a = rp_sin(t) / t;
        b = RP_C(2.0) * sh * sh / t2; /* 1 - cos t without cancellation */
    }
    const rp_real xx = w[0] * w[0], yy = w[1] * w[1], zz = w[2] * w[2];
    const rp_real xy = w[0] * w[1], xz = w[0] * w[2], yz = w[1] * w[2];
    R[0] = RP_C(1.0) - b * (yy + zz);
    R[1] = -a * w[2] + b * xy;
    R[2] = a * w[1] + b * xz;
    R[3] = a * w[2] + b * xy;
    R[4] = RP_C(1.0) - b * (xx + zz);
    R[5] = -a * w[0] + b * yz;
    R[6] = -a * w[1] + b * xz;
    R[7] = a * w[0] + b * yz;
    R[8] = RP_C(1.0) - b * (xx + yy);
}

/* Through the (Shepperd, hence stable) quaternion: angle = 2 atan2(|v|, w) with w >= 0, so the
 * angle is in [0, pi] and neither small angles nor angles near pi lose the axis. */
void rp_rot_log(const rp_real R[9], rp_real w[3])
{
    rp_real q[4];
    rp_rot_to_quat(R, q);
    const rp_real n = rp_sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    const rp_real s = (n > RP_C(0.0)) ? RP_C(2.0) * rp_atan2(n, q[0]) / n : RP_C(2.0);
    w[0] = s * q[1];
    w[1] = s * q[2];
    w[2] = s * q[3];
}

void rp_rot_mul(const rp_real A[9], const rp_real B[9], rp_real C[9])
{
    rp_real T[9];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            T[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
        }
    }
    for (int i = 0; i < 9; ++i) {
        C[i] = T[i];
    }
}

void rp_rot_mul_at_b(const rp_real A[9], const rp_real B[9], rp_real C[9])
{
    rp_real T[9];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            T[3 * i + j] = A[i] * B[j] + A[3 + i] * B[3 + j] + A[6 + i] * B[6 + j];
        }
    }
    for (int i = 0; i < 9; ++i) {
        C[i] = T[i];
    }
}

void rp_rot_mul_a_bt(const rp_real A[9], const rp_real B[9], rp_real C[9])
{
    rp_real T[9];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            T[3 * i + j] = A[3 * i] * B[3 * j] + A[3 * i + 1] * B[3 * j + 1] +
                           A[3 * i + 2] * B[3 * j + 2];
        }
    }
    for (int i = 0; i < 9; ++i) {
        C[i] = T[i];
    }
}

void rp_rot_apply(const rp_real R[9], const rp_real v[3], rp_real out[3])
{
    const rp_real x = v[0], y = v[1], z = v[2];
    out[0] = R[0] * x + R[1] * y + R[2] * z;
    out[1] = R[3] * x + R[4] * y + R[5] * z;
    out[2] = R[6] * x + R[7] * y + R[8] * z;
}

void rp_rot_apply_t(const rp_real R[9], const rp_real v[3], rp_real out[3])
{
    const rp_real x = v[0], y = v[1], z = v[2];
    out[0] = R[0] * x + R[3] * y + R[6] * z;
    out[1] = R[1] * x + R[4] * y + R[7] * z;
    out[2] = R[2] * x + R[5] * y + R[8] * z;
}

void rp_rot_transpose(const rp_real R[9], rp_real Rt[9])
{
    rp_real t;
    Rt[0] = R[0];
    Rt[4] = R[4];
    Rt[8] = R[8];
    t = R[1]; Rt[1] = R[3]; Rt[3] = t;
    t = R[2]; Rt[2] = R[6]; Rt[6] = t;
    t = R[5]; Rt[5] = R[7]; Rt[7] = t;
}

/* Polar decomposition by Newton's iteration X <- (X + X^-T) / 2, which converges
 * quadratically to the orthogonal polar factor: the rotation nearest to R in the Frobenius
 * norm when det R > 0. X^-T = cof(X) / det X, the cofactor rows being cross products of the
 * rows of X. A matrix that is not close to a rotation (det <= 0, non-finite) is mapped to
 * a rotation through the quaternion instead. */
void rp_rot_orthonormalize(rp_real R[9])
{
    const rp_real tol = RP_C(8.0) * RP_REAL_EPS;
    for (int it = 0; it < 30; ++it) {
        rp_real C[9];
        const rp_real *r0 = R, *r1 = R + 3, *r2 = R + 6;
        C[0] = r1[1] * r2[2] - r1[2] * r2[1];
        C[1] = r1[2] * r2[0] - r1[0] * r2[2];
        C[2] = r1[0] * r2[1] - r1[1] * r2[0];
        C[3] = r2[1] * r0[2] - r2[2] * r0[1];
        C[4] = r2[2] * r0[0] - r2[0] * r0[2];
        C[5] = r2[0] * r0[1] - r2[1] * r0[0];
        C[6] = r0[1] * r1[2] - r0[2] * r1[1];
        C[7] = r0[2] * r1[0] - r0[0] * r1[2];
        C[8] = r0[0] * r1[1] - r0[1] * r1[0];
        const rp_real det = r0[0] * C[0] + r0[1] * C[1] + r0[2] * C[2];
        if (!(det > RP_C(1e-3)) || !rp_finite(det)) {
            break;
        }
        const rp_real h = RP_C(0.5) / det;
        rp_real change = RP_C(0.0);
        for (int i = 0; i < 9; ++i) {
            const rp_real x = RP_C(0.5) * R[i] + h * C[i];
            const rp_real d = rp_fabs(x - R[i]);
            change = d > change ? d : change;
            R[i] = x;
        }
        if (change <= tol) {
            return;
        }
    }
    if (rp_all_finite(R, 9)) {
        rp_real q[4];
        rp_rot_to_quat(R, q);
        if (rp_rot_from_quat(q, R) == RP_OK) {
            return;
        }
    }
    for (int i = 0; i < 9; ++i) {
        R[i] = (i % 4 == 0) ? RP_C(1.0) : RP_C(0.0);
    }
}

/* angle = atan2(|v|, c), v the axial vector of C = A^T B (|v| = sin angle), c = cos angle:
 * accurate for every angle, unlike acos near 0 and pi. */
rp_real rp_rot_distance(const rp_real A[9], const rp_real B[9])
{
    rp_real C[9];
    rp_rot_mul_at_b(A, B, C);
    const rp_real vx = C[7] - C[5], vy = C[2] - C[6], vz = C[3] - C[1];
    const rp_real s = RP_C(0.5) * rp_sqrt(vx * vx + vy * vy + vz * vz);
    const rp_real c = RP_C(0.5) * (C[0] + C[4] + C[8] - RP_C(1.0));
    return rp_atan2(s, c);
}

rp_real rp_angle_wrap(rp_real x)
{
    if (!rp_finite(x)) {
        return x;
    }
    rp_real r = x - TWO_PI * rp_floor((x + RP_PI) / TWO_PI);
    if (r >= RP_PI) {
        r -= TWO_PI;
    } else if (r < -RP_PI) {
        r += TWO_PI;
    }
    return r;
}
