/*
 * bt_scene.c - the tracker benchmark's scene (bt_scene.h): value-noise wall textures, the rig on
 * rp_sim's trajectory, plane-induced rendering with bilinear sampling.
 */
#include "bt_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rp_sim.h"

#define TEX 2048 /* texture side, texels (mirrored beyond) */

struct bt_scene {
    int w, h, n_frames;
    double f;               /* focal length, px */
    double texel_m;         /* texel size on a wall, m */
    rp_sim_run_t run;       /* trajectory and rig */
    uint8_t *tex[BT_NCAMS]; /* one texture per wall */
};

/* Wall of camera k: the plane n . X = dist (world frame), with in-plane axes e1, e2. The stereo
 * partners (rig cameras 4, 5) see the walls of cam1 and cam3. */
static const double wall_n[BT_NCAMS][3] = {{0, 0, 1}, {1, 0, 0}, {0, 0, -1}, {-1, 0, 0}};
static const double wall_e1[BT_NCAMS][3] = {{1, 0, 0}, {0, 0, -1}, {-1, 0, 0}, {0, 0, 1}};
static const double wall_e2[BT_NCAMS][3] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
static const double wall_dist[BT_NCAMS] = {1.0, 0.9, 1.1, 0.85}; /* m from the start */

static int wall_of(int k) { return k < BT_NCAMS ? k : (k == BT_NCAMS ? 0 : 2); }

/* Natural-looking texture: value noise over octaves (cells 256 .. 2 texels, amplitude
 * ~ cell^0.25, smoothstep interpolation) plus hard-edged blobs (discs and rectangles of random
 * size and grey, like stains and posters), then a contrast stretch to [10, 245]. */
static int make_texture(uint8_t *out, uint64_t seed)
{
    float *acc = calloc((size_t)TEX * TEX, sizeof(float));
    float *grid = malloc(sizeof(float) * (TEX / 2 + 2) * (TEX / 2 + 2));
    if (acc == NULL || grid == NULL) {
        free(acc);
        free(grid);
        return -1;
    }
    rp_rng_t rng;
    rp_rng_seed(&rng, seed);
    for (int cell = 256; cell >= 2; cell /= 2) {
        const int g = TEX / cell + 2;
        const float amp = (float)pow((double)cell, 0.25);
        for (int i = 0; i < g * g; ++i) {
            grid[i] = (float)rp_rng_uniform(&rng);
        }
        for (int y = 0; y < TEX; ++y) {
            const int gy = y / cell;
            float ty = (float)(y % cell) / (float)cell;
            ty = ty * ty * (3.0f - 2.0f * ty);
            for (int x = 0; x < TEX; ++x) {
                const int gx = x / cell;
                float tx = (float)(x % cell) / (float)cell;
                tx = tx * tx * (3.0f - 2.0f * tx);
                const float *q = grid + gy * g + gx;
                const float top = q[0] + (q[1] - q[0]) * tx, bot = q[g] + (q[g + 1] - q[g]) * tx;
                acc[(size_t)y * TEX + x] += amp * (top + (bot - top) * ty);
            }
        }
    }
    for (int i = 0; i < 800; ++i) {
        const int cx = (int)(rp_rng_uniform(&rng) * TEX), cy = (int)(rp_rng_uniform(&rng) * TEX);
        const int r = 4 + (int)(rp_rng_uniform(&rng) * 40);
        const int disc = rp_rng_uniform(&rng) < 0.5;
        const float add = (float)(rp_rng_uniform(&rng) - 0.5) * 8.0f;
        for (int y = cy - r; y <= cy + r; ++y) {
            for (int x = cx - r; x <= cx + r; ++x) {
                if (x < 0 || y < 0 || x >= TEX || y >= TEX ||
                    (disc && (x - cx) * (x - cx) + (y - cy) * (y - cy) > r * r)) {
                    continue;
                }
                acc[(size_t)y * TEX + x] += add;
            }
        }
    }
    float lo = acc[0], hi = acc[0];
    for (size_t i = 0; i < (size_t)TEX * TEX; ++i) {
        lo = acc[i] < lo ? acc[i] : lo;
        hi = acc[i] > hi ? acc[i] : hi;
    }
    for (size_t i = 0; i < (size_t)TEX * TEX; ++i) {
        out[i] = (uint8_t)(10.0f + 235.0f * (acc[i] - lo) / (hi - lo) + 0.5f);
    }
    free(acc);
    free(grid);
    return 0;
}

bt_scene_t *bt_scene_new(int w, int h, uint64_t seed, int n_frames)
{
    bt_scene_t *sc = calloc(1, sizeof(*sc));
    if (sc == NULL) {
        return NULL;
    }
    sc->w = w;
    sc->h = h;
    sc->n_frames = n_frames;
    sc->f = 800.0 * w / 640.0;
    sc->texel_m = 1.0 / sc->f; /* about one texel per pixel at 1 m */
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.n_points = 1;
    cfg.width = (uint16_t)w;
    cfg.height = (uint16_t)h;
    cfg.focal_px = sc->f;
    cfg.n_frames = (uint32_t)n_frames;
    if (rp_sim_run_init(&sc->run, &cfg, seed, 0) != 0) {
        free(sc);
        return NULL;
    }
    for (int k = 0; k < BT_NCAMS; ++k) {
        sc->tex[k] = malloc((size_t)TEX * TEX);
        if (sc->tex[k] == NULL || make_texture(sc->tex[k], seed * 16 + (uint64_t)k + 1) != 0) {
            bt_scene_free(sc);
            return NULL;
        }
    }
    return sc;
}

void bt_scene_free(bt_scene_t *sc)
{
    if (sc == NULL) {
        return;
    }
    for (int k = 0; k < BT_NCAMS; ++k) {
        free(sc->tex[k]);
    }
    rp_sim_run_free(&sc->run);
    free(sc);
}

const rp_rig_t *bt_scene_rig(const bt_scene_t *sc) { return &sc->run.rig; }

const double *bt_scene_pose(const bt_scene_t *sc, int frame) { return sc->run.truth + 6 * frame; }

/* Camera k at frame j in the world: rotation Rw (camera-to-world, row-major), centre c. */
static void cam_pose(const bt_scene_t *sc, int frame, int k, double Rw[9], double c[3])
{
    const double *Rj = sc->run.truth_R + 9 * frame, *dj = sc->run.truth + 6 * frame;
    const rp_rig_cam_t *rc = &sc->run.rig.cam[k];
    for (int r = 0; r < 3; ++r) {
        c[r] = dj[r];
        for (int i = 0; i < 3; ++i) {
            c[r] += Rj[3 * r + i] * (double)rc->D[i];
            double s = 0;
            for (int m = 0; m < 3; ++m) {
                s += Rj[3 * r + m] * (double)rc->R[3 * m + i];
            }
            Rw[3 * r + i] = s;
        }
    }
}

/* Homography pixel -> wall coordinates in texels: [a b s] = H [u v 1], (a/s, b/s). */
static void pixel_to_wall(const bt_scene_t *sc, int frame, int k, double H[9])
{
    double Rw[9], c[3];
    cam_pose(sc, frame, k, Rw, c);
    const double cx = 0.5 * (sc->w - 1), cy = 0.5 * (sc->h - 1), f = sc->f;
    /* ray r = Rw Kinv [u v 1]; X = c + t r with t = (dist - n.c) / (n.r) */
    const double Ki[9] = {1 / f, 0, -cx / f, 0, 1 / f, -cy / f, 0, 0, 1};
    double M[9]; /* Rw Kinv */
    for (int r = 0; r < 3; ++r) {
        for (int i = 0; i < 3; ++i) {
            M[3 * r + i] = Rw[3 * r] * Ki[i] + Rw[3 * r + 1] * Ki[3 + i] + Rw[3 * r + 2] * Ki[6 + i];
        }
    }
    const int wl = wall_of(k);
    const double *n = wall_n[wl], *e1 = wall_e1[wl], *e2 = wall_e2[wl];
    const double dn = wall_dist[wl] - (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]);
    /* e.X = e.c + t e.r, t = dn / n.r: homogeneous [e1.c n.r + dn e1.r, ..., n.r] */
    const double ec1 = e1[0] * c[0] + e1[1] * c[1] + e1[2] * c[2];
    const double ec2 = e2[0] * c[0] + e2[1] * c[1] + e2[2] * c[2];
    for (int i = 0; i < 3; ++i) {
        const double nr = n[0] * M[i] + n[1] * M[3 + i] + n[2] * M[6 + i];
        const double e1r = e1[0] * M[i] + e1[1] * M[3 + i] + e1[2] * M[6 + i];
        const double e2r = e2[0] * M[i] + e2[1] * M[3 + i] + e2[2] * M[6 + i];
        H[i] = (ec1 * nr + dn * e1r) / sc->texel_m + TEX / 2 * nr;
        H[3 + i] = (ec2 * nr + dn * e2r) / sc->texel_m + TEX / 2 * nr;
        H[6 + i] = nr;
    }
}

static int mirror(int i)
{
    const int p = 2 * TEX;
    i %= p;
    if (i < 0) {
        i += p;
    }
    return i < TEX ? i : p - 1 - i;
}

void bt_scene_render(bt_scene_t *sc, int frame, int k, uint8_t *img)
{
    double H[9];
    pixel_to_wall(sc, frame, k, H);
    const uint8_t *t = sc->tex[wall_of(k)];
    for (int v = 0; v < sc->h; ++v) {
        for (int u = 0; u < sc->w; ++u) {
            const double s = H[6] * u + H[7] * v + H[8];
            uint8_t out = 128;
            if (s > 0) {
                const double a = (H[0] * u + H[1] * v + H[2]) / s;
                const double b = (H[3] * u + H[4] * v + H[5]) / s;
                const double fa = floor(a), fb = floor(b);
                const int ia = (int)fa, ib = (int)fb;
                const double wa = a - fa, wb = b - fb;
                const int a0 = mirror(ia), a1 = mirror(ia + 1), b0 = mirror(ib), b1 = mirror(ib + 1);
                const double g = (1 - wb) * ((1 - wa) * t[(size_t)b0 * TEX + a0] +
                                             wa * t[(size_t)b0 * TEX + a1]) +
                                 wb * ((1 - wa) * t[(size_t)b1 * TEX + a0] +
                                       wa * t[(size_t)b1 * TEX + a1]);
                out = (uint8_t)(g + 0.5);
            }
            img[(size_t)v * sc->w + u] = out;
        }
    }
}

/* Solves the 3x3 system H x = y (Cramer). */
static int solve3(const double H[9], const double y[3], double x[3])
{
    const double det = H[0] * (H[4] * H[8] - H[5] * H[7]) - H[1] * (H[3] * H[8] - H[5] * H[6]) +
                       H[2] * (H[3] * H[7] - H[4] * H[6]);
    if (fabs(det) < 1e-300) {
        return 0;
    }
    for (int c = 0; c < 3; ++c) {
        double M[9];
        memcpy(M, H, sizeof(M));
        M[c] = y[0];
        M[3 + c] = y[1];
        M[6 + c] = y[2];
        x[c] = (M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
                M[2] * (M[3] * M[7] - M[4] * M[6])) / det;
    }
    return 1;
}

int bt_scene_transfer(const bt_scene_t *sc, int k, int fa, const double uv_a[2], int fb,
                      double uv_b[2])
{
    double Ha[9], Hb[9];
    pixel_to_wall(sc, fa, k, Ha);
    pixel_to_wall(sc, fb, k, Hb);
    const double s = Ha[6] * uv_a[0] + Ha[7] * uv_a[1] + Ha[8];
    if (s <= 0) {
        return 0;
    }
    const double y[3] = {(Ha[0] * uv_a[0] + Ha[1] * uv_a[1] + Ha[2]) / s,
                         (Ha[3] * uv_a[0] + Ha[4] * uv_a[1] + Ha[5]) / s, 1.0};
    double x[3];
    if (!solve3(Hb, y, x) || x[2] <= 0) {
        return 0;
    }
    uv_b[0] = x[0] / x[2];
    uv_b[1] = x[1] / x[2];
    return 1;
}
