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

/* ---- 8-lane int16 vectors: priv/rp_v8.h (RP_TRACK_SCALAR: the plain-C lanes) --------------- */

#if defined(RP_TRACK_SCALAR) && !defined(RP_V8_SCALAR)
#define RP_V8_SCALAR 1
#endif
#include "priv/rp_v8.h"

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
    /* vertical 5-tap sums (<= 16 x 255) of column x at rs[2 + x], the row reflected two columns
     * each side; 0 beyond (read by the last lane group, never used) */
    int16_t rs[RP_TRACK_MAX_W + 16];
    int16_t hs[RP_TRACK_MAX_W + 8]; /* horizontal 5-tap sums at every column, rounded >> 8 */
    memset(rs, 0, sizeof(rs));
    const v8_t k2 = v8_set(2), k4 = v8_set(4), k6 = v8_set(6), r64 = v8_set(64);
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
            int x = 0;
            for (; x + 8 <= sw; x += 8) {
                const v8_t v = v8_add(v8_add(v8_ld_u8(r0 + x), v8_ld_u8(r4 + x)),
                                      v8_add(v8_mul(v8_add(v8_ld_u8(r1 + x), v8_ld_u8(r3 + x)), k4),
                                             v8_mul(v8_ld_u8(r2 + x), k6)));
                v8_st(rs + 2 + x, v);
            }
            for (; x < sw; ++x) {
                rs[2 + x] = (int16_t)(r0[x] + 4 * (r1[x] + r3[x]) + 6 * r2[x] + r4[x]);
            }
            rs[1] = rs[3]; /* reflect 101 (sw >= 9 here) */
            rs[0] = rs[4];
            rs[2 + sw] = rs[sw];
            rs[3 + sw] = rs[sw - 1];
            /* (sum + 128) >> 8 with sum = A + B <= 65280, A = rs0 + rs4 + 6 rs2, B = 4 (rs1 + rs3)
             * even: equals ((A >> 1) + B / 2 + 64) >> 7, whose terms all fit int16 */
            for (int c = 0; c < sw; c += 8) {
                const v8_t a = v8_add(v8_add(v8_ld(rs + c), v8_ld(rs + c + 4)),
                                      v8_mul(v8_ld(rs + c + 2), k6));
                const v8_t b = v8_mul(v8_add(v8_ld(rs + c + 1), v8_ld(rs + c + 3)), k2);
                v8_st(hs + c, v8_sra(v8_add(v8_add(v8_sra(a, 1), b), r64), 7));
            }
            uint8_t *drow = dp + (size_t)y * dw;
            for (int k = 0; k < dw; ++k) {
                drow[k] = (uint8_t)hs[2 * k]; /* <= 255, no saturation */
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
    cfg->reset_q8 = 205;
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
    trk->pyr_gen[0] = trk->pyr_gen[1] = 0;
    trk->gen_next = 0;
    {
        trk->slot_len = 3u * cfg->win * ((cfg->win + 7u) & ~7u); /* rows padded to 8 */
        const uint32_t k = (uint32_t)(RP_TRACK_PATCH_CACHE_BYTES / 2) / trk->slot_len;
        trk->n_slots = (uint16_t)(k < RP_MAX_FEATS_PER_CAM ? k : RP_MAX_FEATS_PER_CAM);
        memset(trk->slot_key, 0, sizeof(trk->slot_key));
    }
    trk->utime = 0;
    trk->next_k = 0;
    trk->n = 0;
    trk->n_dormant = 0;
    trk->topup_turn = 1;
    return RP_OK;
}

rp_status_t rp_track_set_topup_turn(rp_tracker_t *trk, uint8_t turn)
{
    if (trk == NULL) {
        return RP_E_ARG;
    }
    trk->topup_turn = turn != 0;
    return RP_OK;
}

/* ---- Lucas-Kanade --------------------------------------------------------------------------- */

/* Q7 bilinear weights of the fractional part (Q16) of a position, with a, b the fractions in Q7
 * (0..128): w0 (top left) + w1 (top right) = 128 - b and w2 + w3 = b exactly, w1 and w3 the
 * rounded a (128 - b) / 128 and a b / 128. So every weight is in 0..128, each within 1/2 of
 * its exact value, and the four sum to exactly 128: 8-bit grey levels interpolate in int16
 * lanes (at most 255 * 128 = 32640 < 2^15). Used for J, sampled at every iteration; positions
 * resolve to 1/128 px there (the estimate itself stays Q16). */
static void weights_q7(int32_t fx_q16, int32_t fy_q16, v8_t w[4])
{
    const int32_t a = (fx_q16 + (1 << 8)) >> 9, b = (fy_q16 + (1 << 8)) >> 9; /* Q7, 0..128 */
    const int16_t w1 = (int16_t)((a * (128 - b) + 64) >> 7);
    const int16_t w3 = (int16_t)((a * b + 64) >> 7);
    w[0] = v8_set((int16_t)(128 - b - w1));
    w[1] = v8_set(w1);
    w[2] = v8_set((int16_t)(b - w3));
    w[3] = v8_set(w3);
}

/* Window rows are padded to a multiple of 8 pixels so that every inner loop below runs over whole
 * lane groups of 8. Padded columns carry zero gradients, so they add nothing to the sums. */
#define WPAD(n) (((n) + 7) & ~7)
#define WP_MAX WPAD(RP_TRACK_MAX_WIN)
#define PATCH_MAX (RP_TRACK_MAX_WIN * WP_MAX)
#define GS_MAX (WP_MAX + 8)                          /* row stride of the gradient grid */
#define GRID_MAX ((RP_TRACK_MAX_WIN + 2) * GS_MAX)
/* int32 lane partial sums over at most CHUNK pixels (CHUNK / 8 lane groups), then int64: a lane
 * of v8_madd adds two products of at most 8160 x 4080, so 32 x 2 x 8160 x 4080 < 2^31 */
#define CHUNK 256

/* Sums of x^2, x y, y^2 over n (a multiple of 8) values, |x|, |y| <= 4080 (Scharr). */
static void sum_sq3(const int16_t *restrict x, const int16_t *restrict y, int n, int64_t *sxx,
                    int64_t *sxy, int64_t *syy)
{
    int64_t axx = 0, axy = 0, ayy = 0;
    for (int c = 0; c < n; c += CHUNK) {
        const int e = c + CHUNK < n ? c + CHUNK : n;
        v4_t pxx = v4_zero(), pxy = v4_zero(), pyy = v4_zero();
        for (int k = c; k < e; k += 8) {
            const v8_t vx = v8_ld(x + k), vy = v8_ld(y + k);
            pxx = v4_add(pxx, v8_madd(vx, vx));
            pxy = v4_add(pxy, v8_madd(vx, vy));
            pyy = v4_add(pyy, v8_madd(vy, vy));
        }
        axx += v4_sum(pxx);
        axy += v4_sum(pxy);
        ayy += v4_sum(pyy);
    }
    *sxx = axx;
    *sxy = axy;
    *syy = ayy;
}

/* Mismatch vector sum (J - I) Ix, sum (J - I) Iy over n (a multiple of 8) values; J, I in Q5
 * ([0, 8160]), gradients |.| <= 4080. */
static void sum_mismatch(const int16_t *restrict J, const int16_t *restrict I,
                         const int16_t *restrict gx, const int16_t *restrict gy, int n,
                         int64_t *b1, int64_t *b2)
{
    int64_t a1 = 0, a2 = 0;
    for (int c = 0; c < n; c += CHUNK) {
        const int e = c + CHUNK < n ? c + CHUNK : n;
        v4_t p1 = v4_zero(), p2 = v4_zero();
        for (int k = c; k < e; k += 8) {
            const v8_t d = v8_sub(v8_ld(J + k), v8_ld(I + k));
            p1 = v4_add(p1, v8_madd(d, v8_ld(gx + k)));
            p2 = v4_add(p2, v8_madd(d, v8_ld(gy + k)));
        }
        a1 += v4_sum(p1);
        a2 += v4_sum(p2);
    }
    *b1 = a1;
    *b2 = a2;
}

/* Sum |J - I| over the win x win window (rows of wp, mask -1 on the window's columns, 0 on the
 * padding), Q5: <= 8160 x 63^2 < 2^25; a lane adds at most 2 x 8160 per lane group. */
static int32_t sum_absdiff(const int16_t *restrict J, const int16_t *restrict I,
                           const int16_t *restrict mask, int win, int wp)
{
    const v8_t one = v8_set(1);
    v4_t acc = v4_zero();
    for (int y = 0; y < win; ++y) {
        for (int x = 0; x < wp; x += 8) {
            const int k = y * wp + x;
            const v8_t d = v8_abs(v8_sub(v8_ld(J + k), v8_ld(I + k)));
            acc = v4_add(acc, v8_madd(v8_and(d, v8_ld(mask + x)), one));
        }
    }
    return (int32_t)v4_sum(acc);
}

/* Per-call scratch of lk_point (on the stack, about 13 kB at the default limits). */
typedef struct {
    int16_t Iv[PATCH_MAX], Ix[PATCH_MAX], Iy[PATCH_MAX]; /* I in Q5; its Scharr gradients */
    int16_t Jv[PATCH_MAX];                               /* J in Q5 at the current estimate */
    uint8_t T[(RP_TRACK_MAX_WIN + 3) * (GS_MAX + 8)];   /* a bordered copy near the border */
    int16_t Gg[GRID_MAX], Gx[GRID_MAX]; /* I interpolated at the patch, Q7 and Q3 */
    int16_t mask[WP_MAX];               /* -1 on the window's columns, 0 on the padding */
} lk_scratch_t;

/* The nr x nc block of level image P (w x h) whose top-left pixel is (x0, y0), as a pointer and
 * row stride: into P itself when the block lies inside, else into T (nr x nc bytes), a copy with
 * the border replicated where the block leaves the image. */
static const uint8_t *load_tile(const uint8_t *P, int w, int h, int x0, int y0, int nr, int nc,
                                uint8_t *T, int *stride)
{
    if (x0 >= 0 && y0 >= 0 && x0 + nc <= w && y0 + nr <= h) {
        *stride = w;
        return P + (size_t)y0 * w + x0;
    }
    const int a = clampi(-x0, 0, nc), b = clampi(w - x0, a, nc); /* [a, b) in the image */
    for (int y = 0; y < nr; ++y) {
        uint8_t *t = T + y * nc;
        const uint8_t *row = P + (size_t)clampi(y0 + y, 0, h - 1) * w;
        memset(t, row[0], (size_t)a);
        memcpy(t + a, row + x0 + a, (size_t)(b - a));
        memset(t + b, row[w - 1], (size_t)(nc - b));
    }
    *stride = nc;
    return T;
}

/* Bilinear interpolation with Q7 weights w of grey levels src (row stride ss) at nr rows and n
 * (a multiple of 8) columns (reading nr + 1 rows, n + 1 columns) to Q7 (<= 255 x 128 = 32640),
 * written to out >> sh (rounded) and, if q3 is not NULL, to q3 >> 4 (rounded; <= 2040), both at
 * row stride os. Column groups outer, rows inner: each source row is loaded once per group. */
static void interp_q7_q3(const uint8_t *src, int ss, int nr, int n, int os, const v8_t w[4],
                         int sh, int16_t *restrict out, int16_t *restrict q3)
{
    const v8_t r8 = v8_set(8), rs = v8_set((int16_t)((1 << sh) >> 1));
    for (int k = 0; k < n; k += 8) {
        const uint8_t *r = src + k;
        v8_t a0 = v8_ld_u8(r), a1 = v8_ld_u8(r + 1);
        for (int y = 0; y < nr; ++y) {
            r += ss;
            const v8_t b0 = v8_ld_u8(r), b1 = v8_ld_u8(r + 1);
            const v8_t v = v8_add(v8_add(v8_mul(a0, w[0]), v8_mul(a1, w[1])),
                                  v8_add(v8_mul(b0, w[2]), v8_mul(b1, w[3])));
            v8_st(out + y * os + k, v8_sra(v8_add(v, rs), sh));
            if (q3 != NULL) {
                v8_st(q3 + y * os + k, v8_sra(v8_add(v, r8), 4));
            }
            a0 = b0;
            a1 = b1;
        }
    }
}

/* Window values and gradients from the interpolated grid (row stride gs; row 0 and column 0 are
 * one pixel above / left of the window): Q3 rows y, y+1, y+2 give window row y's Scharr
 * gradients ([3 10 3]^T x [-1 0 1] and its transpose on Q3: |.| <= 16 x 2040 = 32640, brought
 * back to grey levels by >> 3, rounded: |.| <= 4080; 0 where mask is 0, the padding) and Q7 row
 * y+1 its value in Q5 (>> 2, rounded). win rows of wp (a multiple of 8) columns into iv, ix, iy.
 * Separably: per Q3 row, the horizontal difference h ([-1 0 1], |.| <= 2040) and smoothing t
 * ([3 10 3], <= 32640); then Ix = [3 10 3]^T h and Iy = [-1 0 1]^T t over three rows. Column
 * groups outer, rows inner: the h and t of the two rows above roll down in registers. */
/* Horizontal Scharr parts of the Q3 row group at r: difference r[2] - r[0] into *h, smoothing
 * 3 (r[0] + r[2]) + 10 r[1] into *t. */
static inline void scharr_h(const int16_t *r, v8_t k3, v8_t k10, v8_t *h, v8_t *t)
{
    const v8_t c0 = v8_ld(r), c2 = v8_ld(r + 2);
    *h = v8_sub(c2, c0);
    *t = v8_add(v8_mul(v8_add(c0, c2), k3), v8_mul(v8_ld(r + 1), k10));
}

static void lk_grads(const int16_t *q3, const int16_t *q7, int gs, int win, int wp,
                     const int16_t *mask, int16_t *restrict iv, int16_t *restrict ix,
                     int16_t *restrict iy)
{
    const v8_t k3 = v8_set(3), k10 = v8_set(10), r2 = v8_set(2), r4 = v8_set(4);
    for (int k = 0; k < wp; k += 8) {
        const v8_t m = v8_ld(mask + k);
        const int16_t *r = q3 + k;
        v8_t ha, ta, hb, tb, hc, tc;
        scharr_h(r, k3, k10, &ha, &ta);
        scharr_h(r + gs, k3, k10, &hb, &tb);
        for (int y = 0; y < win; ++y) {
            scharr_h(r + (y + 2) * gs, k3, k10, &hc, &tc);
            const v8_t gx = v8_add(v8_mul(v8_add(ha, hc), k3), v8_mul(hb, k10));
            const int o = y * wp + k;
            v8_st(ix + o, v8_and(v8_sra(v8_add(gx, r4), 3), m));
            v8_st(iy + o, v8_and(v8_sra(v8_add(v8_sub(tc, ta), r4), 3), m));
            v8_st(iv + o, v8_sra(v8_add(v8_ld(q7 + (y + 1) * gs + k + 1), r2), 2));
            ha = hb;
            hb = hc;
            ta = tb;
            tb = tc;
        }
    }
}

/* Patch of I at integer origin (ix, iy) plus a sub-pixel offset given by Q7 weights wt: the grey
 * levels around it (border replicated) are interpolated to Q7 (int16 lanes), giving Iv in Q5 and,
 * from Q3 values, Scharr gradients (lk_grads). Linear filters commute, so this equals OpenCV's
 * gradients-then-interpolation up to rounding. Padding columns get zero gradients. */
static void lk_patch(lk_scratch_t *s, const uint8_t *I, int wI, int hI, int ix, int iy, int win,
                     const v8_t wt[4])
{
    const int wp = WPAD(win), gs = wp + 8, ng = WPAD(win + 2);
    int ss;
    /* interpolated rows iy-1 .. iy+win, columns ix-1 .. ix+ng-2, Q7 in Gg, Q3 in Gx at row stride
     * gs: the window's values and gradients need win + 2 columns; lk_grads also reads the grid's
     * columns ng .. gs-1, which lk_point zeroes once, and which reach only the padding lanes */
    const uint8_t *src = load_tile(I, wI, hI, ix - 1, iy - 1, win + 3, ng + 1, s->T, &ss);
    interp_q7_q3(src, ss, win + 2, ng, gs, wt, 0, s->Gg, s->Gx);
    lk_grads(s->Gx, s->Gg, gs, win, wp, s->mask, s->Iv, s->Ix, s->Iy);
}

/* J in Q5 on the window at integer origin (jx, jy) with Q7 weights wj (into s->Jv, row stride
 * wp): bilinear interpolation of the (win+1) x (wp+1) grey levels there (border replicated),
 * >> 2 rounded. */
static void lk_sample(lk_scratch_t *s, const uint8_t *J, int wJ, int hJ, int jx, int jy, int win,
                      const v8_t wj[4])
{
    const int wp = WPAD(win);
    int ss;
    const uint8_t *src = load_tile(J, wJ, hJ, jx, jy, win + 1, wp + 1, s->T, &ss);
    interp_q7_q3(src, ss, win, wp, wp, wj, 2, s->Jv, NULL);
}

/* One slot of the tracker's patch cache (rp_tracker_t) as lk_point sees it: I's level-0 patch at
 * p_q16 is taken from the slot if its key matches (use), or stored there (store). */
typedef struct {
    rp_track_patch_key_t *key;
    int16_t *pix; /* Iv, Ix, Iy: 3 x win x wp */
    uint32_t gen; /* generation of I */
    int store;    /* 0: use on a match; 1: store */
    int hit;      /* set to 1 when used */
} lk_cache_t;

/* Offset (Q16) that moves fractional part f (Q16) to the nearest 1/128 px. */
static int32_t round_q7_off(int32_t f) { return (((f + 256) >> 9) << 9) - f; }

/* Tracks one point from pyramid pI into pJ using the n_lev finest levels (<= both pyramids and
 * cfg.levels). p_q16: level-0 position in I; g_q16: the level-0 displacement to start from (NULL:
 * none, start at p); *q_q16: level-0 result in J. Iterations stop at a step under cfg.eps_q16 at
 * level 0 and under 16 x cfg.eps_q16 at coarser levels (their result is only the start of the
 * next finer level, which converges from there). res_check: apply the residual test (once per
 * track, see track_fb). Returns 1 if tracked, 0 if lost (out of bounds, too little texture,
 * singular at level 0, residual above cfg.max_err_q5). */
static int lk_point(const rp_track_cfg_t *cfg, const rp_pyr_t *pI, const rp_pyr_t *pJ, int n_lev,
                    const int32_t p_q16[2], const int32_t *g_q16, int res_check,
                    lk_cache_t *cache, int32_t q_q16[2])
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
    for (int x = 0; x < wp; ++x) {
        s.mask[x] = (int16_t)(x < win ? -1 : 0); /* padding columns: zero gradients */
    }
    if (WPAD(win + 2) < wp + 8) { /* the grid's columns that lk_patch leaves (see there) */
        for (int y = 0; y < win + 2; ++y) {
            v8_st(s.Gg + y * (wp + 8) + wp, v8_set(0));
            v8_st(s.Gx + y * (wp + 8) + wp, v8_set(0));
        }
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
            nx = g_q16 != NULL ? (p_q16[0] + g_q16[0]) / (1 << l) : px;
            ny = g_q16 != NULL ? (p_q16[1] + g_q16[1]) / (1 << l) : py;
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
        /* I's patch: from the cache at level 0 when it holds this image's at p (the same
         * numbers), else computed (and stored if asked) */
        const int16_t *Iv = s.Iv, *Ix = s.Ix, *Iy = s.Iy;
        int64_t A11, A12, A22;
        if (l == 0 && cache != NULL && !cache->store && cache->key->gen == cache->gen &&
            cache->key->key[0] == p_q16[0] && cache->key->key[1] == p_q16[1]) {
            cache->hit = 1;
            Iv = cache->pix;
            Ix = Iv + win * wp;
            Iy = Ix + win * wp;
            A11 = cache->key->A[0];
            A12 = cache->key->A[1];
            A22 = cache->key->A[2];
        } else {
            v8_t wt[4];
            weights_q7(ox & 0xffff, oy & 0xffff, wt);
            lk_patch(&s, I, wI, hI, ix, iy, win, wt);
            sum_sq3(s.Ix, s.Iy, win * wp, &A11, &A12, &A22);
            if (l == 0 && cache != NULL && cache->store) {
                memcpy(cache->pix, s.Iv, sizeof(int16_t) * (size_t)(win * wp));
                memcpy(cache->pix + win * wp, s.Ix, sizeof(int16_t) * (size_t)(win * wp));
                memcpy(cache->pix + 2 * win * wp, s.Iy, sizeof(int16_t) * (size_t)(win * wp));
                cache->key->gen = cache->gen;
                cache->key->key[0] = p_q16[0];
                cache->key->key[1] = p_q16[1];
                cache->key->A[0] = A11;
                cache->key->A[1] = A12;
                cache->key->A[2] = A22;
            }
        }
        /* the patch sits at the position rounded to 1/128 px: track that point, then move the
         * result back by the rounding (a translation locally) */
        const int32_t qx = round_q7_off(ox & 0xffff), qy = round_q7_off(oy & 0xffff);
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
            v8_t wj[4];
            weights_q7(jx0 & 0xffff, jy0 & 0xffff, wj);
            /* J is sampled at the estimate rounded to 1/128 px: the step is taken from there */
            nx += round_q7_off(jx0 & 0xffff);
            ny += round_q7_off(jy0 & 0xffff);
            lk_sample(&s, J, wJ, hJ, jx, jy, win, wj);
            iterated = 1;
            int64_t b1, b2;
            sum_mismatch(s.Jv, Iv, Ix, Iy, win * wp, &b1, &b2);
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
        if (l == 0 && iterated && res_check) {
            /* residual of the last iteration, over the window's real columns */
            res_last = sum_absdiff(s.Jv, Iv, s.mask, win, wp);
        }
    }
    q_q16[0] = nx;
    q_q16[1] = ny;
    /* photometric check at level 0: mean |J - I| (Q5) against cfg.max_err_q5 */
    if (res_check && cfg->max_err_q5 > 0 && res_last > (int32_t)cfg->max_err_q5 * area) {
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
    const v8_t two = v8_set(2);
    int x = xa;
    for (; x + 8 <= xb; x += 8) { /* |gx|, |gy| <= 1020 in int16 lanes */
        const v8_t a0 = v8_ld_u8(r0 + x - 1), a1 = v8_ld_u8(r0 + x), a2 = v8_ld_u8(r0 + x + 1);
        const v8_t c0 = v8_ld_u8(r2 + x - 1), c1 = v8_ld_u8(r2 + x), c2 = v8_ld_u8(r2 + x + 1);
        const v8_t b = v8_sub(v8_ld_u8(r1 + x + 1), v8_ld_u8(r1 + x - 1));
        const v8_t gx = v8_add(v8_add(v8_sub(a2, a0), v8_sub(c2, c0)), v8_mul(b, two));
        const v8_t gy = v8_add(v8_add(v8_sub(c0, a0), v8_sub(c2, a2)), v8_mul(v8_sub(c1, a1), two));
        v8_mul_wide(gx, gx, xx + x);
        v8_mul_wide(gx, gy, xy + x);
        v8_mul_wide(gy, gy, yy + x);
    }
    for (; x < xb; ++x) {
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
    int x0 = xa - 1;
    for (; x0 + 4 <= xb + 1; x0 += 4) {
        for (int k = 0; k < 3; ++k) {
            v4_st(trk->vsum[k] + x0, v4_add(v4_add(v4_ld(trk->prod[a][k] + x0),
                                                   v4_ld(trk->prod[b][k] + x0)),
                                            v4_ld(trk->prod[c][k] + x0)));
        }
    }
    for (int x = x0; x < xb + 1; ++x) {
        vxx[x] = trk->prod[a][0][x] + trk->prod[b][0][x] + trk->prod[c][0][x];
        vxy[x] = trk->prod[a][1][x] + trk->prod[b][1][x] + trk->prod[c][1][x];
        vyy[x] = trk->prod[a][2][x] + trk->prod[b][2][x] + trk->prod[c][2][x];
    }
    int32_t best = 0;
    int x = xa;
#if RP_V8_VEC
    /* four pixels at a time, the same integers: the discriminant (< 2^51) is exact in a double,
     * its square root correctly rounded (IEEE 754), and for D < 2^52 the rounded root never
     * reaches the next integer (sqrt(n^2 - 1) is 1 / 2n below n, more than half an ulp of n), so
     * truncating it is isqrt52's floor(sqrt(D)); lanes under the floor give 0 */
    typedef double v4d_t __attribute__((vector_size(32)));
    const v4_t fl = {floor_r, floor_r, floor_r, floor_r};
    v4_t vbest = v4_zero();
    for (; x + 4 <= xb; x += 4) {
        const v4_t sxx = v4_add(v4_add(v4_ld(vxx + x - 1), v4_ld(vxx + x)), v4_ld(vxx + x + 1));
        const v4_t sxy = v4_add(v4_add(v4_ld(vxy + x - 1), v4_ld(vxy + x)), v4_ld(vxy + x + 1));
        const v4_t syy = v4_add(v4_add(v4_ld(vyy + x - 1), v4_ld(vyy + x)), v4_ld(vyy + x + 1));
        const v4_t lt = sxx < syy;
        const v4_t mn = (lt & sxx) | (~lt & syy);
        const v4_t pass = (mn + mn) >= fl;
        const v4d_t d = __builtin_convertvector(sxx - syy, v4d_t);
        const v4d_t q = __builtin_convertvector(sxy, v4d_t);
        const v4d_t disc = d * d + 4.0 * q * q;
        const v4d_t root = {sqrt(disc[0]), sqrt(disc[1]), sqrt(disc[2]), sqrt(disc[3])};
        const v4_t r = (sxx + syy - __builtin_convertvector(root, v4_t)) & pass;
        v4_st(out + x, r);
        const v4_t gt = r > vbest;
        vbest = (gt & r) | (~gt & vbest);
    }
    for (int k = 0; k < 4; ++k) {
        best = vbest[k] > best ? vbest[k] : best;
    }
#endif
    for (; x < xb; ++x) {
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
        trk->id[n] = rp_track_id(cfg->cam, trk->next_k);
        trk->dormant[n] = 0;
        trk->next_k = (trk->next_k + 1u) & RP_TRACK_SERIAL_MASK;
        trk->n = (uint16_t)(n + 1);
        per_cell[c]++;
        ++added;
    }
    return added;
}

/* Tops up to want new features in the current level-0 image, away (min_dist) from the tracked
 * ones, with per-cell caps counting the tracked ones. Only cells under their fair share
 * (ceil(target / cells)) are searched first; the other cells under their cap only if the live
 * count (dormant tracks left out) is still under cfg.topup_below (or zero) after that. A first
 * frame searches every cell.
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
    const int live = (int)trk->n - (int)trk->n_dormant;
    if (added < want && (live < (int)cfg->topup_below || trk->n == 0)) {
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

/* The flow guess: once GUESS_MIN tracks of a frame passed (tracked from zero motion over all
 * cfg.levels levels), each next one starts from the displacement of the nearest of the last
 * tracks to pass in its bucketing cell and the 8 around it (a smooth flow varies little over that
 * distance: 0.55 px rms at 320x240 and 0.93 px at 640x480 on the benchmark's scenes, against 1.9
 * and 4.0 px for the frame's mean) on the finest level only. A track with no such neighbour, or
 * that fails from the guess (lost or failing the backward check, but not by leaving the image),
 * runs from zero motion over all levels, so a guess only saves work. (The frame's mean flow is no
 * guess where no neighbour is near: under forward motion there is no common flow.)
 * The backward check starts at the original position (the forward displacement reversed) on the
 * finest BACK_LEVELS levels: a consistent track returns there within cfg.fb_max_q16; a wrong one
 * (an occlusion, another surface) finds no fixed point near it or fails the residual test
 * (cfg.max_err_q5), which runs in the backward pass (the forward one when there is no backward
 * check): both compare the same two windows. */
#define GUESS_MIN 2
#define BACK_LEVELS 1

enum { TRACK_OK, TRACK_LOST, TRACK_LEFT, TRACK_LOST_FB };

/* Tracks level-0 position p from pyramid P into C over the n_lev finest levels, starting from
 * displacement g (Q16 px; NULL: zero), then checks it backward; use / store (NULL: none): the
 * cache slots of P's patch at p and of C's at f (lk_cache_t). *f: the forward result, inside
 * [0, wq] x [0, hq] (Q16 px) when TRACK_OK. Returns TRACK_OK, TRACK_LOST (lost forward),
 * TRACK_LEFT (tracked out of the image) or TRACK_LOST_FB (the backward check failed). */
static int track_fb(const rp_track_cfg_t *cfg, const rp_pyr_t *P, const rp_pyr_t *C, int n_lev,
                    const int32_t p[2], const int32_t *g, int32_t wq, int32_t hq,
                    lk_cache_t *use, lk_cache_t *store, int32_t f[2])
{
    if (!lk_point(cfg, P, C, n_lev, p, g, cfg->fb_max_q16 == 0, use, f)) {
        return TRACK_LOST;
    }
    if (f[0] < 0 || f[1] < 0 || f[0] > wq || f[1] > hq) {
        return TRACK_LEFT;
    }
    if (cfg->fb_max_q16 == 0) {
        return TRACK_OK;
    }
    const int32_t back[2] = {p[0] - f[0], p[1] - f[1]};
    int32_t b[2];
    if (!lk_point(cfg, C, P, BACK_LEVELS, f, back, 1, store, b)) {
        return TRACK_LOST_FB;
    }
    const int64_t dx = (int64_t)b[0] - p[0], dy = (int64_t)b[1] - p[1];
    if (dx * dx + dy * dy > (int64_t)cfg->fb_max_q16 * cfg->fb_max_q16) {
        return TRACK_LOST_FB;
    }
    return TRACK_OK;
}

/* The tracks that passed so far in a frame: in trk (compacted to the first n, flow_q16 their
 * displacements) and the last one per bucketing cell. */
typedef struct {
    uint16_t n;
    int16_t last[RP_TRACK_MAX_CELLS]; /* index of the last track passed in the cell, -1: none */
} flow_set_t;

/* The guess *g (Q16 px) for a track at p (Q16 px, previous image, bucketing cell column cx, row
 * cy): the displacement of the nearest passed track in the 3 x 3 cells around. Returns 1, or 0
 * if there is none. */
static int flow_guess(const rp_tracker_t *trk, const flow_set_t *fs, const int32_t p[2], int cx,
                      int cy, int32_t g[2])
{
    const rp_track_cfg_t *cfg = &trk->cfg;
    int64_t best = INT64_MAX;
    int bj = -1;
    for (int y = cy - 1; y <= cy + 1; ++y) {
        for (int x = cx - 1; x <= cx + 1; ++x) {
            const int j = x < 0 || y < 0 || x >= cfg->grid_x || y >= cfg->grid_y
                              ? -1
                              : fs->last[y * cfg->grid_x + x];
            if (j < 0) {
                continue;
            }
            const int64_t dx = (int64_t)trk->pos_q16[j][0] - trk->flow_q16[j][0] - p[0];
            const int64_t dy = (int64_t)trk->pos_q16[j][1] - trk->flow_q16[j][1] - p[1];
            const int64_t d = dx * dx + dy * dy;
            if (d < best) {
                best = d;
                bj = j;
            }
        }
    }
    if (bj < 0) {
        return 0;
    }
    g[0] = trk->flow_q16[bj][0];
    g[1] = trk->flow_q16[bj][1];
    return 1;
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
    trk->pyr_gen[nxt] = 0; /* no cached patch is of this pyramid until it is built */
    st = rp_pyr_build(&trk->pyr[nxt], img, trk->cfg.levels);
    if (st != RP_OK) {
        return st;
    }
    if (++trk->gen_next == 0u) {
        /* wrapped (after 2^32 images): no slot may keep a generation that comes round again
         * (emptied slots have generation 0, which no built pyramid has) */
        memset(trk->slot_key, 0, sizeof(trk->slot_key));
        trk->gen_next = 1u;
    }
    trk->pyr_gen[nxt] = trk->gen_next;
    if (trk->has_prev) {
        const rp_pyr_t *P = &trk->pyr[trk->cur], *C = &trk->pyr[nxt];
        const int32_t wq = (int32_t)(img->w - 1) * Q16, hq = (int32_t)(img->h - 1) * Q16;
        const rp_track_cfg_t *cfg = &trk->cfg;
        flow_set_t fs;
        fs.n = 0;
        for (int c = 0; c < RP_TRACK_MAX_CELLS; ++c) {
            fs.last[c] = -1;
        }
        uint32_t n_left = 0; /* tracked out of the image: not a failure */
        uint16_t n_dormant = 0;
        for (uint16_t i = 0; i < trk->n; ++i) {
            const int32_t p[2] = {trk->pos_q16[i][0], trk->pos_q16[i][1]};
            const int cell = cell_of(cfg, img->w, img->h, p[0] >> 16, p[1] >> 16);
            const int cx = cell % cfg->grid_x, cy = cell / cfg->grid_x;
            int32_t f[2];
            int r = TRACK_LOST;
            int32_t g[2];
            /* the cache: P's patch at p in slot i (stored by the last frame's backward check),
             * C's at f into slot fs.n, the index the track takes if it passes */
            lk_cache_t use = {NULL, NULL, trk->pyr_gen[trk->cur], 0, 0};
            lk_cache_t store = {NULL, NULL, trk->pyr_gen[nxt], 1, 0};
            if (i < trk->n_slots) {
                use.key = &trk->slot_key[i];
                use.pix = trk->slot_pix + (size_t)i * trk->slot_len;
            }
            if (fs.n < trk->n_slots) {
                store.key = &trk->slot_key[fs.n];
                store.pix = trk->slot_pix + (size_t)fs.n * trk->slot_len;
            }
            lk_cache_t *pu = use.key != NULL ? &use : NULL;
            lk_cache_t *ps = store.key != NULL ? &store : NULL;
            if (fs.n >= GUESS_MIN && flow_guess(trk, &fs, p, cx, cy, g)) {
                r = track_fb(cfg, P, C, 1, p, g, wq, hq, pu, ps, f);
            }
            if (r == TRACK_LOST || r == TRACK_LOST_FB) {
                r = track_fb(cfg, P, C, cfg->levels, p, NULL, wq, hq, pu, ps, f);
            }
            inf.n_cached = (uint16_t)(inf.n_cached + use.hit);
            if (r != TRACK_OK) {
                inf.n_lost_fb = (uint16_t)(inf.n_lost_fb + (r == TRACK_LOST_FB));
                inf.n_lost = (uint16_t)(inf.n_lost + (r != TRACK_LOST_FB));
                n_left += r == TRACK_LEFT;
                continue;
            }
            const uint16_t m = fs.n++;
            trk->id[m] = trk->id[i];
            trk->pos_q16[m][0] = f[0];
            trk->pos_q16[m][1] = f[1];
            trk->dormant[m] = trk->dormant[i];
            n_dormant = (uint16_t)(n_dormant + trk->dormant[i]);
            trk->flow_q16[m][0] = f[0] - p[0];
            trk->flow_q16[m][1] = f[1] - p[1];
            fs.last[cell] = (int16_t)m;
        }
        uint16_t m = fs.n;
        /* failed = lost or failing the backward check, of the tracks that stayed inside */
        const uint32_t failed = (uint32_t)inf.n_lost_fb + inf.n_lost - n_left;
        if (cfg->reset_q8 > 0 && m > 0 && inf.n_prev - n_left >= RP_TRACK_RESET_MIN &&
            failed * 256u >= (uint32_t)cfg->reset_q8 * (inf.n_prev - n_left)) {
            inf.n_reset = m;
            inf.flags |= RP_TRACK_RESET;
            m = 0;
            n_dormant = 0;
        }
        trk->n = m;
        trk->n_dormant = n_dormant;
        if (m == 0 && inf.n_prev > 0) {
            inf.flags |= RP_TRACK_ALL_LOST;
        }
    } else {
        inf.flags |= RP_TRACK_FIRST;
        trk->n = 0;
        trk->n_dormant = 0;
    }
    inf.n_tracked = trk->n;
    trk->cur = nxt;
    trk->has_prev = 1;
    trk->utime = utime;
    /* the budget counts live tracks only: dormant ones hold their place (rp_track.h) */
    const int live = (int)trk->n - (int)trk->n_dormant;
    if ((live < (int)trk->cfg.topup_below && trk->topup_turn) || trk->n == 0) {
        inf.n_new = (uint16_t)detect(trk, (int)trk->cfg.target - live);
        if (inf.n_new > 0) {
            inf.flags |= RP_TRACK_TOPPED_UP;
        }
    }
    st = rp_track_features(trk, out, cap, n_out);
    if (info != NULL) {
        *info = inf;
    }
    if (trk->n == 0) {
        return RP_E_TOO_FEW;
    }
    return st;
}
