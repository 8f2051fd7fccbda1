/*
 * rp_discs.cpp - the "points" scene: rp_sim's own point cloud made visible as small textured
 * discs (see rp_render.hpp, DiscScene).
 */
#include "rp_render.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

namespace rpr {

namespace {

double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Smoothstep: 0 at x <= 0, 1 at x >= 1, C1 in between. */
double smooth01(double x)
{
    x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
    return x * x * (3.0 - 2.0 * x);
}

} /* namespace */

DiscScene::DiscScene(const std::vector<double> &centres, const DiscCfg &cfg)
    : cfg_(cfg), noise_(key(cfg.seed, 0x701CE))
{
    const size_t n = centres.size() / 3u;
    discs_.resize(n);
    std::mt19937_64 rng(cfg.seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (size_t i = 0; i < n; ++i) {
        Disc &D = discs_[i];
        std::memcpy(D.c, &centres[3u * i], sizeof D.c);
        /* Normal towards the world origin (the rig's start): every camera sees it nearly
         * face-on. A centre at the origin faces +z. */
        const double r = std::sqrt(dot3(D.c, D.c));
        const double nz[3] = {0.0, 0.0, -1.0};
        for (int a = 0; a < 3; ++a) {
            D.n[a] = r > 1e-9 ? -D.c[a] / r : nz[a];
        }
        /* e1: the world axis least aligned with n, made orthogonal to it; e2 = n x e1. */
        int ax = 0;
        for (int a = 1; a < 3; ++a) {
            ax = std::fabs(D.n[a]) < std::fabs(D.n[ax]) ? a : ax;
        }
        double e[3] = {0.0, 0.0, 0.0};
        e[ax] = 1.0;
        const double en = dot3(e, D.n);
        for (int a = 0; a < 3; ++a) {
            e[a] -= en * D.n[a];
        }
        const double el = std::sqrt(dot3(e, e));
        for (int a = 0; a < 3; ++a) {
            D.e1[a] = e[a] / el;
        }
        D.e2[0] = D.n[1] * D.e1[2] - D.n[2] * D.e1[1];
        D.e2[1] = D.n[2] * D.e1[0] - D.n[0] * D.e1[2];
        D.e2[2] = D.n[0] * D.e1[1] - D.n[1] * D.e1[0];
        /* Body grey level away from the background, and gradient noise in the disc's plane
         * (its own patch of the noise field: no two discs alike): the corners a tracker finds. */
        const double lift = 0.12 + 0.15 * uni(rng);
        D.level = (float)(cfg.background + (uni(rng) < 0.5 ? -lift : lift));
        for (int a = 0; a < 3; ++a) {
            D.off[a] = (float)(200.0 * uni(rng));
        }
    }
}

const double *DiscScene::centre(size_t i) const { return discs_[i].c; }

void DiscScene::axes(size_t i, double n[3], double e1[3], double e2[3]) const
{
    const Disc &D = discs_[i];
    for (int a = 0; a < 3; ++a) {
        n[a] = D.n[a];
        e1[a] = D.e1[a];
        e2[a] = D.e2[a];
    }
}

void DiscScene::look(size_t i, double a, double b, float *albedo, float *alpha) const
{
    const Disc &D = discs_[i];
    const double rho = std::sqrt(a * a + b * b) / cfg_.radius_m;
    double v = D.level;
    for (int o = 0; o < kOctaves; ++o) {
        const double inv_l = std::ldexp(1.0, o) / (kWave0 * cfg_.radius_m); /* 1 / wavelength */
        v += kAmp0 * std::ldexp(1.0, -o) *
             noise_(a * inv_l + D.off[0], b * inv_l + D.off[1], D.off[2] + 31.7 * o);
    }
    *albedo = (float)std::min(1.0, std::max(0.0, v));
    /* Opaque to 0.7 radii, then a smooth fade to transparent at the rim: no hard silhouette. */
    *alpha = (float)(1.0 - smooth01((rho - 0.7) / 0.3));
}

bool DiscScene::pick(const double C[3], const double d[3], size_t *idx, double X[3]) const
{
    double best = 1e300;
    bool hit = false;
    for (size_t i = 0; i < discs_.size(); ++i) {
        const Disc &D = discs_[i];
        const double den = dot3(D.n, d);
        if (std::fabs(den) < 1e-12) {
            continue;
        }
        const double rel[3] = {D.c[0] - C[0], D.c[1] - C[1], D.c[2] - C[2]};
        const double t = dot3(D.n, rel) / den;
        if (!(t > 0.0) || t >= best) {
            continue;
        }
        const double h[3] = {C[0] + t * d[0] - D.c[0], C[1] + t * d[1] - D.c[1],
                             C[2] + t * d[2] - D.c[2]};
        const double a = dot3(h, D.e1), b = dot3(h, D.e2);
        if (a * a + b * b >= cfg_.radius_m * cfg_.radius_m) {
            continue;
        }
        float alb, alpha;
        look(i, a, b, &alb, &alpha);
        if (alpha < 0.5f) {
            continue;
        }
        best = t;
        *idx = i;
        for (int q = 0; q < 3; ++q) {
            X[q] = C[q] + t * d[q];
        }
        hit = true;
    }
    return hit;
}

void DiscScene::render(const rp_rig_t &rig, int k, const double d[3], const double R[9],
                       const CamRays &rays, cv::Mat *out, const ObjView *ov) const
{
    const rp_rig_cam_t &rc = rig.cam[k];
    double C[3], M[9];
    cam_in_world(rig, k, d, R, C, M);
    /* World vector -> camera frame: M^T v. */
    auto to_cam = [&](const double v[3], double o[3]) {
        for (int j = 0; j < 3; ++j) {
            o[j] = M[j] * v[0] + M[3 + j] * v[1] + M[6 + j] * v[2];
        }
    };
    struct Vis {
        double z;
        size_t i;
        double p[3], n[3], e1[3], e2[3];
        int u0, u1, v0, v1;
    };
    std::vector<Vis> vis;
    const double Rd = cfg_.radius_m;
    for (size_t i = 0; i < discs_.size(); ++i) {
        const Disc &D = discs_[i];
        Vis s;
        const double rel[3] = {D.c[0] - C[0], D.c[1] - C[1], D.c[2] - C[2]};
        to_cam(rel, s.p);
        if (s.p[2] < 0.05 + Rd) {
            continue; /* behind the camera or closer than the simulation's visibility limit */
        }
        to_cam(D.n, s.n);
        to_cam(D.e1, s.e1);
        to_cam(D.e2, s.e2);
        /* Pixel bounding box from 16 rim points (and the centre), 2 px margin. */
        double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
        bool ok = true;
        for (int q = 0; q <= 16 && ok; ++q) {
            const double ph = 2.0 * M_PI * q / 16.0, rr = q == 16 ? 0.0 : Rd;
            rp_real P[3], uv[2];
            for (int a = 0; a < 3; ++a) {
                P[a] = (rp_real)(s.p[a] + rr * (std::cos(ph) * s.e1[a] + std::sin(ph) * s.e2[a]));
            }
            ok = rp_cam_project(&rc.cam, P, uv, NULL) == RP_OK;
            for (int a = 0; a < 2 && ok; ++a) {
                lo[a] = std::min(lo[a], (double)uv[a]);
                hi[a] = std::max(hi[a], (double)uv[a]);
            }
        }
        if (!ok || hi[0] < -2.0 || hi[1] < -2.0 || lo[0] > rays.w + 1.0 || lo[1] > rays.h + 1.0) {
            continue;
        }
        s.u0 = std::max(0, (int)std::floor(lo[0]) - 2);
        s.v0 = std::max(0, (int)std::floor(lo[1]) - 2);
        s.u1 = std::min(rays.w - 1, (int)std::ceil(hi[0]) + 2);
        s.v1 = std::min(rays.h - 1, (int)std::ceil(hi[1]) + 2);
        s.z = s.p[2];
        s.i = i;
        vis.push_back(s);
    }
    /* Back to front (the discs are small and far apart: centre depth orders them). */
    std::stable_sort(vis.begin(), vis.end(), [](const Vis &a, const Vis &b) { return a.z > b.z; });

    const int per_px = rays.ss * rays.ss;
    std::vector<float> buf((size_t)rays.w * rays.h * per_px, cfg_.background);
    for (const Vis &s : vis) {
        const double np = dot3(s.n, s.p);
        for (int v = s.v0; v <= s.v1; ++v) {
            for (int u = s.u0; u <= s.u1; ++u) {
                const size_t px = ((size_t)v * rays.w + u) * per_px;
                const float *r = &rays.ray[px * 3u];
                for (int q = 0; q < per_px; ++q, r += 3) {
                    if (r[2] == 0.0f) {
                        continue;
                    }
                    const double rd[3] = {r[0], r[1], r[2]};
                    const double den = dot3(s.n, rd);
                    if (std::fabs(den) < 1e-12) {
                        continue;
                    }
                    const double t = np / den;
                    if (!(t > 0.0)) {
                        continue;
                    }
                    const double h[3] = {t * rd[0] - s.p[0], t * rd[1] - s.p[1],
                                         t * rd[2] - s.p[2]};
                    const double a = dot3(h, s.e1), b = dot3(h, s.e2);
                    if (a * a + b * b >= Rd * Rd) {
                        continue;
                    }
                    float alb, alpha;
                    look(s.i, a, b, &alb, &alpha);
                    float &dst = buf[px + (size_t)q];
                    dst = alpha * alb + (1.0f - alpha) * dst;
                }
            }
        }
    }
    if (ov) { /* the moving object, in front of every disc (it stays inside the shell) */
        for (size_t px = 0; px < (size_t)rays.w * rays.h; ++px) {
            const float *r = &rays.ray[px * per_px * 3u];
            for (int q = 0; q < per_px; ++q, r += 3) {
                double t;
                if (r[2] != 0.0f && ov->hit_t(r, &t)) {
                    buf[px * per_px + (size_t)q] = ov->albedo_at(r, t);
                }
            }
        }
    }
    out->create(rays.h, rays.w, CV_32F);
    const float inv = 1.0f / (float)per_px;
    for (int v = 0; v < rays.h; ++v) {
        float *row = out->ptr<float>(v);
        for (int u = 0; u < rays.w; ++u) {
            const float *b = &buf[((size_t)v * rays.w + u) * per_px];
            float acc = 0.0f;
            for (int q = 0; q < per_px; ++q) {
                acc += b[q];
            }
            row[u] = acc * inv;
        }
    }
}

} /* namespace rpr */
