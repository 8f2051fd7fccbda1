/*
 * rp_track.c - pyramids, Shi-Tomasi detection with bucketing, pyramidal Lucas-Kanade with a
 * forward-backward check (rp_track.h). Integer arithmetic only; formats named where used.
 * The LK step follows OpenCV's calcOpticalFlowPyrLK (Bouguet's pyramidal LK): Scharr gradients of
 * the previous image, Q14 bilinear weights, intensities in Q5, the 2x2 normal equations solved per
 * iteration; here the sums are exact int64 and the solve is integer.
 */
#include <string.h>

#include "priv/rp_math.h"
#include "rigpose/rp_track.h"

#define Q16 65536
#define W_BITS 14 /* bilinear weights, Q14 */

/* ---- small integer helpers ------------------------------------------------------------------ */

/* floor(sqrt(x)) for any uint64. */
static uint64_t isqrt64(uint64_t x)
{
    uint64_t r = 0, bit = (uint64_t)1 << 62;
    while (bit > x) {
        bit >>= 2;
    }
    while (bit != 0) {
        if (x >= r + bit) {
            x -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    return r;
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

/* Raw pixel with replicated border. */
static int px_at(const uint8_t *p, int w, int h, int x, int y)
{
    return p[(size_t)clampi(y, 0, h - 1) * w + clampi(x, 0, w - 1)];
}

/* Q14 bilinear weights of the fractional part (Q16) of a position, as OpenCV: rounded, summing
 * to exactly 2^14. */
static void weights_q14(int32_t fx_q16, int32_t fy_q16, int32_t w[4])
{
    const int64_t a = fx_q16, b = fy_q16; /* Q16 in [0, 1) */
    const int64_t one = Q16;
    /* (Q16 * Q16) = Q32 -> Q14: >> 18, rounded */
    w[0] = (int32_t)(((one - a) * (one - b) + (1 << 17)) >> 18);
    w[1] = (int32_t)((a * (one - b) + (1 << 17)) >> 18);
    w[2] = (int32_t)(((one - a) * b + (1 << 17)) >> 18);
    w[3] = (1 << W_BITS) - w[0] - w[1] - w[2];
}

#define PATCH_MAX (RP_TRACK_MAX_WIN * RP_TRACK_MAX_WIN)
#define GRID_MAX ((RP_TRACK_MAX_WIN + 1) * (RP_TRACK_MAX_WIN + 1))

/* Tracks one point from level image pair (I, J) of pyramids pI, pJ. p_q16: level-0 position in
 * I; *q_q16: level-0 result in J. Returns 1 if tracked, 0 if lost (out of bounds, too little
 * texture, singular at level 0, residual above cfg.max_err_q5). */
static int lk_point(const rp_track_cfg_t *cfg, const rp_pyr_t *pI, const rp_pyr_t *pJ,
                    const int32_t p_q16[2], int32_t q_q16[2])
{
    const int win = cfg->win, half = (cfg->win - 1) / 2;
    const int area = win * win;
    int16_t Ival[PATCH_MAX], Ix[PATCH_MAX], Iy[PATCH_MAX]; /* Q5; Scharr */
    int16_t Gg[GRID_MAX], Gx[GRID_MAX], Gy[GRID_MAX];      /* grey; Scharr at the grid */
    int n_lev = pI->n_lev < pJ->n_lev ? pI->n_lev : pJ->n_lev;
    if (n_lev > cfg->levels) {
        n_lev = cfg->levels;
    }
    int32_t nx = 0, ny = 0; /* level position of the estimate in J, Q16 */
    int32_t res_last = 0;   /* residual of the last iteration, sum |J - I|, Q5 */
    const int64_t eps2 = (int64_t)cfg->eps_q16 * cfg->eps_q16;

    for (int l = n_lev - 1; l >= 0; --l) {
        const rp_pyr_level_t *LI = &pI->lev[l], *LJ = &pJ->lev[l];
        const uint8_t *I = pI->pix + LI->off, *J = pJ->pix + LJ->off;
        const int wI = LI->w, hI = LI->h, wJ = LJ->w, hJ = LJ->h;
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
        int32_t wt[4];
        weights_q14(ox & 0xffff, oy & 0xffff, wt);
        /* Patch of I and its Scharr gradients ([3 10 3]^T x [-1 0 1], |.| <= 16 * 255 = 4080)
         * on the (win+1)^2 integer grid (border replicated), then interpolated. */
        const int gw = win + 1;
        const int in_I = ix >= 1 && iy >= 1 && ix + gw < wI && iy + gw < hI; /* no clamping */
        for (int y = 0; y < gw; ++y) {
            for (int x = 0; x < gw; ++x) {
                const int X = ix + x, Y = iy + y;
                int a0, a1, a2, b0, b1, b2, c0, c1, c2;
                if (in_I) {
                    const uint8_t *q = I + (size_t)Y * wI + X;
                    a0 = q[-wI - 1]; a1 = q[-wI]; a2 = q[-wI + 1];
                    b0 = q[-1]; b1 = q[0]; b2 = q[1];
                    c0 = q[wI - 1]; c1 = q[wI]; c2 = q[wI + 1];
                } else {
                    a0 = px_at(I, wI, hI, X - 1, Y - 1); a1 = px_at(I, wI, hI, X, Y - 1);
                    a2 = px_at(I, wI, hI, X + 1, Y - 1); b0 = px_at(I, wI, hI, X - 1, Y);
                    b1 = px_at(I, wI, hI, X, Y); b2 = px_at(I, wI, hI, X + 1, Y);
                    c0 = px_at(I, wI, hI, X - 1, Y + 1); c1 = px_at(I, wI, hI, X, Y + 1);
                    c2 = px_at(I, wI, hI, X + 1, Y + 1);
                }
                const int k = y * gw + x;
                Gg[k] = (int16_t)b1;
                Gx[k] = (int16_t)(3 * (a2 - a0) + 10 * (b2 - b0) + 3 * (c2 - c0));
                Gy[k] = (int16_t)(3 * (c0 - a0) + 10 * (c1 - a1) + 3 * (c2 - a2));
            }
        }
        int64_t A11 = 0, A12 = 0, A22 = 0;
        for (int y = 0; y < win; ++y) {
            for (int x = 0; x < win; ++x) {
                const int k0 = y * gw + x, k1 = k0 + 1, k2 = k0 + gw, k3 = k2 + 1;
                /* intensity: Q0 * Q14 -> Q5 (>> 9, rounded), <= 8160; gradient Q14 -> Q0 */
                const int32_t iv = (Gg[k0] * wt[0] + Gg[k1] * wt[1] + Gg[k2] * wt[2] +
                                    Gg[k3] * wt[3] + (1 << 8)) >> 9;
                const int32_t gx = (Gx[k0] * wt[0] + Gx[k1] * wt[1] + Gx[k2] * wt[2] +
                                    Gx[k3] * wt[3] + (1 << 13)) >> 14;
                const int32_t gy = (Gy[k0] * wt[0] + Gy[k1] * wt[1] + Gy[k2] * wt[2] +
                                    Gy[k3] * wt[3] + (1 << 13)) >> 14;
                const int k = y * win + x;
                Ival[k] = (int16_t)iv;
                Ix[k] = (int16_t)gx;
                Iy[k] = (int16_t)gy;
                A11 += (int64_t)gx * gx;
                A12 += (int64_t)gx * gy;
                A22 += (int64_t)gy * gy;
            }
        }
        /* Texture test: min eigenvalue of A / area vs cfg.min_eig (OpenCV's units x 2^20, A in
         * Scharr^2 like OpenCV before its 2^-20 scale). Work with A >> s < 2^29. */
        {
            int s = 0;
            while (((A11 | A22 | iabs64(A12)) >> s) >= ((int64_t)1 << 29)) {
                ++s;
            }
            const int64_t a = A11 >> s, c = A22 >> s, b = A12 >> s;
            const int64_t disc = (a - c) * (a - c) + 4 * b * b;
            const int64_t two_min = a + c - (int64_t)isqrt64((uint64_t)disc); /* 2 x min eig */
            const int64_t thr = ((int64_t)2 * area * cfg->min_eig) >> s;
            if (two_min < thr || a * c - b * b <= 0) {
                if (l == 0) {
                    return 0;
                }
                continue;
            }
        }
        int32_t pdx = 0, pdy = 0; /* previous step, Q16 */
        for (int it = 0; it < cfg->max_iter; ++it) {
            const int32_t jx0 = nx - half * Q16, jy0 = ny - half * Q16;
            const int jx = jx0 >> 16, jy = jy0 >> 16;
            if (jx < -win || jx >= wJ || jy < -win || jy >= hJ) {
                if (l == 0) {
                    return 0;
                }
                break;
            }
            int32_t wj[4];
            weights_q14(jx0 & 0xffff, jy0 & 0xffff, wj);
            int64_t b1 = 0, b2 = 0;
            int32_t res = 0; /* sum |J - I| over the window, Q5, <= 8160 * 63^2 < 2^25 */
            const int inside = jx >= 0 && jy >= 0 && jx + win < wJ && jy + win < hJ;
            for (int y = 0; y < win; ++y) {
                for (int x = 0; x < win; ++x) {
                    int g0, g1, g2, g3;
                    if (inside) {
                        const uint8_t *r = J + (size_t)(jy + y) * wJ + jx + x;
                        g0 = r[0];
                        g1 = r[1];
                        g2 = r[wJ];
                        g3 = r[wJ + 1];
                    } else {
                        g0 = px_at(J, wJ, hJ, jx + x, jy + y);
                        g1 = px_at(J, wJ, hJ, jx + x + 1, jy + y);
                        g2 = px_at(J, wJ, hJ, jx + x, jy + y + 1);
                        g3 = px_at(J, wJ, hJ, jx + x + 1, jy + y + 1);
                    }
                    const int32_t jv = (g0 * wj[0] + g1 * wj[1] + g2 * wj[2] + g3 * wj[3] +
                                        (1 << 8)) >> 9; /* Q5 */
                    const int k = y * win + x;
                    const int32_t diff = jv - Ival[k]; /* Q5, |.| <= 8160 */
                    res += diff < 0 ? -diff : diff;
                    b1 += (int64_t)diff * Ix[k];
                    b2 += (int64_t)diff * Iy[k];
                }
            }
            /* delta = -A^-1 b (px: Q5 x Scharr over Scharr^2 x 32 = px). Scale A, b by 2^-s so
             * all < 2^22: det < 2^44, numerators < 2^45, times 2^16 < 2^61 (no overflow). */
            int s = 0;
            while (((A11 | A22 | iabs64(b1) | iabs64(b2)) >> s) >= ((int64_t)1 << 22)) {
                ++s;
            }
            const int64_t a = A11 >> s, c = A22 >> s, b = A12 >> s, u = b1 >> s, v = b2 >> s;
            res_last = res;
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

/* Shi-Tomasi response 2 x min eigenvalue of the 3x3-block structure tensor of 3x3 Sobel
 * gradients (as cv::cornerMinEigenVal, blockSize 3, up to its positive scale), Sobel |.| <= 1020,
 * tensor entries <= 9 * 1020^2 < 2^24 (int32), response in int32. Pixels within 2 of the border
 * get 0, and so do pixels whose bound 2 min(a, c) is under cfg.min_response (no square root
 * spent on flat areas). Streams the gradient products through a 3-row ring. Returns the largest
 * response. */
static int32_t response_map(rp_tracker_t *trk, const uint8_t *p, int w, int h)
{
    int32_t *R = trk->resp;
    int32_t best = 0;
    const int32_t floor_r = (int32_t)trk->cfg.min_response;
    memset(R, 0, sizeof(int32_t) * (size_t)w * h);
    for (int y = 1; y < h - 1; ++y) {
        /* products of row y into ring slot y % 3 */
        int32_t *xx = trk->ring[y % 3][0], *xy = trk->ring[y % 3][1], *yy = trk->ring[y % 3][2];
        const uint8_t *r0 = p + (size_t)(y - 1) * w, *r1 = r0 + w, *r2 = r1 + w;
        for (int x = 1; x < w - 1; ++x) {
            const int gx = (r0[x + 1] - r0[x - 1]) + 2 * (r1[x + 1] - r1[x - 1]) +
                           (r2[x + 1] - r2[x - 1]);
            const int gy = (r2[x - 1] - r0[x - 1]) + 2 * (r2[x] - r0[x]) + (r2[x + 1] - r0[x + 1]);
            xx[x] = gx * gx;
            xy[x] = gx * gy;
            yy[x] = gy * gy;
        }
        if (y < 3) {
            continue;
        }
        const int yc = y - 1; /* block rows yc-1 .. yc+1 are in the ring now */
        if (yc >= h - 2) {
            break;
        }
        const int32_t(*ra)[RP_TRACK_MAX_W] = trk->ring[(yc - 1) % 3];
        const int32_t(*rb)[RP_TRACK_MAX_W] = trk->ring[yc % 3];
        const int32_t(*rc)[RP_TRACK_MAX_W] = trk->ring[(yc + 1) % 3];
        int32_t *Rrow = R + (size_t)yc * w;
        for (int x = 2; x < w - 2; ++x) {
            int32_t sxx = 0, sxy = 0, syy = 0;
            for (int i = x - 1; i <= x + 1; ++i) {
                sxx += ra[0][i] + rb[0][i] + rc[0][i];
                sxy += ra[1][i] + rb[1][i] + rc[1][i];
                syy += ra[2][i] + rb[2][i] + rc[2][i];
            }
            if (2 * (sxx < syy ? sxx : syy) < floor_r) {
                continue;
            }
            const int64_t d = (int64_t)(sxx - syy);
            const int64_t disc = d * d + 4 * (int64_t)sxy * sxy;
            const int32_t r = (int32_t)((int64_t)sxx + syy - (int64_t)isqrt64((uint64_t)disc));
            Rrow[x] = r;
            if (r > best) {
                best = r;
            }
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

/* Detects up to want new features in the current level-0 image, away (min_dist) from the
 * tracked ones, with per-cell caps counting the tracked ones. Returns the number added. */
static int detect(rp_tracker_t *trk, int want)
{
    const rp_track_cfg_t *cfg = &trk->cfg;
    const rp_pyr_t *P = &trk->pyr[trk->cur];
    const int w = P->lev[0].w, h = P->lev[0].h;
    const uint8_t *p = P->pix;
    const int ncell = cfg->grid_x * cfg->grid_y;
    if (want <= 0) {
        return 0;
    }
    const int32_t best = response_map(trk, p, w, h);
    int32_t thr = (int32_t)(((int64_t)best * cfg->quality_q16) >> 16);
    if (thr < (int32_t)cfg->min_response) {
        thr = (int32_t)cfg->min_response;
    }
    if (best < thr || best <= 0) {
        return 0;
    }
    for (int c = 0; c < ncell; ++c) {
        trk->n_cand[c] = 0;
    }
    /* local maxima (>= the 8 neighbours, as cv::dilate), kept per cell, best K by insertion */
    const int32_t *R = trk->resp;
    for (int y = 3; y < h - 3; ++y) {
        for (int x = 3; x < w - 3; ++x) {
            const int32_t *r = R + (size_t)y * w + x;
            const int32_t v = r[0];
            if (v < thr || v < r[-1] || v < r[1] || v < r[-w - 1] || v < r[-w] || v < r[-w + 1] ||
                v < r[w - 1] || v < r[w] || v < r[w + 1]) {
                continue;
            }
            const int c = cell_of(cfg, w, h, x, y);
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
    int nl = 0;
    for (int c = 0; c < ncell; ++c) {
        for (int i = 0; i < trk->n_cand[c]; ++i) {
            trk->list[nl++] = trk->cand[c][i];
        }
    }
    sort_cands(trk->list, nl);
    uint16_t per_cell[RP_TRACK_MAX_CELLS];
    for (int c = 0; c < ncell; ++c) {
        per_cell[c] = 0;
    }
    for (int i = 0; i < trk->n; ++i) {
        per_cell[cell_of(cfg, w, h, trk->pos_q16[i][0] >> 16, trk->pos_q16[i][1] >> 16)]++;
    }
    const int64_t md2 = (int64_t)cfg->min_dist * cfg->min_dist * Q16 * Q16; /* Q32 px^2 */
    int added = 0;
    for (int i = 0; i < nl && added < want && trk->n < RP_MAX_FEATS_PER_CAM; ++i) {
        const rp_track_cand_t *k = &trk->list[i];
        const int c = cell_of(cfg, w, h, k->x, k->y);
        if (per_cell[c] >= cfg->cell_cap) {
            continue;
        }
        const int32_t kx = (int32_t)k->x * Q16, ky = (int32_t)k->y * Q16;
        int ok = 1;
        for (int f = 0; f < trk->n && ok; ++f) {
            const int64_t dx = (int64_t)trk->pos_q16[f][0] - kx, dy = (int64_t)trk->pos_q16[f][1] - ky;
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

/* ---- the per-frame step --------------------------------------------------------------------- */

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
            if (!lk_point(&trk->cfg, P, C, trk->pos_q16[i], f) || f[0] < 0 || f[1] < 0 ||
                f[0] > wq || f[1] > hq) {
                inf.n_lost++;
                continue;
            }
            if (trk->cfg.fb_max_q16 > 0) {
                if (!lk_point(&trk->cfg, C, P, f, b)) {
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
