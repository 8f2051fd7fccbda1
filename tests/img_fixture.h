/*
 * img_fixture.h - synthetic grey images for the image-path tests (test_smatch.c, test_pipe.c):
 * a textured box room seen by the cameras of a rig at a known pose, rendered in C by casting
 * each pixel's ray (rp_cam_unproject, so distortion is honoured) to the walls.
 *
 * The room: an axis-aligned box of half sizes hx, hy, hz in its own frame, turned by yaw about
 * the world's y axis and centred at the world origin; every wall carries value noise (two
 * octaves, bilinear lattice interpolation, cells of 0.012 m and 0.04 m), distinct per wall and
 * seed. `stripes` replaces it with vertical stripes of period stripe_m on every wall (a
 * repeated texture: stereo matching must see it is ambiguous). Deterministic, no heap.
 */
#ifndef IMG_FIXTURE_H
#define IMG_FIXTURE_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rigpose/rp_camera.h"
#include "rigpose/rp_rig.h"
#include "rigpose/rp_track.h"

typedef struct {
    double hx, hy, hz; /* half sizes, m */
    double yaw;        /* rotation of the room about the world y axis, rad */
    uint32_t seed;
    int stripes;       /* 1: vertical stripes instead of value noise */
    double stripe_m;   /* stripe period, m */
} fx_room_t;

static inline fx_room_t fx_room_default(void)
{
    fx_room_t r;
    r.hx = 1.2;
    r.hy = 0.9;
    r.hz = 1.3;
    r.yaw = 0.35;
    r.seed = 7;
    r.stripes = 0;
    r.stripe_m = 0.03;
    return r;
}

static inline double fx_lattice(uint32_t seed, int32_t i, int32_t j)
{
    uint32_t h = seed * 0x9E3779B1u ^ (uint32_t)i * 0x85EBCA77u ^ (uint32_t)j * 0xC2B2AE3Du;
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 12;
    h *= 0x297A2D39u;
    h ^= h >> 15;
    return (double)(h & 0xffffu) / 65535.0;
}

/* Value noise in [0, 1] at (s, t) with cells of `cell` metres, smoothstep interpolation. */
static inline double fx_noise(uint32_t seed, double s, double t, double cell)
{
    const double x = s / cell, y = t / cell;
    const double fx = floor(x), fy = floor(y);
    const int32_t i = (int32_t)fx, j = (int32_t)fy;
    double a = x - fx, b = y - fy;
    a = a * a * (3.0 - 2.0 * a);
    b = b * b * (3.0 - 2.0 * b);
    const double v00 = fx_lattice(seed, i, j), v10 = fx_lattice(seed, i + 1, j);
    const double v01 = fx_lattice(seed, i, j + 1), v11 = fx_lattice(seed, i + 1, j + 1);
    return (v00 * (1 - a) + v10 * a) * (1 - b) + (v01 * (1 - a) + v11 * a) * b;
}

/* Distance t along the world ray o + t d to the room's wall, the hit in the room frame (q) and
 * the wall (0..5); -1 if the origin is outside the room. */
static inline int fx_room_hit(const fx_room_t *rm, const double o[3], const double d[3],
                              double *t_out, double q[3])
{
    const double c = cos(rm->yaw), s = sin(rm->yaw);
    /* room frame: x' = R^T x with R = Ry(yaw) */
    const double ro[3] = {c * o[0] - s * o[2], o[1], s * o[0] + c * o[2]};
    const double rd[3] = {c * d[0] - s * d[2], d[1], s * d[0] + c * d[2]};
    const double h[3] = {rm->hx, rm->hy, rm->hz};
    double tb = 1e30;
    int wall = -1;
    for (int k = 0; k < 3; ++k) {
        if (fabs(ro[k]) >= h[k]) {
            return -1;
        }
        if (rd[k] > 1e-12 || rd[k] < -1e-12) {
            const double t = ((rd[k] > 0 ? h[k] : -h[k]) - ro[k]) / rd[k];
            if (t < tb) {
                tb = t;
                wall = 2 * k + (rd[k] > 0);
            }
        }
    }
    for (int k = 0; k < 3; ++k) {
        q[k] = ro[k] + tb * rd[k];
    }
    *t_out = tb;
    return wall;
}

/* Grey level (0..255) of the room at wall point q (room frame). */
static inline double fx_room_grey(const fx_room_t *rm, int wall, const double q[3])
{
    /* wall coordinates: the two box axes along the wall */
    const int ax = wall / 2;
    const double s = q[ax == 0 ? 2 : 0], t = q[ax == 1 ? 2 : 1];
    if (rm->stripes) {
        const double ph = (ax == 1 ? t : s) / rm->stripe_m;
        return 128.0 + 90.0 * sin(2.0 * 3.14159265358979 * ph);
    }
    const uint32_t sd = rm->seed * 8u + (uint32_t)wall;
    const double v = 0.65 * fx_noise(sd, s, t, 0.012) + 0.35 * fx_noise(sd ^ 0xABCDu, s, t, 0.04);
    return 20.0 + 215.0 * v;
}

/* World ray of pixel (u, v) of camera k at rig pose p: origin o, direction d (not unit).
 * Returns 0, or -1 if the pixel has no ray (undistortion failed). */
static inline int fx_pixel_ray(const rp_rig_t *rig, int k, const rp_pose_lin_t *pl, double u,
                               double v, double o[3], double d[3])
{
    const rp_real uv[2] = {(rp_real)u, (rp_real)v};
    rp_real xn[2];
    if (rp_cam_unproject(&rig->cam[k].cam, uv, xn) != RP_OK) {
        return -1;
    }
    const double r[3] = {(double)xn[0], (double)xn[1], 1.0};
    double rc[3]; /* in cam1's frame: R_k r */
    for (int i = 0; i < 3; ++i) {
        rc[i] = 0;
        for (int j = 0; j < 3; ++j) {
            rc[i] += (double)rig->cam[k].R[3 * i + j] * r[j];
        }
    }
    for (int i = 0; i < 3; ++i) {
        d[i] = 0;
        o[i] = (double)pl->p[i];
        for (int j = 0; j < 3; ++j) {
            d[i] += (double)pl->R[3 * i + j] * rc[j];
            o[i] += (double)pl->R[3 * i + j] * (double)rig->cam[k].D[j];
        }
    }
    return 0;
}

/* Render camera k of rig at pose p into img (width x height of its calibration, stride w);
 * pixels without a wall are 0. noise_amp: uniform noise +-amp grey levels from state *rs. */
static inline void fx_render(const rp_rig_t *rig, int k, const rp_real p[6], const fx_room_t *rm,
                             uint8_t *img, double noise_amp, uint64_t *rs)
{
    rp_pose_lin_t pl;
    rp_pose_lin_set(&pl, p);
    const rp_camera_t *c = &rig->cam[k].cam;
    for (int v = 0; v < c->height; ++v) {
        for (int u = 0; u < c->width; ++u) {
            double o[3], d[3], q[3], t;
            double g = 0;
            if (fx_pixel_ray(rig, k, &pl, u, v, o, d) == 0) {
                const int wall = fx_room_hit(rm, o, d, &t, q);
                if (wall >= 0) {
                    g = fx_room_grey(rm, wall, q);
                }
            }
            if (noise_amp > 0 && rs != NULL) {
                *rs = *rs * 6364136223846793005ULL + 1442695040888963407ULL;
                g += noise_amp * (2.0 * (double)(*rs >> 11) / 9007199254740992.0 - 1.0);
            }
            g = g < 0 ? 0 : (g > 255 ? 255 : g);
            img[(size_t)v * c->width + u] = (uint8_t)(g + 0.5);
        }
    }
}

/* World point seen at pixel uv of camera k at pose p (on the room's wall). Returns 0 or -1. */
static inline int fx_pixel_point(const rp_rig_t *rig, int k, const rp_real p[6],
                                 const fx_room_t *rm, const rp_real uv[2], rp_real M[3])
{
    rp_pose_lin_t pl;
    rp_pose_lin_set(&pl, p);
    double o[3], d[3], q[3], t;
    if (fx_pixel_ray(rig, k, &pl, (double)uv[0], (double)uv[1], o, d) != 0 ||
        fx_room_hit(rm, o, d, &t, q) < 0) {
        return -1;
    }
    for (int i = 0; i < 3; ++i) {
        M[i] = (rp_real)(o[i] + t * d[i]);
    }
    return 0;
}

/* An rp_image_t over a packed buffer. */
static inline rp_image_t fx_image(const uint8_t *data, uint16_t w, uint16_t h)
{
    rp_image_t im;
    im.data = data;
    im.w = w;
    im.h = h;
    im.stride = w;
    im.size = (uint32_t)w * h;
    return im;
}

#endif /* IMG_FIXTURE_H */
