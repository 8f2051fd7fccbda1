/*
 * rp_stereo.c - a calibrated stereo pair: fixed E and F from the rig extrinsics, the epipolar
 * check of candidate matches, and two-view triangulation (midpoint, then Gauss-Newton on the
 * reprojection error in both images, distortion included).
 *
 * Frames: everything here is in camera a's frame. Camera b's point is P_b = R_ab^T (P_a - t_ab).
 */
#include "rigpose/rp_stereo.h"

#include <stddef.h>

#include "priv/rp_math.h"
#include "rigpose/rp_camera.h"
#include "rigpose/rp_linalg.h"
#include "rigpose/rp_rot.h"

/* Gauss-Newton refinement of a triangulated point: iteration limit and relative step
 * tolerance (step norm / distance of the point). */
#define RP_STEREO_GN_ITERS 10
#if RP_REAL_IS_FLOAT
#define RP_STEREO_GN_TOL RP_C(1e-6)
/* Rays closer to parallel than this (sine of the angle between them) give no depth. */
#define RP_STEREO_MIN_SIN RP_C(1e-5)
#else
#define RP_STEREO_GN_TOL RP_C(1e-13)
#define RP_STEREO_MIN_SIN RP_C(1e-9)
#endif

/* Shortest baseline (m) that makes a pair. */
#define RP_STEREO_MIN_BASELINE RP_C(1e-3)

static rp_real dot3(const rp_real a[3], const rp_real b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static rp_real norm3(const rp_real a[3]) { return rp_sqrt(dot3(a, a)); }

/* K^-1 of a pinhole camera (maps pixels to normalised homogeneous coordinates). */
static void k_inverse(const rp_camera_t *c, rp_real Ki[9])
{
    Ki[0] = RP_C(1.0) / c->fx;
    Ki[1] = RP_C(0.0);
    Ki[2] = -c->cx / c->fx;
    Ki[3] = RP_C(0.0);
    Ki[4] = RP_C(1.0) / c->fy;
    Ki[5] = -c->cy / c->fy;
    Ki[6] = RP_C(0.0);
    Ki[7] = RP_C(0.0);
    Ki[8] = RP_C(1.0);
}

static int pair_valid(const rp_rig_t *rig, const rp_stereo_pair_t *sp)
{
    return rig != NULL && sp != NULL && rig->n_cams <= RP_MAX_CAMS && sp->a < rig->n_cams &&
           sp->b < rig->n_cams && sp->a != sp->b;
}

rp_status_t rp_stereo_pair_init(const rp_rig_t *rig, uint8_t a, uint8_t b, rp_stereo_pair_t *sp)
{
    if (rig == NULL || sp == NULL || rig->n_cams > RP_MAX_CAMS || a >= rig->n_cams ||
        b >= rig->n_cams || a == b) {
        return RP_E_ARG;
    }
    const rp_rig_cam_t *ca = &rig->cam[a];
    const rp_rig_cam_t *cb = &rig->cam[b];
    if (!rp_all_finite(ca->R, 9) || !rp_all_finite(cb->R, 9) || !rp_all_finite(ca->D, 3) ||
        !rp_all_finite(cb->D, 3)) {
        return RP_E_NAN;
    }
    rp_status_t st = rp_cam_check(&ca->cam);
    if (st == RP_OK) {
        st = rp_cam_check(&cb->cam);
    }
    if (st != RP_OK) {
        return st;
    }

    rp_stereo_pair_t out;
    out.a = a;
    out.b = b;
    /* R_ab = R_a^T R_b,  t_ab = R_a^T (D_b - D_a). */
    rp_rot_mul_at_b(ca->R, cb->R, out.R_ab);
    const rp_real dD[3] = {cb->D[0] - ca->D[0], cb->D[1] - ca->D[1], cb->D[2] - ca->D[2]};
    rp_rot_apply_t(ca->R, dD, out.t_ab);
    out.baseline_m = norm3(out.t_ab);
    if (!(out.baseline_m >= RP_STEREO_MIN_BASELINE)) {
        return RP_E_DEGENERATE;
    }

    /* Coplanarity of P_a, t_ab and the ray of b (R_ab x_b): x_a . (t x R_ab x_b) = 0, i.e.
     * x_b^T R_ab^T [t]x x_a = 0 up to sign. E = R_ab^T [t_hat]x with the unit baseline t_hat,
     * so that E does not scale with the baseline. */
    const rp_real s = RP_C(1.0) / out.baseline_m;
    const rp_real t0 = out.t_ab[0] * s, t1 = out.t_ab[1] * s, t2 = out.t_ab[2] * s;
    const rp_real tx[9] = {RP_C(0.0), -t2, t1, t2, RP_C(0.0), -t0, -t1, t0, RP_C(0.0)};
    rp_rot_mul_at_b(out.R_ab, tx, out.E);

    /* F = K_b^-T E K_a^-1 on undistorted pixels. */
    rp_real Kai[9], Kbi[9], EK[9];
    k_inverse(&ca->cam, Kai);
    k_inverse(&cb->cam, Kbi);
    rp_rot_mul(out.E, Kai, EK);
    rp_rot_mul_at_b(Kbi, EK, out.F);

    *sp = out;
    return RP_OK;
}

/* Undistorted pixel (homogeneous, third element 1) of distorted pixel uv in camera c:
 * K (undistort(K^-1 uv)). */
static rp_status_t undistorted_px(const rp_camera_t *c, const rp_real uv[2], rp_real x[3])
{
    rp_real xn[2];
    const rp_status_t st = rp_cam_unproject(c, uv, xn);
    if (st != RP_OK) {
        return st;
    }
    x[0] = c->fx * xn[0] + c->cx;
    x[1] = c->fy * xn[1] + c->cy;
    x[2] = RP_C(1.0);
    return RP_OK;
}

/* Distance (pixels) of homogeneous point x (x[2] = 1) to line l; 0 when l is no line (the
 * other point is the epipole, which agrees with every point). */
static rp_real point_line_px(const rp_real l[3], const rp_real x[3])
{
    const rp_real n = rp_sqrt(l[0] * l[0] + l[1] * l[1]);
    if (!(n > RP_C(0.0))) {
        return RP_C(0.0);
    }
    return rp_fabs(dot3(l, x)) / n;
}

rp_status_t rp_stereo_epipolar_px(const rp_rig_t *rig, const rp_stereo_pair_t *sp,
                                  const rp_real uv_a[2], const rp_real uv_b[2], rp_real *dist_px)
{
    if (!pair_valid(rig, sp) || uv_a == NULL || uv_b == NULL || dist_px == NULL) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(uv_a, 2) || !rp_all_finite(uv_b, 2)) {
        return RP_E_NAN;
    }
    rp_real xa[3], xb[3];
    rp_status_t st = undistorted_px(&rig->cam[sp->a].cam, uv_a, xa);
    if (st == RP_OK) {
        st = undistorted_px(&rig->cam[sp->b].cam, uv_b, xb);
    }
    if (st != RP_OK) {
        return st;
    }
    rp_real lb[3], la[3];
    rp_rot_apply(sp->F, xa, lb);   /* epipolar line of x_a in image b: F x_a */
    rp_rot_apply_t(sp->F, xb, la); /* epipolar line of x_b in image a: F^T x_b */
    const rp_real db = point_line_px(lb, xb);
    const rp_real da = point_line_px(la, xa);
    const rp_real d = da > db ? da : db;
    if (!rp_finite(d)) {
        return RP_E_NAN;
    }
    *dist_px = d;
    return RP_OK;
}

/* Residuals (measured - predicted, pixels) of P_a in both images and, when J is not NULL,
 * their Jacobian d(predicted)/d P_a (4x3 row-major: rows u_a v_a u_b v_b). */
static rp_status_t reproject(const rp_rig_t *rig, const rp_stereo_pair_t *sp,
                             const rp_real uv_a[2], const rp_real uv_b[2], const rp_real P_a[3],
                             rp_real r[4], rp_real J[12])
{
    rp_real pa[2], pb[2], Ja[6], Jb[6], P_b[3];
    const rp_real d[3] = {P_a[0] - sp->t_ab[0], P_a[1] - sp->t_ab[1], P_a[2] - sp->t_ab[2]};
    rp_rot_apply_t(sp->R_ab, d, P_b);
    rp_status_t st = rp_cam_project(&rig->cam[sp->a].cam, P_a, pa, J ? Ja : NULL);
    if (st == RP_OK) {
        st = rp_cam_project(&rig->cam[sp->b].cam, P_b, pb, J ? Jb : NULL);
    }
    if (st != RP_OK) {
        return st;
    }
    r[0] = uv_a[0] - pa[0];
    r[1] = uv_a[1] - pa[1];
    r[2] = uv_b[0] - pb[0];
    r[3] = uv_b[1] - pb[1];
    if (J != NULL) {
        for (int i = 0; i < 6; ++i) {
            J[i] = Ja[i];
        }
        /* d uv_b / d P_a = (d uv_b / d P_b) R_ab^T: row i of Jb times R_ab^T, i.e. column j
         * is Jb_i . (row j of R_ab). */
        for (int i = 0; i < 2; ++i) {
            for (int j = 0; j < 3; ++j) {
                J[6 + 3 * i + j] = dot3(&Jb[3 * i], &sp->R_ab[3 * j]);
            }
        }
    }
    return RP_OK;
}

static rp_real max_reproj(const rp_real r[4])
{
    const rp_real ea = rp_sqrt(r[0] * r[0] + r[1] * r[1]);
    const rp_real eb = rp_sqrt(r[2] * r[2] + r[3] * r[3]);
    return ea > eb ? ea : eb;
}

rp_status_t rp_stereo_triangulate(const rp_rig_t *rig, const rp_stereo_pair_t *sp,
                                  const rp_real uv_a[2], const rp_real uv_b[2], rp_real P_a[3],
                                  rp_real *reproj_px)
{
    if (!pair_valid(rig, sp) || uv_a == NULL || uv_b == NULL || P_a == NULL) {
        return RP_E_ARG;
    }
    if (!rp_all_finite(uv_a, 2) || !rp_all_finite(uv_b, 2)) {
        return RP_E_NAN;
    }
    rp_real xa[2], xb[2];
    rp_status_t st = rp_cam_unproject(&rig->cam[sp->a].cam, uv_a, xa);
    if (st == RP_OK) {
        st = rp_cam_unproject(&rig->cam[sp->b].cam, uv_b, xb);
    }
    if (st != RP_OK) {
        return st;
    }

    /* Midpoint: rays s da (from a's centre) and t_ab + t db (from b's centre), both in a's
     * frame; the ray directions have unit depth in their own cameras, so s and t are the
     * depths along each camera's z. Minimise |s da - t_ab - t db|^2:
     *   [da.da  -da.db] [s]   [ da.t_ab]
     *   [-da.db  db.db] [t] = [-db.t_ab]                                                      */
    const rp_real da[3] = {xa[0], xa[1], RP_C(1.0)};
    const rp_real xb3[3] = {xb[0], xb[1], RP_C(1.0)};
    rp_real db[3];
    rp_rot_apply(sp->R_ab, xb3, db);
    const rp_real aa = dot3(da, da), bb = dot3(db, db), ab = dot3(da, db);
    const rp_real det = aa * bb - ab * ab; /* |da x db|^2 */
    if (!(det > RP_STEREO_MIN_SIN * RP_STEREO_MIN_SIN * aa * bb)) {
        return RP_E_DEGENERATE;
    }
    const rp_real ra = dot3(da, sp->t_ab), rb = -dot3(db, sp->t_ab);
    const rp_real s = (bb * ra + ab * rb) / det;
    const rp_real t = (ab * ra + aa * rb) / det;
    if (s < RP_C(RP_MIN_DEPTH) || t < RP_C(RP_MIN_DEPTH)) {
        return RP_E_BEHIND;
    }
    rp_real P[3];
    for (int i = 0; i < 3; ++i) {
        P[i] = RP_C(0.5) * (s * da[i] + sp->t_ab[i] + t * db[i]);
    }

    /* Gauss-Newton on the 4 reprojection residuals; a step is kept only if it lowers the
     * squared error and leaves the point in front of both cameras. */
    rp_real r[4], J[12];
    st = reproject(rig, sp, uv_a, uv_b, P, r, J);
    if (st != RP_OK) {
        return st; /* midpoint behind one camera despite positive ray depths */
    }
    rp_real cost = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3];
    for (int it = 0; it < RP_STEREO_GN_ITERS && cost > RP_C(0.0); ++it) {
        rp_real H[9] = {0}, g[3] = {0};
        for (int k = 0; k < 4; ++k) {
            const rp_real *Jk = &J[3 * k];
            for (int i = 0; i < 3; ++i) {
                g[i] += Jk[i] * r[k];
                for (int j = 0; j < 3; ++j) {
                    H[3 * i + j] += Jk[i] * Jk[j];
                }
            }
        }
        rp_mat_t Hm = RP_MAT(3, 3, H), gm = RP_MAT(3, 1, g);
        if (rp_la_chol(&Hm, &Hm) != RP_OK || rp_la_chol_solve(&Hm, &gm, &gm) != RP_OK) {
            break;
        }
        const rp_real Pn[3] = {P[0] + g[0], P[1] + g[1], P[2] + g[2]};
        rp_real rn[4], Jn[12];
        if (reproject(rig, sp, uv_a, uv_b, Pn, rn, Jn) != RP_OK) {
            break;
        }
        const rp_real cn = rn[0] * rn[0] + rn[1] * rn[1] + rn[2] * rn[2] + rn[3] * rn[3];
        if (!(cn <= cost)) {
            break;
        }
        cost = cn;
        for (int i = 0; i < 3; ++i) {
            P[i] = Pn[i];
        }
        for (int i = 0; i < 4; ++i) {
            r[i] = rn[i];
        }
        for (int i = 0; i < 12; ++i) {
            J[i] = Jn[i];
        }
        if (norm3(g) <= RP_STEREO_GN_TOL * norm3(P)) {
            break;
        }
    }
    if (!rp_all_finite(P, 3)) {
        return RP_E_NAN;
    }
    /* Depth in both cameras (reproject already refused points behind either). */
    P_a[0] = P[0];
    P_a[1] = P[1];
    P_a[2] = P[2];
    if (reproj_px != NULL) {
        *reproj_px = max_reproj(r);
    }
    return RP_OK;
}
