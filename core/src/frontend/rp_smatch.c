/*
 * rp_smatch.c - left-right matching of a stereo pair's features along epipolar curves
 * (rp_smatch.h has the method).
 *
 * Fixed-point formats:
 *   positions    int32 Q16 pixels of a level (origin at the top-left pixel centre)
 *   windows      int16 grey levels in Q5 (x 32), bilinear weights Q14 (sum 2^14)
 *   sums         int64: sum Q5, sum of squares and cross products Q10
 *   scores       ZNCC in Q15 (int16, 32767 = 1); only the final ratio of the integer sums is
 *                taken in rp_real (num / sqrt(var_T var_R))
 * Geometry (rays, projection, the curve's anchors, the sub-pixel steps) is rp_real.
 */
#include "rigpose/rp_smatch.h"

#include <stddef.h>
#include <string.h>

#include "priv/rp_math.h"
#include "priv/rp_v8.h"
#include "rigpose/rp_camera.h"

#define Q16 65536
#define HW_MAX 7
#define AREA_MAX ((2 * HW_MAX + 1) * (2 * HW_MAX + 1))
#define N_ANCHORS 33        /* curve anchors, uniform in inverse depth */
#define SCORE_NONE INT16_MIN /* no score: window outside the image */
#define UNIQ_EXCLUDE 2      /* a second peak must be farther than this many coarse steps */

/* ---- windows ------------------------------------------------------------------------------ */

typedef struct {
    const uint8_t *p;
    int w, h; /* pixels; row stride is w (rp_pyr_t levels are packed) */
} lev_t;

static lev_t level_of(const rp_pyr_t *pyr, int l)
{
    lev_t L;
    L.p = pyr->pix + pyr->lev[l].off;
    L.w = pyr->lev[l].w;
    L.h = pyr->lev[l].h;
    return L;
}

/* A (2 hw + 1)^2 window of grey levels (Q5) and its sums. */
typedef struct {
    int hw, n;
    int16_t v[AREA_MAX];
    int64_t s;  /* sum, Q5 */
    int64_t s2; /* sum of squares, Q10 */
    rp_real sd; /* sqrt(n s2 - s^2): n^2 x the standard deviation, Q5 */
} win_t;

/* Samples the window centred on level position (x_q16, y_q16) bilinearly (integer positions
 * copy). Returns 0 if the window (and its right / lower interpolation neighbours) leaves the
 * level image. */
static int win_sample(const lev_t *L, int32_t x_q16, int32_t y_q16, int hw, win_t *W)
{
    const int32_t ox = x_q16 - hw * Q16, oy = y_q16 - hw * Q16;
    const int ix = ox >> 16, iy = oy >> 16; /* floor (arithmetic shift) */
    const int side = 2 * hw + 1;
    if (ix < 0 || iy < 0 || ix + side >= L->w || iy + side >= L->h) {
        return 0;
    }
    const int32_t fx = ox & 0xffff, fy = oy & 0xffff;
    W->hw = hw;
    W->n = side * side;
    int64_t s = 0, s2 = 0;
    int16_t *v = W->v;
    if (fx == 0 && fy == 0) {
        for (int y = 0; y < side; ++y) {
            const uint8_t *r = L->p + (size_t)(iy + y) * L->w + ix;
            for (int x = 0; x < side; ++x) {
                const int32_t q = (int32_t)r[x] << 5;
                *v++ = (int16_t)q;
                s += q;
                s2 += q * q;
            }
        }
    } else {
        /* Q16 x Q16 -> Q14 weights, rounded, summing to 2^14 */
        const int64_t a = fx, b = fy, one = Q16;
        const int32_t w00 = (int32_t)(((one - a) * (one - b) + (1 << 17)) >> 18);
        const int32_t w10 = (int32_t)((a * (one - b) + (1 << 17)) >> 18);
        const int32_t w01 = (int32_t)(((one - a) * b + (1 << 17)) >> 18);
        const int32_t w11 = (1 << 14) - w00 - w10 - w01;
        for (int y = 0; y < side; ++y) {
            const uint8_t *r0 = L->p + (size_t)(iy + y) * L->w + ix;
            const uint8_t *r1 = r0 + L->w;
            for (int x = 0; x < side; ++x) {
                /* grey x Q14 = Q14 -> Q5: >> 9, rounded; <= 255 * 32 */
                const int32_t q =
                    (w00 * r0[x] + w10 * r0[x + 1] + w01 * r1[x] + w11 * r1[x + 1] + 256) >> 9;
                *v++ = (int16_t)q;
                s += q;
                s2 += q * q;
            }
        }
    }
    W->s = s;
    W->s2 = s2;
    const int64_t var = (int64_t)W->n * s2 - s * s;
    W->sd = var > 0 ? rp_sqrt((rp_real)var) : RP_C(0.0);
    return 1;
}

/* num / den (den > 0) in Q15, rounded, within +-32767. */
static int16_t score_q15(int64_t num, rp_real den)
{
    rp_real z = (rp_real)num / den * RP_C(32767.0);
    z = z > RP_C(32767.0) ? RP_C(32767.0) : (z < RP_C(-32767.0) ? RP_C(-32767.0) : z);
    return (int16_t)(z >= RP_C(0.0) ? z + RP_C(0.5) : z - RP_C(0.5));
}

/* ZNCC of two windows of one size, Q15; 0 if either is flat. */
static int16_t zncc_q15(const win_t *T, const win_t *R)
{
    if (!(T->sd > RP_C(0.0)) || !(R->sd > RP_C(0.0))) {
        return 0;
    }
    int64_t sTR = 0;
    for (int i = 0; i < T->n; ++i) {
        sTR += (int32_t)T->v[i] * R->v[i];
    }
    return score_q15((int64_t)T->n * sTR - T->s * R->s, T->sd * R->sd);
}

/* ZNCC (Q15) of template T against the level image's window centred on integer pixel (x, y),
 * in one pass (int32 sums: window <= 15x15, T in Q5 <= 8160, grey <= 255); SCORE_NONE if the
 * window leaves the image, 0 if either side is flat. The first 8 columns of each row go through
 * one lane group (priv/rp_v8.h: a lane pair adds at most 2 x 255 x 8160 < 2^22 per row), the
 * others one by one; the integer sums are the same either way. */
static int16_t zncc_int(const lev_t *L, int x, int y, const win_t *T)
{
    const int hw = T->hw, side = 2 * hw + 1;
    if (x - hw < 0 || y - hw < 0 || x + hw >= L->w || y + hw >= L->h) {
        return SCORE_NONE;
    }
    const int nv = side >= 8 ? 8 : 0; /* columns in the lane group */
    const v8_t one = v8_set(1);
    v4_t vs = v4_zero(), vs2 = v4_zero(), vtr = v4_zero();
    int32_t s = 0, s2 = 0, sTR = 0;
    const int16_t *t = T->v;
    for (int r = 0; r < side; ++r) {
        const uint8_t *p = L->p + (size_t)(y - hw + r) * L->w + (x - hw);
        if (nv > 0) {
            const v8_t q = v8_ld_u8(p);
            vs = v4_add(vs, v8_madd(q, one));
            vs2 = v4_add(vs2, v8_madd(q, q));
            vtr = v4_add(vtr, v8_madd(q, v8_ld(t)));
        }
        for (int c = nv; c < side; ++c) {
            const int32_t q = p[c];
            s += q;
            s2 += q * q;
            sTR += q * t[c];
        }
        t += side;
    }
    s += (int32_t)v4_sum(vs);
    s2 += (int32_t)v4_sum(vs2);
    sTR += (int32_t)v4_sum(vtr);
    const int64_t var = (int64_t)T->n * s2 - (int64_t)s * s;
    if (var <= 0 || !(T->sd > RP_C(0.0))) {
        return 0;
    }
    return score_q15((int64_t)T->n * sTR - T->s * s, T->sd * rp_sqrt((rp_real)var));
}

static int32_t to_q16(rp_real x) { return (int32_t)rp_floor(x * RP_C(65536.0) + RP_C(0.5)); }

/* ---- epipolar curves ---------------------------------------------------------------------- */

/* The geometry of one search direction: the ray r of a source pixel (normalised, z = 1) seen
 * from the destination camera is V(w) = M r + w c, w the inverse depth along the source's z. */
typedef struct {
    rp_real M[9];
    rp_real c[3];
    const rp_camera_t *src, *dst;
} dir_t;

/* Samples the epipolar curve of source pixel uv in the destination image at about `step`
 * level-0 pixels apart into sm->curve (level-0 Q16). Returns the number of samples (0: the ray
 * has no undistortion, or no part of the curve within the depth range lies in the image). */
static int make_curve(rp_smatch_t *sm, const dir_t *g, const rp_real uv[2], rp_real step)
{
    rp_real xn[2];
    if (rp_cam_unproject(g->src, uv, xn) != RP_OK) {
        return 0;
    }
    const rp_real r[3] = {xn[0], xn[1], RP_C(1.0)};
    rp_real q[3];
    for (int i = 0; i < 3; ++i) {
        q[i] = g->M[3 * i] * r[0] + g->M[3 * i + 1] * r[1] + g->M[3 * i + 2] * r[2];
    }
    const rp_real w_lo = RP_C(1.0) / sm->cfg.max_depth_m, w_hi = RP_C(1.0) / sm->cfg.min_depth_m;
    const rp_real umax = (rp_real)g->dst->width - RP_C(0.5);
    const rp_real vmax = (rp_real)g->dst->height - RP_C(0.5);
    rp_real A[N_ANCHORS][2];
    int ok[N_ANCHORS];
    rp_real total = RP_C(0.0);
    for (int k = 0; k < N_ANCHORS; ++k) {
        const rp_real w = w_lo + (w_hi - w_lo) * (rp_real)k / (rp_real)(N_ANCHORS - 1);
        const rp_real V[3] = {q[0] + w * g->c[0], q[1] + w * g->c[1], q[2] + w * g->c[2]};
        ok[k] = rp_cam_project(g->dst, V, A[k], NULL) == RP_OK && A[k][0] > RP_C(-64.0) &&
                A[k][1] > RP_C(-64.0) && A[k][0] < umax + RP_C(64.0) &&
                A[k][1] < vmax + RP_C(64.0);
        if (k > 0 && ok[k] && ok[k - 1]) {
            const rp_real du = A[k][0] - A[k - 1][0], dv = A[k][1] - A[k - 1][1];
            total += rp_sqrt(du * du + dv * dv);
        }
    }
    if (total > step * (rp_real)(RP_SMATCH_MAX_STEPS - N_ANCHORS)) {
        step = total / (rp_real)(RP_SMATCH_MAX_STEPS - N_ANCHORS); /* long curve: coarser */
    }
    int n = 0;
    for (int k = 1; k < N_ANCHORS; ++k) {
        if (!ok[k] || !ok[k - 1]) {
            continue;
        }
        const rp_real du = A[k][0] - A[k - 1][0], dv = A[k][1] - A[k - 1][1];
        const rp_real len = rp_sqrt(du * du + dv * dv);
        int m = (int)(len / step) + 1;
        const int last = k == N_ANCHORS - 1 || !ok[k + 1]; /* also emit the segment's end */
        for (int j = 0; j < m + last; ++j) {
            const rp_real t = (rp_real)j / (rp_real)m;
            const rp_real u = A[k - 1][0] + t * du, v = A[k - 1][1] + t * dv;
            if (u < RP_C(0.0) || v < RP_C(0.0) || u > umax || v > vmax || n >= RP_SMATCH_MAX_STEPS) {
                continue;
            }
            sm->curve[n].u_q16 = to_q16(u);
            sm->curve[n].v_q16 = to_q16(v);
            ++n;
        }
    }
    return n;
}

/* Point at curve parameter t (sample index, fractional), level-0 pixels. */
static void curve_at(const rp_smatch_t *sm, int n, rp_real t, rp_real uv[2])
{
    int i = (int)rp_floor(t);
    i = i < 0 ? 0 : (i > n - 2 ? n - 2 : i);
    const rp_real f = t - (rp_real)i;
    const rp_smatch_pt_t *a = &sm->curve[i], *b = &sm->curve[i + 1 < n ? i + 1 : i];
    uv[0] = ((rp_real)a->u_q16 + f * (rp_real)(b->u_q16 - a->u_q16)) / RP_C(65536.0);
    uv[1] = ((rp_real)a->v_q16 + f * (rp_real)(b->v_q16 - a->v_q16)) / RP_C(65536.0);
}

/* Vertex offset in [-0.5, 0.5] of the parabola through scores (l, c, r), c the largest. */
static rp_real parabola(int16_t l, int16_t c, int16_t r)
{
    if (l == SCORE_NONE || r == SCORE_NONE) {
        return RP_C(0.0);
    }
    const rp_real den = (rp_real)((int32_t)l - 2 * (int32_t)c + (int32_t)r);
    if (!(den < RP_C(0.0))) {
        return RP_C(0.0);
    }
    rp_real d = RP_C(0.5) * (rp_real)((int32_t)l - (int32_t)r) / den;
    return d > RP_C(0.5) ? RP_C(0.5) : (d < RP_C(-0.5) ? RP_C(-0.5) : d);
}

/* ---- one search ---------------------------------------------------------------------------- */

enum { HIT = 0, MISS_OUTSIDE, MISS_FLAT, MISS_LOW, MISS_AMBIGUOUS };

typedef struct {
    rp_real uv[2];  /* level-0 match in the destination, pixels */
    rp_real dir[2]; /* unit tangent of the curve there */
    int16_t score;  /* fine ZNCC, Q15 */
    win_t T0;       /* source template at level 0 */
} hit_t;

/* Search the epipolar curve of source pixel uv: coarse over the whole curve at level lv, fine
 * at level 0 around the best, sub-pixel by a parabola. Returns HIT or a MISS_ reason. */
static int search(rp_smatch_t *sm, const dir_t *g, const rp_pyr_t *src, const rp_pyr_t *dst,
                  int lv, const rp_real uv[2], hit_t *hit)
{
    const rp_smatch_cfg_t *cfg = &sm->cfg;
    const int hw = cfg->half_win;
    const lev_t s0 = level_of(src, 0), d0 = level_of(dst, 0);
    win_t Tl, W;
    if (!win_sample(&s0, to_q16(uv[0]), to_q16(uv[1]), hw, &hit->T0)) {
        return MISS_OUTSIDE;
    }
    /* flat: n^2 var < (n min_std 32)^2 */
    if (hit->T0.sd < (rp_real)hit->T0.n * (rp_real)cfg->min_std * RP_C(32.0)) {
        return MISS_FLAT;
    }
    const int S = 1 << lv, hwc = lv > 0 ? (hw - 1 < 2 ? 2 : hw - 1) : hw;
    const int n = make_curve(sm, g, uv, (rp_real)S);
    if (n < 2) {
        return MISS_OUTSIDE;
    }
    const lev_t sl = level_of(src, lv), dl = level_of(dst, lv);
    if (!win_sample(&sl, to_q16(uv[0] / (rp_real)S), to_q16(uv[1] / (rp_real)S), hwc, &Tl)) {
        return MISS_OUTSIDE;
    }
    /* coarse */
    int best = -1;
    for (int i = 0; i < n; ++i) {
        const int x = (sm->curve[i].u_q16 / S + Q16 / 2) >> 16;
        const int y = (sm->curve[i].v_q16 / S + Q16 / 2) >> 16;
        sm->score[i] = zncc_int(&dl, x, y, &Tl);
        if (sm->score[i] != SCORE_NONE && (best < 0 || sm->score[i] > sm->score[best])) {
            best = i;
        }
    }
    if (best < 0) {
        return MISS_OUTSIDE;
    }
    /* a best sample at an end of the part of the curve inside the image is no peak: the true
     * match may lie beyond the border, and its window is cut there */
    if (best == 0 || best == n - 1 || sm->score[best - 1] == SCORE_NONE ||
        sm->score[best + 1] == SCORE_NONE) {
        return MISS_OUTSIDE;
    }
    /* hopeless already at the coarse level: under min - (1 - min) (0.6 for 0.8) */
    if ((int32_t)sm->score[best] < 2 * (int32_t)cfg->min_zncc_q15 - 32767) {
        return MISS_LOW;
    }
    /* uniqueness: the best other local maximum */
    int32_t second = SCORE_NONE;
    for (int i = 0; i < n; ++i) {
        const int16_t s = sm->score[i];
        if (s == SCORE_NONE || (i - best <= UNIQ_EXCLUDE && best - i <= UNIQ_EXCLUDE) ||
            (i > 0 && sm->score[i - 1] > s) || (i + 1 < n && sm->score[i + 1] > s)) {
            continue;
        }
        second = s > second ? s : second;
    }
    if (second != SCORE_NONE && (int32_t)sm->score[best] - second < cfg->uniq_margin_q15) {
        return MISS_AMBIGUOUS;
    }
    /* fine: level 0, one step per pixel from sample best - 1 to best + 1 */
    enum { FINE_MAX = 2 * (1 << (RP_TRACK_MAX_LEVELS - 1)) + 1 };
    int16_t fs[FINE_MAX];
    const int nf = 2 * S + 1;
    int fb = -1;
    for (int j = 0; j < nf; ++j) {
        rp_real p[2];
        curve_at(sm, n, (rp_real)best - RP_C(1.0) + (rp_real)j / (rp_real)S, p);
        fs[j] = win_sample(&d0, to_q16(p[0]), to_q16(p[1]), hw, &W) ? zncc_q15(&hit->T0, &W)
                                                                     : SCORE_NONE;
        if (fs[j] != SCORE_NONE && (fb < 0 || fs[j] > fs[fb])) {
            fb = j;
        }
    }
    if (fb < 0) {
        return MISS_OUTSIDE;
    }
    if (fs[fb] < cfg->min_zncc_q15) {
        return MISS_LOW;
    }
    const rp_real off = (fb > 0 && fb < nf - 1) ? parabola(fs[fb - 1], fs[fb], fs[fb + 1])
                                                : RP_C(0.0);
    const rp_real t = (rp_real)best - RP_C(1.0) + ((rp_real)fb + off) / (rp_real)S;
    curve_at(sm, n, t, hit->uv);
    rp_real a[2], b[2];
    curve_at(sm, n, t - RP_C(1.0), a);
    curve_at(sm, n, t + RP_C(1.0), b);
    const rp_real du = b[0] - a[0], dv = b[1] - a[1], len = rp_sqrt(du * du + dv * dv);
    hit->dir[0] = len > RP_C(0.0) ? du / len : RP_C(1.0);
    hit->dir[1] = len > RP_C(0.0) ? dv / len : RP_C(0.0);
    hit->score = fs[fb];
    return HIT;
}

/* 1-D Lucas-Kanade along hit->dir: minimises sum (R(x + s d) - mean_R - g (T - mean_T))^2 over
 * s, g = sd_R / sd_T (gain), the derivative along d from windows sampled at +-1 px. At most
 * `iters` steps, each clamped to 1 px, |s| <= 1.5 px. */
static void refine_1d(const rp_pyr_t *dst, hit_t *hit, int iters)
{
    const lev_t d0 = level_of(dst, 0);
    const win_t *T = &hit->T0;
    const int hw = T->hw;
    win_t R, Rp, Rm;
    rp_real s = RP_C(0.0);
    for (int it = 0; it < iters; ++it) {
        const rp_real x = hit->uv[0] + s * hit->dir[0], y = hit->uv[1] + s * hit->dir[1];
        if (!win_sample(&d0, to_q16(x), to_q16(y), hw, &R) ||
            !win_sample(&d0, to_q16(x + hit->dir[0]), to_q16(y + hit->dir[1]), hw, &Rp) ||
            !win_sample(&d0, to_q16(x - hit->dir[0]), to_q16(y - hit->dir[1]), hw, &Rm) ||
            !(R.sd > RP_C(0.0)) || !(T->sd > RP_C(0.0))) {
            break;
        }
        const rp_real gain = R.sd / T->sd;
        const rp_real mR = (rp_real)R.s / (rp_real)R.n, mT = (rp_real)T->s / (rp_real)T->n;
        int64_t sg = 0;
        for (int i = 0; i < R.n; ++i) {
            sg += (int32_t)Rp.v[i] - Rm.v[i];
        }
        const rp_real mg = (rp_real)sg / (rp_real)(2 * R.n);
        rp_real sge = RP_C(0.0), sgg = RP_C(0.0);
        for (int i = 0; i < R.n; ++i) {
            const rp_real gi = RP_C(0.5) * (rp_real)((int32_t)Rp.v[i] - Rm.v[i]) - mg;
            const rp_real e = ((rp_real)R.v[i] - mR) - gain * ((rp_real)T->v[i] - mT);
            sge += gi * e;
            sgg += gi * gi;
        }
        if (!(sgg > RP_C(0.0))) {
            break;
        }
        rp_real ds = -sge / sgg;
        ds = ds > RP_C(1.0) ? RP_C(1.0) : (ds < RP_C(-1.0) ? RP_C(-1.0) : ds);
        s += ds;
        if (s > RP_C(1.5) || s < RP_C(-1.5)) {
            s = s > RP_C(0.0) ? RP_C(1.5) : RP_C(-1.5);
            break;
        }
        if (rp_fabs(ds) < RP_C(0.01)) {
            break;
        }
    }
    hit->uv[0] += s * hit->dir[0];
    hit->uv[1] += s * hit->dir[1];
}

/* 2-D Lucas-Kanade of the match: minimises sum (R(x + s) - mean_R - g (T - mean_T))^2 over
 * s = (su, sv), g = sd_R / sd_T (gain), the image gradient from windows sampled at +-1 px in u
 * and v. At most `iters` steps, each clamped to 1 px, |s| <= 1.5 px per axis. Unlike a search
 * along the epipolar curve alone, the match does not take up the calibration's error across
 * the curve as a shift along it (on an edge slanted by theta, a curve off by e across it moves
 * a 1-D match by e cot theta along it). Returns 0 if it left the image or diverged (hit
 * unchanged). */
static int refine_2d(const rp_pyr_t *dst, hit_t *hit, int iters)
{
    const lev_t d0 = level_of(dst, 0);
    const win_t *T = &hit->T0;
    const int hw = T->hw;
    win_t R, Ru, Rl, Rd, Rt;
    rp_real su = RP_C(0.0), sv = RP_C(0.0);
    for (int it = 0; it < iters; ++it) {
        const rp_real x = hit->uv[0] + su, y = hit->uv[1] + sv;
        if (!win_sample(&d0, to_q16(x), to_q16(y), hw, &R) ||
            !win_sample(&d0, to_q16(x + RP_C(1.0)), to_q16(y), hw, &Ru) ||
            !win_sample(&d0, to_q16(x - RP_C(1.0)), to_q16(y), hw, &Rl) ||
            !win_sample(&d0, to_q16(x), to_q16(y + RP_C(1.0)), hw, &Rd) ||
            !win_sample(&d0, to_q16(x), to_q16(y - RP_C(1.0)), hw, &Rt) ||
            !(R.sd > RP_C(0.0)) || !(T->sd > RP_C(0.0))) {
            return 0;
        }
        const rp_real gain = R.sd / T->sd;
        const rp_real mR = (rp_real)R.s / (rp_real)R.n, mT = (rp_real)T->s / (rp_real)T->n;
        int64_t sgu = 0, sgv = 0;
        for (int i = 0; i < R.n; ++i) {
            sgu += (int32_t)Ru.v[i] - Rl.v[i];
            sgv += (int32_t)Rd.v[i] - Rt.v[i];
        }
        const rp_real mgu = (rp_real)sgu / (rp_real)(2 * R.n);
        const rp_real mgv = (rp_real)sgv / (rp_real)(2 * R.n);
        rp_real a = RP_C(0.0), b = RP_C(0.0), c = RP_C(0.0), eu = RP_C(0.0), ev = RP_C(0.0);
        for (int i = 0; i < R.n; ++i) {
            const rp_real gu = RP_C(0.5) * (rp_real)((int32_t)Ru.v[i] - Rl.v[i]) - mgu;
            const rp_real gv = RP_C(0.5) * (rp_real)((int32_t)Rd.v[i] - Rt.v[i]) - mgv;
            const rp_real e = ((rp_real)R.v[i] - mR) - gain * ((rp_real)T->v[i] - mT);
            a += gu * gu;
            b += gu * gv;
            c += gv * gv;
            eu += gu * e;
            ev += gv * e;
        }
        const rp_real det = a * c - b * b;
        if (!(det > RP_C(1e-6) * (a * c)) || !(det > RP_C(0.0))) {
            return 0; /* an edge: the window fixes one direction only */
        }
        rp_real du = -(c * eu - b * ev) / det, dv = -(a * ev - b * eu) / det;
        du = du > RP_C(1.0) ? RP_C(1.0) : (du < RP_C(-1.0) ? RP_C(-1.0) : du);
        dv = dv > RP_C(1.0) ? RP_C(1.0) : (dv < RP_C(-1.0) ? RP_C(-1.0) : dv);
        su += du;
        sv += dv;
        if (rp_fabs(su) > RP_C(1.5) || rp_fabs(sv) > RP_C(1.5)) {
            return 0;
        }
        if (rp_fabs(du) < RP_C(0.01) && rp_fabs(dv) < RP_C(0.01)) {
            break;
        }
    }
    hit->uv[0] += su;
    hit->uv[1] += sv;
    return 1;
}

/* ---- public -------------------------------------------------------------------------------- */

rp_status_t rp_smatch_default_cfg(rp_smatch_cfg_t *cfg)
{
    if (cfg == NULL) {
        return RP_E_ARG;
    }
    memset(cfg, 0, sizeof(*cfg));
    cfg->half_win = 4;
    cfg->min_zncc_q15 = 26214;  /* 0.8 */
    cfg->uniq_margin_q15 = 1638; /* 0.05 */
    cfg->min_std = 4;
    cfg->min_depth_m = RP_C(0.2);
    cfg->max_depth_m = RP_C(100.0);
    cfg->lr_max_px = RP_C(1.0);
    cfg->max_epipolar_px = RP_C(1.0);
    cfg->subpix_iter = 5;
    cfg->search_level = 0;
    return RP_OK;
}

rp_status_t rp_smatch_init(rp_smatch_t *sm, const rp_smatch_cfg_t *cfg)
{
    if (sm == NULL || cfg == NULL) {
        return RP_E_ARG;
    }
    if (cfg->half_win < 2 || cfg->half_win > HW_MAX || cfg->min_zncc_q15 < 0 ||
        cfg->uniq_margin_q15 < 0 || !(cfg->min_depth_m > RP_C(0.0)) ||
        !(cfg->max_depth_m > cfg->min_depth_m) || !rp_finite(cfg->max_depth_m) ||
        !(cfg->lr_max_px > RP_C(0.0)) || !(cfg->max_epipolar_px > RP_C(0.0)) ||
        cfg->search_level >= RP_TRACK_MAX_LEVELS) {
        return RP_E_ARG;
    }
    sm->cfg = *cfg;
    return RP_OK;
}

static int pyr_matches(const rp_pyr_t *pyr, const rp_camera_t *cam)
{
    return pyr->n_lev >= 1 && pyr->n_lev <= RP_TRACK_MAX_LEVELS && pyr->lev[0].w == cam->width &&
           pyr->lev[0].h == cam->height;
}

rp_status_t rp_smatch_pair(rp_smatch_t *sm, const rp_rig_t *rig, const rp_stereo_pair_t *sp,
                           const rp_pyr_t *pyr_a, const rp_pyr_t *pyr_b,
                           const rp_feat_t *fa, uint16_t n_a, rp_feat_t *fb, uint16_t cap,
                           uint16_t *n_b, rp_smatch_stats_t *stats)
{
    if (sm == NULL || rig == NULL || sp == NULL || pyr_a == NULL || pyr_b == NULL ||
        (fa == NULL && n_a > 0) || (fb == NULL && cap > 0) || n_b == NULL) {
        return RP_E_ARG;
    }
    if (rig->n_cams > RP_MAX_CAMS || sp->a >= rig->n_cams || sp->b >= rig->n_cams ||
        sp->a == sp->b) {
        return RP_E_ARG;
    }
    const rp_camera_t *ca = &rig->cam[sp->a].cam, *cb = &rig->cam[sp->b].cam;
    if (!pyr_matches(pyr_a, ca) || !pyr_matches(pyr_b, cb)) {
        return RP_E_ARG;
    }
    *n_b = 0;
    rp_smatch_stats_t st;
    memset(&st, 0, sizeof(st));
    st.n_in = n_a;
    int lv = sm->cfg.search_level;
    lv = lv > pyr_a->n_lev - 1 ? pyr_a->n_lev - 1 : lv;
    lv = lv > pyr_b->n_lev - 1 ? pyr_b->n_lev - 1 : lv;
    /* forward: V = R_ab^T r_a - w R_ab^T t_ab; backward: V = R_ab r_b + w t_ab */
    dir_t fw, bw;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            fw.M[3 * i + j] = sp->R_ab[3 * j + i];
            bw.M[3 * i + j] = sp->R_ab[3 * i + j];
        }
    }
    for (int i = 0; i < 3; ++i) {
        fw.c[i] = -(sp->R_ab[i] * sp->t_ab[0] + sp->R_ab[3 + i] * sp->t_ab[1] +
                    sp->R_ab[6 + i] * sp->t_ab[2]);
        bw.c[i] = sp->t_ab[i];
    }
    fw.src = ca;
    fw.dst = cb;
    bw.src = cb;
    bw.dst = ca;
    rp_status_t ret = RP_OK;
    for (uint16_t k = 0; k < n_a; ++k) {
        if (!rp_finite(fa[k].uv[0]) || !rp_finite(fa[k].uv[1])) {
            ret = RP_E_NAN;
            st.n_outside++;
            continue;
        }
        hit_t h, back;
        int r = search(sm, &fw, pyr_a, pyr_b, lv, fa[k].uv, &h);
        if (r == HIT) {
            refine_1d(pyr_b, &h, sm->cfg.subpix_iter);
            (void)refine_2d(pyr_b, &h, 2 * sm->cfg.subpix_iter); /* 0: the 1-D match stays */
            const int rb = search(sm, &bw, pyr_b, pyr_a, lv, h.uv, &back);
            const rp_real dx = back.uv[0] - fa[k].uv[0], dy = back.uv[1] - fa[k].uv[1];
            if (rb != HIT || !(dx * dx + dy * dy <= sm->cfg.lr_max_px * sm->cfg.lr_max_px)) {
                st.n_lr_fail++;
                continue;
            }
            rp_real d = RP_C(0.0);
            if (rp_stereo_epipolar_px(rig, sp, fa[k].uv, h.uv, &d) != RP_OK ||
                !(d <= sm->cfg.max_epipolar_px)) {
                st.n_epi_fail++;
                continue;
            }
            st.n_matched++;
            if (*n_b >= cap) {
                ret = ret == RP_OK ? RP_E_FULL : ret;
                continue;
            }
            fb[*n_b].id = fa[k].id;
            fb[*n_b].uv[0] = h.uv[0];
            fb[*n_b].uv[1] = h.uv[1];
            ++*n_b;
        } else if (r == MISS_OUTSIDE) {
            st.n_outside++;
        } else if (r == MISS_FLAT) {
            st.n_flat++;
        } else if (r == MISS_LOW) {
            st.n_low_score++;
        } else {
            st.n_ambiguous++;
        }
    }
    if (stats != NULL) {
        *stats = st;
    }
    return ret;
}
