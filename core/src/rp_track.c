/*
 * rp_track.c - pyramids, Shi-Tomasi detection with bucketing, pyramidal Lucas-Kanade with a
 * forward-backward check (rp_track.h). Integer arithmetic only; formats named where used.
 * The LK step follows OpenCV's calcOpticalFlowPyrLK (Bouguet's pyramidal LK): Scharr gradients of
 * the previous image, Q14 bilinear weights, intensities in Q5, the 2x2 normal equations solved per
 * iteration; here the sums are exact int64 and the solve is integer.
 */
#include <math.h>
#include <string.h>

#include "priv/rp_math.h"
#include "rigpose/rp_track.h"

#define Q16 65536

/* ---- small integer helpers ------------------------------------------------------------------ */

/* floor(sqrt(x)) for x < 2^52: the FPU's square root of x (exact in a double, correctly rounded
 * by IEEE 754) truncated, then corrected by one step. One hardware instruction instead of a bit
 * loop; the result is the same integer on every IEEE platform. */
static uint32_t isqrt52(uint64_t x)
{
    uint64_t r = (uint64_t)sqrt((double)x);
    if (r * r > x) {
        --r;
    } else if ((r + 1) * (r + 1) <= x) {
        ++r;
    }
    return (uint32_t)r;
}

static int64_t iabs64(int64_t x) { return x < 0 ? -x : x; }

/* Reflect-101 border index (cv::BORDER_REFLECT_101) for i in [-n+1, 2n-2]. */
static int refl101(int i, int n)
{
    if (n == 1) {
        return 0;
    }
    if (i < 0) {
        i = -i;
    }
    if (i >= n) {
        i = 2 * n - 2 - i;
    }
    return i;
}

static int clampi(int i, int lo, int hi) { return i < lo ? lo : (i > hi ? hi : i); }

/* ---- image checks and pyramid --------------------------------------------------------------- */

static rp_status_t check_image(const rp_image_t *img, unsigned min_side)
{
    if (img == NULL || img->data == NULL) {
        return RP_E_ARG;
    }
    if (img->w < min_side || img->h < min_side || img->w > RP_TRACK_MAX_W ||
        img->h > RP_TRACK_MAX_H || img->stride < img->w) {
        return RP_E_ARG;
    }
    if ((uint64_t)img->size < (uint64_t)img->stride * (img->h - 1u) + img->w) {
        return RP_E_ARG; /* truncated */
    }
    return RP_OK;
}

rp_status_t rp_pyr_build(rp_pyr_t *pyr, const rp_image_t *img, uint8_t levels)
{
    if (pyr == NULL || levels < 1 || levels > RP_TRACK_MAX_LEVELS) {
        return RP_E_ARG;
    }
    rp_status_t st = check_image(img, 5);
    if (st != RP_OK) {
        return st;
    }
    uint32_t off = 0;
    pyr->lev[0].off = 0;
    pyr->lev[0].w = img->w;
    pyr->lev[0].h = img->h;
    for (unsigned v = 0; v < img->h; ++v) {
        memcpy(pyr->pix + (size_t)v * img->w, img->data + (size_t)v * img->stride, img->w);
    }
    off = (uint32_t)img->w * img->h;
    pyr->n_lev = 1;
    int32_t rowsum[RP_TRACK_MAX_W]; /* vertical 5-tap sums, <= 16 * 255 */
    for (unsigned l = 1; l < levels; ++l) {
        const rp_pyr_level_t *s = &pyr->lev[l - 1];
        const int sw = s->w, sh = s->h;
        const int dw = (sw + 1) / 2, dh = (sh + 1) / 2;
        if (dw < 5 || dh < 5) {
            break; /* too small to be useful: fewer levels */
        }
        rp_pyr_level_t *d = &pyr->lev[l];
        d->off = off;
        d->w = (uint16_t)dw;
        d->h = (uint16_t)dh;
        const uint8_t *sp = pyr->pix + s->off;
        uint8_t *dp = pyr->pix + d->off;
        for (int y = 0; y < dh; ++y) {
            const uint8_t *r0 = sp + (size_t)refl101(2 * y - 2, sh) * sw;
            const uint8_t *r1 = sp + (size_t)refl101(2 * y - 1, sh) * sw;
            const uint8_t *r2 = sp + (size_t)refl101(2 * y, sh) * sw;
            const uint8_t *r3 = sp + (size_t)refl101(2 * y + 1, sh) * sw;
            const uint8_t *r4 = sp + (size_t)refl101(2 * y + 2, sh) * sw;
            for (int x = 0; x < sw; ++x) {
                rowsum[x] = r0[x] + 4 * (r1[x] + r3[x]) + 6 * r2[x] + r4[x];
            }
            for (int x = 0; x < dw; ++x) {
                const int c = 2 * x;
                int32_t sum;
                if (c >= 2 && c + 2 < sw) {
                    sum = rowsum[c - 2] + 4 * (rowsum[c - 1] + rowsum[c + 1]) + 6 * rowsum[c] +
                          rowsum[c + 2];
                } else {
                    sum = rowsum[refl101(c - 2, sw)] +
                          4 * (rowsum[refl101(c - 1, sw)] + rowsum[refl101(c + 1, sw)]) +
                          6 * rowsum[c] + rowsum[refl101(c + 2, sw)];
                }
                dp[(size_t)y * dw + x] = (uint8_t)((sum + 128) >> 8); /* <= 255, no saturation */
            }
        }
        off += (uint32_t)dw * dh;
        pyr->n_lev = (uint8_t)(l + 1);
    }
    return RP_OK;
}

/* ---- configuration -------------------------------------------------------------------------- */

rp_status_t rp_track_default_cfg(rp_track_cfg_t *cfg)
{
    if (cfg == NULL) {
        return RP_E_ARG;
    }
    memset(cfg, 0, sizeof(*cfg));
    cfg->cam = 0;
    cfg->levels = RP_TRACK_MAX_LEVELS < 4 ? RP_TRACK_MAX_LEVELS : 4;
    cfg->win = RP_TRACK_MAX_WIN < 21 ? RP_TRACK_MAX_WIN : 21;
    cfg->max_iter = 30;
    cfg->eps_q16 = 655;
    cfg->min_eig = 105;
    cfg->fb_max_q16 = Q16;
    cfg->target = RP_MAX_FEATS_PER_CAM < 150 ? RP_MAX_FEATS_PER_CAM : 150;
    cfg->topup_below = (uint16_t)(cfg->target * 4 / 5);
    cfg->min_dist = 10;
    cfg->quality_q16 = 655;
    cfg->min_response = 2000;
    cfg->grid_x = 8;
    cfg->grid_y = 6;
    cfg->cell_cap = 0;
    cfg->min_contrast = 8;
    cfg->max_err_q5 = 20 * 32;
    return RP_OK;
}

rp_status_t rp_track_init(rp_tracker_t *trk, const rp_track_cfg_t *cfg)
{
    if (trk == NULL || cfg == NULL) {
        return RP_E_ARG;
    }
    if (cfg->cam >= RP_MAX_CAMS || cfg->levels < 1 || cfg->levels > RP_TRACK_MAX_LEVELS ||
        cfg->win < 5 || cfg->win > RP_TRACK_MAX_WIN || (cfg->win & 1) == 0 ||
        cfg->max_iter < 1 || cfg->target < 1 || cfg->target > RP_MAX_FEATS_PER_CAM ||
        cfg->topup_below > cfg->target || cfg->grid_x < 1 || cfg->grid_y < 1 ||
        cfg->grid_x * cfg->grid_y > RP_TRACK_MAX_CELLS) {
        return RP_E_ARG;
    }
    trk->cfg = *cfg;
    if (trk->cfg.cell_cap == 0) {
        trk->cfg.cell_cap = (uint16_t)(2 * cfg->target / (cfg->grid_x * cfg->grid_y) + 1);
    }
    trk->cur = 0;
    trk->has_prev = 0;
    trk->utime = 0;
    trk->next_k = 0;
    trk->n = 0;
    return RP_OK;
}

/* ---- Lucas-Kanade --------------------------------------------------------------------------- */

/* Q7 bilinear weights of the fractional part (Q16) of a position: rounded, summing to exactly
 * 128, so that 8-bit grey levels interpolate in int16 lanes (255 * 128 = 32640 < 2^15). Used
 * for J, sampled at every iteration; positions resolve to 1/128 px there (the estimate itself
 * stays Q16). */
static void weights_q7(int32_t fx_q16, int32_t fy_q16, int16_t w[4])
{
    const int32_t a = (fx_q16 + (1 << 8)) >> 9, b = (fy_q16 + (1 << 8)) >> 9; /* Q7, 0..128 */
    w[0] = (int16_t)(((128 - a) * (128 - b) + 64) >> 7);
    w[1] = (int16_t)((a * (128 - b) + 64) >> 7);
    w[2] = (int16_t)(((128 - a) * b + 64) >> 7);
    w[3] = (int16_t)(128 - w[0] - w[1] - w[2]);
}

/* Window rows are padded to a multiple of 8 pixels so that every inner loop below runs over whole
 * blocks of 8 (fixed trip count: the compiler turns them into SIMD at -O2, e.g. pmaddwd / smlal;
 * the same C is the scalar code elsewhere). Padded columns carry zero gradients, so they add
 * nothing to the sums. */
#define WPAD(n) (((n) + 7) & ~7)
#define WP_MAX WPAD(RP_TRACK_MAX_WIN)
#define PATCH_MAX (RP_TRACK_MAX_WIN * WP_MAX)
#define GS_MAX (WP_MAX + 8)                          /* row stride of the gradient grid */
#define GRID_MAX ((RP_TRACK_MAX_WIN + 2) * GS_MAX)
#define CHUNK 64 /* int32 partial sums over at most 64 pixels: 64 x 8160 x 4080 < 2^31 */

/* Sums of x^2, x y, y^2 over n (a multiple of 8) values, |x|, |y| <= 4080 (Scharr). */
static void sum_sq3(const int16_t *restrict x, const int16_t *restrict y, int n, int64_t *sxx, int64_t *sxy,
                    int64_t *syy)
{
    int64_t axx = 0, axy = 0, ayy = 0;
    for (int c = 0; c < n; c += CHUNK) {
        const int e = c + CHUNK < n ? c + CHUNK : n;
        int32_t pxx = 0, pxy = 0, pyy = 0;
        for (int k = c; k < e; k += 8) {
            for (int i = 0; i < 8; ++i) {
                pxx += x[k + i] * x[k + i];
                pxy += x[k + i] * y[k + i];
                pyy += y[k + i] * y[k + i];
            }
        }
        axx += pxx;
        axy += pxy;
        ayy += pyy;
    }
    *sxx = axx;
    *sxy = axy;
    *syy = ayy;
}

/* Mismatch vector sum (J - I) Ix, sum (J - I) Iy over n (a multiple of 8) values; J, I in Q5
 * ([0, 8160]), gradients |.| <= 4080. */
static void sum_mismatch(const int16_t *restrict J, const int16_t *restrict I,
                         const int16_t *restrict gx, const int16_t *restrict gy, int n, int64_t *b1, int64_t *b2)
{
    int64_t a1 = 0, a2 = 0;
    for (int c = 0; c < n; c += CHUNK) {
        const int e = c + CHUNK < n ? c + CHUNK : n;
        int32_t p1 = 0, p2 = 0;
        for (int k = c; k < e; k += 8) {
            for (int i = 0; i < 8; ++i) {
                const int16_t d = (int16_t)(J[k + i] - I[k + i]);
                p1 += d * gx[k + i];
                p2 += d * gy[k + i];
            }
        }
        a1 += p1;
        a2 += p2;
    }
    *b1 = a1;
    *b2 = a2;
}

/* Per-call scratch of lk_point (on the stack, about 15 kB at the default limits). */
typedef struct {
    int16_t Iv[PATCH_MAX], Ix[PATCH_MAX], Iy[PATCH_MAX]; /* I in Q5; its Scharr gradients */
    int16_t Jv[PATCH_MAX];                               /* J in Q5 at the current estimate */
    int16_t Jg[GRID_MAX];                                /* J's grey levels on the grid */
    int16_t T[(RP_TRACK_MAX_WIN + 3) * (WP_MAX + 16)];  /* I's grey levels around the window */
    int16_t Gg[GRID_MAX], Gx[GRID_MAX]; /* I interpolated at the patch, Q7 and Q3 */
    int16_t mask[WP_MAX];               /* -1 on the window's columns, 0 on the padding */
} lk_scratch_t;

/* Widens n (a multiple of 8) grey levels to int16. */
static void widen_row(const uint8_t *restrict r, int n, int16_t *restrict out)
{
    for (int x = 0; x < n; x += 8) {
        for (int i = 0; i < 8; ++i) {
            out[x + i] = r[x + i];
        }
    }
}

/* The nr x nc (nc a multiple of 8) tile of level image P (w x h) at (x0, y0), widened to int16
 * at row stride ts, border replicated where it leaves the image. */
static void load_tile(const uint8_t *P, int w, int h, int x0, int y0, int nr, int nc,
                      int16_t *T, int ts)
{
    const int inside = x0 >= 0 && y0 >= 0 && x0 + nc <= w && y0 + nr <= h;
    for (int y = 0; y < nr; ++y) {
        int16_t *t = T + y * ts;
        const uint8_t *row = P + (size_t)clampi(y0 + y, 0, h - 1) * w;
        if (inside) {
            widen_row(row + x0, nc, t);
        } else {
            const int a = clampi(-x0, 0, nc), b = clampi(w - x0, a, nc); /* [a, b) in the image */
            int x = 0;
            for (; x < a; ++x) {
                t[x] = row[0];
            }
            for (; x + 8 <= b; x += 8) {
                widen_row(row + x0 + x, 8, t + x);
            }
            for (; x < b; ++x) {
                t[x] = row[x0 + x];
            }
            for (; x < nc; ++x) {
                t[x] = row[w - 1];
            }
        }
    }
}

/* Bilinear interpolation with Q7 weights of tile row t (next row at t + ts; 0..255) at n (a
 * multiple of 8) columns: q7 (<= 32640) and q3 (its >> 4, rounded; <= 2040). */
static void interp_q7_q3(const int16_t *restrict t, int ts, int n, int16_t w0, int16_t w1,
                         int16_t w2, int16_t w3, int16_t *restrict q7, int16_t *restrict q3)
{
    for (int x = 0; x < n; x += 8) {
        for (int i = 0; i < 8; ++i) {
            const int k = x + i;
            const int16_t v = (int16_t)(t[k] * w0 + t[k + 1] * w1 + t[k + ts] * w2 +
                                        t[k + ts + 1] * w3);
            q7[k] = v;
            q3[k] = (int16_t)((v + 8) >> 4);
        }
    }
}

/* One window row from interpolated rows: Q3 rows a, b, c (above, at, below the window row,
 * starting one column left of the window), Q7 row g7 (the window row, same start); n (a multiple
 * of 8) columns of Iv (Q5), Ix, Iy (Scharr units; masked: 0 where mask is 0, the padding). */
static void grad_row(const int16_t *restrict a, const int16_t *restrict b,
                     const int16_t *restrict c, const int16_t *restrict g7,
                     const int16_t *restrict mask, int n, int16_t *restrict iv,
                     int16_t *restrict ix, int16_t *restrict iy)
{
    int16_t vs[GS_MAX], vd[GS_MAX]; /* vertical smoothing / difference per column */
    for (int x = 0; x < n + 8; x += 8) {
        for (int i = 0; i < 8; ++i) {
            vs[x + i] = (int16_t)(3 * (a[x + i] + c[x + i]) + 10 * b[x + i]);
            vd[x + i] = (int16_t)(c[x + i] - a[x + i]);
        }
    }
    for (int x = 0; x < n; x += 8) {
        for (int i = 0; i < 8; ++i) {
            const int k = x + i;
            iv[k] = (int16_t)((g7[k + 1] + 2) >> 2);
            ix[k] = (int16_t)(((vs[k + 2] - vs[k] + 4) >> 3) & mask[k]);
            iy[k] = (int16_t)(((3 * (vd[k] + vd[k + 2]) + 10 * vd[k + 1] + 4) >> 3) & mask[k]);
        }
    }
}

/* Patch of I at integer origin (ix, iy) plus a sub-pixel offset given by Q7 weights wt: the
 * grey tile around it (border replicated) is interpolated to Q7 (int16 lanes), giving Iv in Q5
 * (>> 2, rounded) and, from Q3 values (<= 2040), Scharr gradients ([3 10 3]^T x [-1 0 1] and its
 * transpose; |.| <= 16 * 2040 = 32640 in int16) brought back to Scharr units of grey levels
 * (>> 3, rounded; |.| <= 4080) in Ix, Iy. Linear filters commute, so this equals OpenCV's
 * gradients-then-interpolation up to rounding. Padding columns get zero gradients. */
static void lk_patch(lk_scratch_t *s, const uint8_t *I, int wI, int hI, int ix, int iy, int win,
                     const int16_t wt[4])
{
    const int wp = WPAD(win), gs = wp + 8, ts = wp + 16;
    const int16_t w0 = wt[0], w1 = wt[1], w2 = wt[2], w3 = wt[3];
    for (int x = 0; x < wp; ++x) {
        s->mask[x] = (int16_t)(x < win ? -1 : 0); /* padding columns: zero gradients */
    }
    load_tile(I, wI, hI, ix - 1, iy - 1, win + 3, ts, s->T, ts);
    /* interpolated rows iy-1 .. iy+win, columns ix-1 .. ix+wp+6: Q7 in Gg, Q3 in Gx */
    for (int y = 0; y < win + 2; ++y) {
        interp_q7_q3(s->T + y * ts, ts, gs, w0, w1, w2, w3, s->Gg + y * gs, s->Gx + y * gs);
    }
    for (int y = 0; y < win; ++y) {
        const int16_t *p3 = s->Gx + y * gs;
        grad_row(p3, p3 + gs, p3 + 2 * gs, s->Gg + (y + 1) * gs, s->mask, wp, s->Iv + y * wp,
                 s->Ix + y * wp, s->Iy + y * wp);
    }
}

/* Bilinear interpolation of grey-level grid row g (next row at g + gs; 0..255) at wp (a
 * multiple of 8) columns with Q7 weights, to Q5 (Q7 sum <= 32640 in int16, >> 2 rounded). */
static void interp_row_q7(const int16_t *restrict g, int gs, int wp, int16_t w0, int16_t w1,
                          int16_t w2, int16_t w3, int16_t *restrict out)
{
    for (int x = 0; x < wp; x += 8) {
        for (int i = 0; i < 8; ++i) {
            const int k = x + i;
            const int16_t v = (int16_t)(g[k] * w0 + g[k + 1] * w1 + g[k + gs] * w2 +
                                        g[k + gs + 1] * w3);
            out[k] = (int16_t)((v + 2) >> 2);
        }
    }
}

/* J in Q5 on the window at integer origin (jx, jy) with Q7 weights wj (into s->Jv): the
 * (win+1) x (wp+8) grid of J widened to int16 (border replicated), then interpolated. */
static void lk_sample(lk_scratch_t *s, const uint8_t *J, int wJ, int hJ, int jx, int jy, int win,
                      const int16_t wj[4])
{
    const int wp = WPAD(win), gs = wp + 8;
    load_tile(J, wJ, hJ, jx, jy, win + 1, gs, s->Jg, gs);
    const int16_t w0 = wj[0], w1 = wj[1], w2 = wj[2], w3 = wj[3];
    for (int y = 0; y < win; ++y) {
        interp_row_q7(s->Jg + y * gs, gs, wp, w0, w1, w2, w3, s->Jv + y * wp);
    }
}

/* Tracks one point from pyramid pI into pJ using the n_lev finest levels (<= both pyramids and
 * cfg.levels). p_q16: level-0 position in I; *q_q16: level-0 result in J. Iterations stop at a
 * step under cfg.eps_q16 at level 0 and under 16 x cfg.eps_q16 at coarser levels (their result
 * is only the start of the next finer level, which converges from there). Returns 1 if tracked, 0 if lost (out of bounds,
 * too little texture, singular at level 0, residual above cfg.max_err_q5). */
static int lk_point(const rp_track_cfg_t *cfg, const rp_pyr_t *pI, const rp_pyr_t *pJ, int n_lev,
                    const int32_t p_q16[2], int32_t q_q16[2])
{
    const int win = cfg->win, half = (cfg->win - 1) / 2, wp = WPAD(cfg->win);
    const int area = win * win;
    lk_scratch_t s;
    if (n_lev > pI->n_lev) {
        n_lev = pI->n_lev;
    }
    if (n_lev > pJ->n_lev) {
        n_lev = pJ->n_lev;
    }
    int32_t nx = 0, ny = 0; /* level position of the estimate in J, Q16 */
    int32_t res_last = 0;   /* residual of the last iteration at level 0, sum |J - I|, Q5 */

    for (int l = n_lev - 1; l >= 0; --l) {
        const rp_pyr_level_t *LI = &pI->lev[l], *LJ = &pJ->lev[l];
        const uint8_t *I = pI->pix + LI->off, *J = pJ->pix + LJ->off;
        const int wI = LI->w, hI = LI->h, wJ = LJ->w, hJ = LJ->h;
        const int64_t eps = (int64_t)cfg->eps_q16 * (l > 0 ? 16 : 1);
        const int64_t eps2 = eps * eps;
        /* point at this level (Q16; an arithmetic shift of a position >= -2^15 px) */
        const int32_t px = p_q16[0] / (1 << l), py = p_q16[1] / (1 << l);
        if (l == n_lev - 1) {
            nx = px;
            ny = py;
        } else {
            nx *= 2;
            ny *= 2;
        }
        /* window origin in I */
        const int32_t ox = px - half * Q16, oy = py - half * Q16;
        const int ix = ox >> 16, iy = oy >> 16;
        if (ix < -win || ix >= wI || iy < -win || iy >= hI) {
            if (l == 0) {
                return 0;
            }
            continue;
        }
        int16_t wt[4];
        weights_q7(ox & 0xffff, oy & 0xffff, wt);
        lk_patch(&s, I, wI, hI, ix, iy, win, wt);
        /* the patch sits at the position rounded to 1/128 px: track that point, then move the
         * result back by the rounding (a translation locally) */
        const int32_t qx = ((((ox & 0xffff) + 256) >> 9) << 9) - (ox & 0xffff);
        const int32_t qy = ((((oy & 0xffff) + 256) >> 9) << 9) - (oy & 0xffff);
        int64_t A11, A12, A22;
        sum_sq3(s.Ix, s.Iy, win * wp, &A11, &A12, &A22);
        /* Texture test: min eigenvalue of A / area vs cfg.min_eig (OpenCV's units x 2^20, A in
         * Scharr^2 like OpenCV before its 2^-20 scale). Work with A >> s < 2^25. */
        {
            int sh = 0;
            while (((A11 | A22 | iabs64(A12)) >> sh) >= ((int64_t)1 << 25)) {
                ++sh;
            }
            const int64_t a = A11 >> sh, c = A22 >> sh, b = A12 >> sh;
            const int64_t disc = (a - c) * (a - c) + 4 * b * b; /* < 2^52 */
            const int64_t two_min = a + c - (int64_t)isqrt52((uint64_t)disc); /* 2 x min eig */
            const int64_t thr = ((int64_t)2 * area * cfg->min_eig) >> sh;
            if (two_min < thr || a * c - b * b <= 0) {
                if (l == 0) {
                    return 0;
                }
                continue;
            }
        }
        int32_t pdx = 0, pdy = 0; /* previous step, Q16 */
        int iterated = 0;
        nx += qx;
        ny += qy;
        for (int it = 0; it < cfg->max_iter; ++it) {
            const int32_t jx0 = nx - half * Q16, jy0 = ny - half * Q16;
            const int jx = jx0 >> 16, jy = jy0 >> 16;
            if (jx < -win || jx >= wJ || jy < -win || jy >= hJ) {
                if (l == 0) {
                    return 0;
                }
                break;
            }
            int16_t wj[4];
            weights_q7(jx0 & 0xffff, jy0 & 0xffff, wj);
            /* J is sampled at the estimate rounded to 1/128 px: the step is taken from there */
            nx += ((((jx0 & 0xffff) + 256) >> 9) << 9) - (jx0 & 0xffff);
            ny += ((((jy0 & 0xffff) + 256) >> 9) << 9) - (jy0 & 0xffff);
            lk_sample(&s, J, wJ, hJ, jx, jy, win, wj);
            iterated = 1;
            int64_t b1, b2;
            sum_mismatch(s.Jv, s.Iv, s.Ix, s.Iy, win * wp, &b1, &b2);
            /* delta = -A^-1 b (px: Q5 x Scharr over Scharr^2 x 32 = px). Scale A, b by 2^-sh so
             * all < 2^22: det < 2^44, numerators < 2^45, times 2^16 < 2^61 (no overflow). */
            int sh = 0;
            while (((A11 | A22 | iabs64(b1) | iabs64(b2)) >> sh) >= ((int64_t)1 << 22)) {
                ++sh;
            }
            const int64_t a = A11 >> sh, c = A22 >> sh, b = A12 >> sh, u = b1 >> sh, v = b2 >> sh;
            const int64_t det = a * c - b * b;
            if (det <= 0) {
                if (l == 0) {
                    return 0;
                }
                break;
            }
            const int32_t dx = (int32_t)(((b * v - c * u) * Q16) / det);
            const int32_t dy = (int32_t)(((b * u - a * v) * Q16) / det);
            nx += dx;
            ny += dy;
            if ((int64_t)dx * dx + (int64_t)dy * dy <= eps2) {
                break;
            }
            if (it > 0 && iabs64((int64_t)dx + pdx) < 655 && iabs64((int64_t)dy + pdy) < 655) {
                nx -= dx / 2; /* oscillating: settle in the middle (as OpenCV) */
                ny -= dy / 2;
                break;
            }
            pdx = dx;
            pdy = dy;
        }
        nx -= qx;
        ny -= qy;
        if (l == 0 && iterated) {
            /* residual of the last iteration, over the window's real columns */
            int32_t res = 0; /* Q5, <= 8160 * 63^2 < 2^25 */
            for (int y = 0; y < win; ++y) {
                const int16_t *jv = s.Jv + y * wp, *iv = s.Iv + y * wp;
                for (int x = 0; x < win; ++x) {
                    const int32_t d = jv[x] - iv[x];
                    res += d < 0 ? -d : d;
                }
            }
            res_last = res;
        }
    }
    q_q16[0] = nx;
    q_q16[1] = ny;
    /* photometric check at level 0: mean |J - I| (Q5) against cfg.max_err_q5 */
    if (cfg->max_err_q5 > 0 && res_last > (int32_t)cfg->max_err_q5 * area) {
        return 0;
    }
    return 1;
}

/* ---- detection ------------------------------------------------------------------------------ */

/* Shi-Tomasi response: 2 x min eigenvalue of the 3x3-block structure tensor of 3x3 Sobel
 * gradients (as cv::cornerMinEigenVal, blockSize 3, up to its positive scale). Sobel |.| <= 1020,
 * tensor entries <= 9 * 1020^2 < 2^24 (int32), discriminant < 2^51, response in int32.
 * Detection streams image rows through three small rings (Sobel products, responses) over one
 * rectangle of the image at a time; no full-frame map is kept. */

/* Sobel products of image row y at columns [xa, xb) (1 <= y <= h-2, 1 <= xa, xb <= w-1). */
static void det_products(const uint8_t *p, int w, int y, int xa, int xb, int32_t *xx,
                         int32_t *xy, int32_t *yy)
{
    const uint8_t *r0 = p + (size_t)(y - 1) * w, *r1 = r0 + w, *r2 = r1 + w;
    for (int x = xa; x < xb; ++x) {
        const int gx = (r0[x + 1] - r0[x - 1]) + 2 * (r1[x + 1] - r1[x - 1]) +
                       (r2[x + 1] - r2[x - 1]);
        const int gy = (r2[x - 1] - r0[x - 1]) + 2 * (r2[x] - r0[x]) + (r2[x + 1] - r0[x + 1]);
        xx[x] = gx * gx;
        xy[x] = gx * gy;
        yy[x] = gy * gy;
    }
}

/* Responses of the row whose products are in slot b (rows above/below in a, c) at columns
 * [xa, xb) into out; 0 where the bound 2 min(sxx, syy) is under floor_r (no square root spent on
 * flat areas). Returns the largest. */
static int32_t det_responses(rp_tracker_t *trk, int a, int b, int c, int xa, int xb,
                             int32_t floor_r, int32_t *out)
{
    int32_t *vxx = trk->vsum[0], *vxy = trk->vsum[1], *vyy = trk->vsum[2];
    for (int x = xa - 1; x < xb + 1; ++x) {
        vxx[x] = trk->prod[a][0][x] + trk->prod[b][0][x] + trk->prod[c][0][x];
        vxy[x] = trk->prod[a][1][x] + trk->prod[b][1][x] + trk->prod[c][1][x];
        vyy[x] = trk->prod[a][2][x] + trk->prod[b][2][x] + trk->prod[c][2][x];
    }
    int32_t best = 0;
    for (int x = xa; x < xb; ++x) {
        const int32_t sxx = vxx[x - 1] + vxx[x] + vxx[x + 1];
        const int32_t sxy = vxy[x - 1] + vxy[x] + vxy[x + 1];
        const int32_t syy = vyy[x - 1] + vyy[x] + vyy[x + 1];
        if (2 * (sxx < syy ? sxx : syy) < floor_r) {
            out[x] = 0;
            continue;
        }
        const int64_t d = (int64_t)(sxx - syy);
        const uint64_t disc = (uint64_t)(d * d + 4 * (int64_t)sxy * sxy);
        const int32_t r = (int32_t)((int64_t)sxx + syy - (int64_t)isqrt52(disc));
        out[x] = r;
        best = r > best ? r : best;
    }
    return best;
}

/* Local maxima (>= the 8 neighbours, as cv::dilate) of response row y (rows y-1, y, y+1 in
 * up, mid, dn) at columns [xa, xb), at least floor_r, kept per cell: the best
 * RP_TRACK_CELL_CANDS of each by insertion. */
static void det_maxima(rp_tracker_t *trk, const int32_t *up, const int32_t *mid,
                       const int32_t *dn, int y, int xa, int xb, int32_t floor_r,
                       const uint8_t *cell_x, int cell_row)
{
    for (int x = xa; x < xb; ++x) {
        const int32_t v = mid[x];
        if (v < floor_r || v <= 0 || v < mid[x - 1] || v < mid[x + 1] || v < up[x - 1] ||
            v < up[x] || v < up[x + 1] || v < dn[x - 1] || v < dn[x] || v < dn[x + 1]) {
            continue;
        }
        const int c = cell_row + cell_x[x];
        rp_track_cand_t *cc = trk->cand[c];
        int n = trk->n_cand[c];
        if (n == RP_TRACK_CELL_CANDS) {
            if (cc[n - 1].r >= v) {
                continue;
            }
            --n;
        }
        int j = n;
        while (j > 0 && cc[j - 1].r < v) {
            cc[j] = cc[j - 1];
            --j;
        }
        cc[j].r = v;
        cc[j].x = (uint16_t)x;
        cc[j].y = (uint16_t)y;
        trk->n_cand[c] = (uint16_t)(n + 1);
    }
}

/* Candidates of the rectangle [x0, x1) x [y0, y1) of image p (3 <= x0, x1 <= w-3, same for y):
 * rows stream through the rings (products two rows ahead, responses one row ahead of the
 * maxima). Returns the largest response seen. */
static int32_t det_rect(rp_tracker_t *trk, const uint8_t *p, int w, int x0, int x1, int y0,
                        int y1, const uint8_t *cell_x, const uint8_t *cell_y)
{
    const int32_t floor_r = (int32_t)trk->cfg.min_response;
    int32_t best = 0;
    for (int yy = y0 - 2; yy <= y1 + 1; ++yy) {
        det_products(p, w, yy, x0 - 2, x1 + 2, trk->prod[yy % 3][0], trk->prod[yy % 3][1],
                     trk->prod[yy % 3][2]);
        if (yy < y0) {
            continue;
        }
        const int ry = yy - 1; /* its product rows ry-1 .. ry+1 are in the ring now */
        const int32_t r = det_responses(trk, (ry - 1) % 3, ry % 3, yy % 3, x0 - 1, x1 + 1,
                                        floor_r, trk->rrow[ry % 3]);
        best = r > best ? r : best;
        const int ny = ry - 1; /* its response rows ny-1 .. ny+1 are in the ring now */
        if (ny >= y0) {
            det_maxima(trk, trk->rrow[(ny - 1) % 3], trk->rrow[ny % 3], trk->rrow[ry % 3], ny,
                       x0, x1, floor_r, cell_x, cell_y[ny] * trk->cfg.grid_x);
        }
    }
    return best;
}

/* Shell sort by response, strongest first. */
static void sort_cands(rp_track_cand_t *c, int n)
{
    static const int gaps[] = {701, 301, 132, 57, 23, 10, 4, 1};
    for (unsigned g = 0; g < sizeof(gaps) / sizeof(gaps[0]); ++g) {
        const int gap = gaps[g];
        for (int i = gap; i < n; ++i) {
            const rp_track_cand_t t = c[i];
            int j = i;
            while (j >= gap && c[j - gap].r < t.r) {
                c[j] = c[j - gap];
                j -= gap;
            }
            c[j] = t;
        }
    }
}

static int cell_of(const rp_track_cfg_t *cfg, int w, int h, int32_t x, int32_t y)
{
    int cx = (int)((int64_t)x * cfg->grid_x / w), cy = (int)((int64_t)y * cfg->grid_y / h);
    cx = clampi(cx, 0, cfg->grid_x - 1);
    cy = clampi(cy, 0, cfg->grid_y - 1);
    return cy * cfg->grid_x + cx;
}

/* One detection pass over the cells marked in scan[]: candidates of those cells, then the
 * strongest first, above the quality threshold, min_dist away from every feature, within the
 * cells' caps (per_cell counts features already there and is updated). Returns the number
 * added (at most want). *best: the largest response seen so far (in, out). */
static int detect_pass(rp_tracker_t *trk, const uint8_t *scan, uint16_t *per_cell, int want,
                       int32_t *best)
{
    const rp_track_cfg_t *cfg = &trk->cfg;
    const rp_pyr_t *P = &trk->pyr[trk->cur];
    const int w = P->lev[0].w, h = P->lev[0].h, gx = cfg->grid_x, gy = cfg->grid_y;
    const uint8_t *p = P->pix;
    uint8_t cell_x[RP_TRACK_MAX_W], cell_y[RP_TRACK_MAX_H];
    int xs[RP_TRACK_MAX_CELLS + 1], ys[RP_TRACK_MAX_CELLS + 1]; /* first column / row of a cell */
    for (int x = 0; x < w; ++x) {
        cell_x[x] = (uint8_t)(x * gx / w);
    }
    for (int y = 0; y < h; ++y) {
        cell_y[y] = (uint8_t)(y * gy / h);
    }
    for (int c = 0; c <= gx; ++c) {
        xs[c] = clampi((c * w + gx - 1) / gx, 3, w - 3);
    }
    for (int c = 0; c <= gy; ++c) {
        ys[c] = clampi((c * h + gy - 1) / gy, 3, h - 3);
    }
    /* rectangles: runs of marked cells along each cell row; a run whose cell row above had the
     * same run continues that rectangle (a full image is one rectangle) */
    int n_rect = 0;
    int rx0[RP_TRACK_MAX_CELLS], rx1[RP_TRACK_MAX_CELLS], ry0[RP_TRACK_MAX_CELLS],
        ry1[RP_TRACK_MAX_CELLS], rc0[RP_TRACK_MAX_CELLS], rc1[RP_TRACK_MAX_CELLS];
    for (int cy = 0; cy < gy; ++cy) {
        for (int cx = 0; cx < gx; ++cx) {
            if (!scan[cy * gx + cx]) {
                continue;
            }
            int ce = cx;
            while (ce + 1 < gx && scan[cy * gx + ce + 1]) {
                ++ce;
            }
            int r = 0;
            while (r < n_rect && !(rc0[r] == cx && rc1[r] == ce && ry1[r] == ys[cy])) {
                ++r;
            }
            if (r == n_rect) {
                rc0[r] = cx;
                rc1[r] = ce;
                rx0[r] = xs[cx];
                rx1[r] = xs[ce + 1];
                ry0[r] = ys[cy];
                ++n_rect;
            }
            ry1[r] = ys[cy + 1];
            cx = ce;
        }
    }
    for (int c = 0; c < gx * gy; ++c) {
        if (scan[c]) {
            trk->n_cand[c] = 0;
        }
    }
    for (int r = 0; r < n_rect; ++r) {
        if (rx0[r] < rx1[r] && ry0[r] < ry1[r]) {
            const int32_t b = det_rect(trk, p, w, rx0[r], rx1[r], ry0[r], ry1[r], cell_x, cell_y);
            *best = b > *best ? b : *best;
        }
    }
    int32_t thr = (int32_t)(((int64_t)*best * cfg->quality_q16) >> 16);
    if (thr < (int32_t)cfg->min_response) {
        thr = (int32_t)cfg->min_response;
    }
    int nl = 0;
    for (int c = 0; c < gx * gy; ++c) {
        for (int i = 0; scan[c] && i < trk->n_cand[c] && trk->cand[c][i].r >= thr; ++i) {
            trk->list[nl++] = trk->cand[c][i];
        }
    }
    sort_cands(trk->list, nl);
    const int64_t md2 = (int64_t)cfg->min_dist * cfg->min_dist * Q16 * Q16; /* Q32 px^2 */
    int added = 0;
    for (int i = 0; i < nl && added < want && trk->n < RP_MAX_FEATS_PER_CAM; ++i) {
        const rp_track_cand_t *k = &trk->list[i];
        const int c = cell_y[k->y] * gx + cell_x[k->x];
        if (per_cell[c] >= cfg->cell_cap) {
            continue;
        }
        const int32_t kx = (int32_t)k->x * Q16, ky = (int32_t)k->y * Q16;
        int ok = 1;
        for (int f = 0; f < trk->n && ok; ++f) {
            const int64_t dx = (int64_t)trk->pos_q16[f][0] - kx;
            const int64_t dy = (int64_t)trk->pos_q16[f][1] - ky;
            if (dx * dx + dy * dy < md2) {
                ok = 0;
            }
        }
        if (!ok) {
            continue;
        }
        const uint16_t n = trk->n;
        trk->pos_q16[n][0] = kx;
        trk->pos_q16[n][1] = ky;
        trk->id[n] = (uint32_t)cfg->cam + (uint32_t)RP_MAX_CAMS * trk->next_k++;
        trk->n = (uint16_t)(n + 1);
        per_cell[c]++;
        ++added;
    }
    return added;
}

/* Tops up to want new features in the current level-0 image, away (min_dist) from the tracked
 * ones, with per-cell caps counting the tracked ones. Only cells under their fair share
 * (ceil(target / cells)) are searched first; the other cells under their cap only if the count
 * is still under cfg.topup_below (or zero) after that. A first frame searches every cell.
 * Returns the number added. */
static int detect(rp_tracker_t *trk, int want)
{
    const rp_track_cfg_t *cfg = &trk->cfg;
    const rp_pyr_t *P = &trk->pyr[trk->cur];
    const int w = P->lev[0].w, h = P->lev[0].h;
    const int ncell = cfg->grid_x * cfg->grid_y;
    const int share = (cfg->target + ncell - 1) / ncell;
    if (want <= 0) {
        return 0;
    }
    uint16_t per_cell[RP_TRACK_MAX_CELLS];
    uint8_t scan[RP_TRACK_MAX_CELLS];
    for (int c = 0; c < ncell; ++c) {
        per_cell[c] = 0;
    }
    for (int i = 0; i < trk->n; ++i) {
        per_cell[cell_of(cfg, w, h, trk->pos_q16[i][0] >> 16, trk->pos_q16[i][1] >> 16)]++;
    }
    for (int c = 0; c < ncell; ++c) {
        scan[c] = (uint8_t)(per_cell[c] < share);
    }
    int32_t best = 0;
    int added = detect_pass(trk, scan, per_cell, want, &best);
    if (added < want && (trk->n < cfg->topup_below || trk->n == 0)) {
        int any = 0;
        for (int c = 0; c < ncell; ++c) {
            scan[c] = (uint8_t)(!scan[c] && per_cell[c] < cfg->cell_cap);
            any |= scan[c];
        }
        if (any) {
            added += detect_pass(trk, scan, per_cell, want - added, &best);
        }
    }
    return added;
}

/* ---- the per-frame step --------------------------------------------------------------------- */

/* Pyramid levels of the backward check: only as many as the forward displacement needs (a level
 * reaches about a quarter window at its scale), at most cfg.levels. The backward pass starts at
 * zero motion, like the forward one, so it stays an independent check. */
static int back_levels(const rp_track_cfg_t *cfg, const int32_t p_q16[2], const int32_t f_q16[2])
{
    const int64_t dx = (int64_t)f_q16[0] - p_q16[0], dy = (int64_t)f_q16[1] - p_q16[1];
    const int64_t d = (dx < 0 ? -dx : dx) + (dy < 0 ? -dy : dy); /* L1, Q16 px */
    int64_t reach = (int64_t)((cfg->win - 1) / 4) * Q16;       /* per level, level-0 px */
    int l = 1;
    while (l < cfg->levels && d > reach) {
        ++l;
        reach *= 2;
    }
    return l;
}

static int is_blank(const rp_image_t *img, unsigned min_contrast)
{
    int lo = 255, hi = 0;
    for (unsigned v = 0; v < img->h; ++v) {
        const uint8_t *r = img->data + (size_t)v * img->stride;
        for (unsigned u = 0; u < img->w; ++u) {
            lo = r[u] < lo ? r[u] : lo;
            hi = r[u] > hi ? r[u] : hi;
        }
        if (hi - lo >= (int)min_contrast) {
            return 0;
        }
    }
    return 1;
}

rp_status_t rp_track_process(rp_tracker_t *trk, const rp_image_t *img, int64_t utime,
                             rp_feat_t *out, uint16_t cap, uint16_t *n_out, rp_track_info_t *info)
{
    if (trk == NULL || n_out == NULL || (out == NULL && cap > 0)) {
        return RP_E_ARG;
    }
    *n_out = 0;
    rp_status_t st = check_image(img, trk->cfg.win);
    if (st != RP_OK) {
        return st;
    }
    rp_track_info_t inf;
    memset(&inf, 0, sizeof(inf));
    inf.n_prev = trk->n;
    if (is_blank(img, trk->cfg.min_contrast)) {
        inf.flags = RP_TRACK_BLANK;
        inf.n_tracked = trk->n;
        if (info != NULL) {
            *info = inf;
        }
        return RP_E_DEGENERATE;
    }
    const uint8_t nxt = (uint8_t)(trk->cur ^ 1u);
    st = rp_pyr_build(&trk->pyr[nxt], img, trk->cfg.levels);
    if (st != RP_OK) {
        return st;
    }
    if (trk->has_prev) {
        const rp_pyr_t *P = &trk->pyr[trk->cur], *C = &trk->pyr[nxt];
        const int32_t wq = (int32_t)(img->w - 1) * Q16, hq = (int32_t)(img->h - 1) * Q16;
        uint16_t m = 0;
        for (uint16_t i = 0; i < trk->n; ++i) {
            int32_t f[2], b[2];
            if (!lk_point(&trk->cfg, P, C, trk->cfg.levels, trk->pos_q16[i], f) || f[0] < 0 || f[1] < 0 ||
                f[0] > wq || f[1] > hq) {
                inf.n_lost++;
                continue;
            }
            if (trk->cfg.fb_max_q16 > 0) {
                if (!lk_point(&trk->cfg, C, P, back_levels(&trk->cfg, trk->pos_q16[i], f), f,
                              b)) {
                    inf.n_lost_fb++;
                    continue;
                }
                const int64_t dx = (int64_t)b[0] - trk->pos_q16[i][0];
                const int64_t dy = (int64_t)b[1] - trk->pos_q16[i][1];
                if (dx * dx + dy * dy > (int64_t)trk->cfg.fb_max_q16 * trk->cfg.fb_max_q16) {
                    inf.n_lost_fb++;
                    continue;
                }
            }
            trk->id[m] = trk->id[i];
            trk->pos_q16[m][0] = f[0];
            trk->pos_q16[m][1] = f[1];
            ++m;
        }
        trk->n = m;
        if (m == 0 && inf.n_prev > 0) {
            inf.flags |= RP_TRACK_ALL_LOST;
        }
    } else {
        inf.flags |= RP_TRACK_FIRST;
        trk->n = 0;
    }
    inf.n_tracked = trk->n;
    trk->cur = nxt;
    trk->has_prev = 1;
    trk->utime = utime;
    if (trk->n < trk->cfg.topup_below || trk->n == 0) {
        inf.n_new = (uint16_t)detect(trk, (int)trk->cfg.target - (int)trk->n);
        if (inf.n_new > 0) {
            inf.flags |= RP_TRACK_TOPPED_UP;
        }
    }
    const uint16_t nw = trk->n < cap ? trk->n : cap;
    for (uint16_t i = 0; i < nw; ++i) {
        out[i].id = trk->id[i];
        out[i].uv[0] = (rp_real)trk->pos_q16[i][0] / RP_C(65536.0);
        out[i].uv[1] = (rp_real)trk->pos_q16[i][1] / RP_C(65536.0);
    }
    *n_out = nw;
    if (info != NULL) {
        *info = inf;
    }
    if (trk->n == 0) {
        return RP_E_TOO_FEW;
    }
    return trk->n > cap ? RP_E_FULL : RP_OK;
}
