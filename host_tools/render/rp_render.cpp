/*
 * rp_render.cpp - the textured shell scene and the per-pixel ray caster (see rp_render.hpp).
 */
#include "rp_render.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "rigpose/rp_camera.h"
#include "rigpose/rp_rot.h"
#include "rp_noise.hpp"
#include "rp_sim.h"

namespace rpr {

namespace {

double smoothstep(double a, double b, double x)
{
    const double t = std::min(1.0, std::max(0.0, (x - a) / (b - a)));
    return t * t * (3.0 - 2.0 * t);
}

/* Stream domains of a scene seed. */
enum { DOM_ALBEDO = 1, DOM_RADIUS = 2, DOM_STAIN1 = 3, DOM_STAIN2 = 4 };

} /* namespace */

uint64_t key(uint64_t a, uint64_t b, uint64_t c, uint64_t d)
{
    uint64_t h = mix64(a + 0x9E3779B97F4A7C15ull);
    h = mix64(h ^ (b + 0x632BE59BD9B4E019ull));
    h = mix64(h ^ (c + 0x8CB92BA72F3D8DD7ull));
    return mix64(h ^ d);
}

/* ---- cube map ---------------------------------------------------------------------------- */

void CubeMap::init(int n, int pad)
{
    n_ = n;
    pad_ = pad;
    side_ = n + 2 * pad;
    v_.assign((size_t)6 * side_ * side_, 0.0f);
}

void CubeMap::texel_dir(int face, int i, int j, double u[3]) const
{
    const int m = face >> 1;
    const double sg = (face & 1) ? -1.0 : 1.0;
    u[m] = sg;
    u[(m + 1) % 3] = ((i - pad_) + 0.5) / n_ * 2.0 - 1.0;
    u[(m + 2) % 3] = ((j - pad_) + 0.5) / n_ * 2.0 - 1.0;
    const double s = 1.0 / std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    u[0] *= s;
    u[1] *= s;
    u[2] *= s;
}

template <class F> void CubeMap::fill(F f)
{
    const int rows = 6 * side_;
    cv::parallel_for_(cv::Range(0, rows), [&](const cv::Range &r) {
        for (int row = r.start; row < r.end; ++row) {
            const int face = row / side_, j = row % side_;
            float *dst = &v_[(size_t)row * side_];
            for (int i = 0; i < side_; ++i) {
                double u[3];
                texel_dir(face, i, j, u);
                dst[i] = (float)f(u);
            }
        }
    });
}

float CubeMap::at(const double u[3]) const
{
    const double ax = std::fabs(u[0]), ay = std::fabs(u[1]), az = std::fabs(u[2]);
    const int m = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
    const int face = 2 * m + (u[m] < 0.0);
    const double inv = 1.0 / std::fabs(u[m]);
    const double x = (u[(m + 1) % 3] * inv + 1.0) * 0.5 * n_ - 0.5 + pad_;
    const double y = (u[(m + 2) % 3] * inv + 1.0) * 0.5 * n_ - 0.5 + pad_;
    const int i = std::min(side_ - 2, std::max(0, (int)std::floor(x)));
    const int j = std::min(side_ - 2, std::max(0, (int)std::floor(y)));
    const float fx = (float)(x - i), fy = (float)(y - j);
    const float *p = &v_[((size_t)face * side_ + j) * side_ + i];
    const float top = p[0] + fx * (p[1] - p[0]);
    const float bot = p[side_] + fx * (p[side_ + 1] - p[side_]);
    return top + fy * (bot - top);
}

/* ---- scene ------------------------------------------------------------------------------- */

Scene::Scene(const SceneCfg &cfg) : cfg_(cfg)
{
    /* Radius: r_mid + r_amp tanh(0.9 z), z a unit-variance sum of six random plane waves over
     * the sphere of directions (wave numbers 1.5..3.5 per radian): a few broad bumps and dents. */
    struct Wave {
        double a[3], k, phi, w;
    } waves[6];
    Stream st{key(cfg.seed, DOM_RADIUS)};
    double w2 = 0.0;
    for (Wave &wv : waves) {
        const double z = 2.0 * st.next() - 1.0, ph = 2.0 * M_PI * st.next();
        const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
        wv.a[0] = rho * std::cos(ph);
        wv.a[1] = rho * std::sin(ph);
        wv.a[2] = z;
        wv.k = 1.5 + 2.0 * st.next();
        wv.phi = 2.0 * M_PI * st.next();
        wv.w = 0.5 + st.next();
        w2 += 0.5 * wv.w * wv.w;
    }
    const double norm = 1.0 / std::sqrt(w2);
    radius_.init(cfg.radius_face_px, 2);
    radius_.fill([&](const double u[3]) {
        double z = 0.0;
        for (const Wave &wv : waves) {
            z += wv.w * std::cos(wv.k * (wv.a[0] * u[0] + wv.a[1] * u[1] + wv.a[2] * u[2]) + wv.phi);
        }
        return cfg.r_mid + cfg.r_amp * std::tanh(0.9 * z * norm);
    });

    /* Albedo: fractal gradient noise (octaves 0.25 m .. 7.8 mm, amplitude ~ sqrt(wavelength))
     * plus soft-edged stains at 5 cm and 1.5 cm, evaluated at r_mid u (metres). */
    const GradNoise base(key(cfg.seed, DOM_ALBEDO)), stain1(key(cfg.seed, DOM_STAIN1)),
        stain2(key(cfg.seed, DOM_STAIN2));
    const int n_oct = 6;
    double amp_sum = 0.0;
    for (int o = 0; o < n_oct; ++o) {
        amp_sum += std::sqrt(std::ldexp(1.0, -o));
    }
    const double r0 = cfg.r_mid;
    albedo_.init(cfg.face_px, 2);
    albedo_.fill([&](const double u[3]) {
        double a = 0.2;
        if (!cfg.plain) {
            const double P[3] = {r0 * u[0], r0 * u[1], r0 * u[2]};
            double f = 0.0;
            for (int o = 0; o < n_oct; ++o) {
                const double inv_l = std::ldexp(1.0, o) / 0.25; /* 1 / wavelength, 1/m */
                const double off = 17.31 * o;
                f += std::sqrt(std::ldexp(1.0, -o)) *
                     base(P[0] * inv_l + off, P[1] * inv_l - off, P[2] * inv_l + 0.5 * off);
            }
            f *= 1.8 / amp_sum;
            const double s1 = smoothstep(0.08, 0.16, stain1(P[0] / 0.05, P[1] / 0.05, P[2] / 0.05));
            const double s2 =
                smoothstep(0.15, 0.22, stain2(P[0] / 0.015, P[1] / 0.015, P[2] / 0.015));
            a = 0.5 + 0.4 * f - 0.16 * s1 + 0.16 * s2;
            a = std::min(0.97, std::max(0.03, a));
        }
        for (const Marker &mk : cfg.markers) {
            const double n = std::sqrt(mk.u[0] * mk.u[0] + mk.u[1] * mk.u[1] + mk.u[2] * mk.u[2]);
            const double c = (u[0] * mk.u[0] + u[1] * mk.u[1] + u[2] * mk.u[2]) / n;
            const double ang = std::acos(std::min(1.0, std::max(-1.0, c)));
            if (ang < 6.0 * mk.sigma_rad) {
                a += mk.amp * std::exp(-0.5 * ang * ang / (mk.sigma_rad * mk.sigma_rad));
            }
        }
        return a;
    });
}

void Scene::surface_point(const double u[3], double M[3]) const
{
    const double n = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    const double r = radius(u) / n;
    M[0] = r * u[0];
    M[1] = r * u[1];
    M[2] = r * u[2];
}

bool Scene::intersect(const double C[3], const double d[3], double *t_out, double u_hit[3]) const
{
    const double b = C[0] * d[0] + C[1] * d[1] + C[2] * d[2];
    const double cc = C[0] * C[0] + C[1] * C[1] + C[2] * C[2];
    /* Distance along the ray to the sphere of radius r around the origin (C inside it). */
    auto sphere_t = [&](double r) {
        const double disc = b * b - (cc - r * r);
        return disc > 0.0 ? -b + std::sqrt(disc) : -1.0;
    };
    /* g(t) = |C + t d| - r(dir(C + t d)): negative inside the surface, zero on it. */
    auto g = [&](double t, double p[3]) {
        p[0] = C[0] + t * d[0];
        p[1] = C[1] + t * d[1];
        p[2] = C[2] + t * d[2];
        return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - radius(p);
    };
    if (cc > 0.0 && std::sqrt(cc) >= radius(C)) {
        return false; /* outside the surface */
    }
    double p[3];
    double t0 = sphere_t(cfg_.r_mid);
    if (t0 <= 0.0) {
        return false;
    }
    double g0 = g(t0, p);
    double t1 = sphere_t(radius(p));
    if (t1 <= 0.0) {
        return false;
    }
    double g1 = g(t1, p);
    for (int it = 0; it < 16 && std::fabs(g1) > 1e-9; ++it) {
        const double den = g1 - g0;
        double t2 = std::fabs(den) > 1e-15 ? t1 - g1 * (t1 - t0) / den : sphere_t(radius(p));
        if (!(t2 > 0.0) || !std::isfinite(t2)) {
            t2 = sphere_t(radius(p)); /* fixed-point step instead */
            if (t2 <= 0.0) {
                return false;
            }
        }
        t0 = t1;
        g0 = g1;
        t1 = t2;
        g1 = g(t1, p);
    }
    if (std::fabs(g1) > 1e-7) {
        return false;
    }
    const double n = 1.0 / std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    u_hit[0] = p[0] * n;
    u_hit[1] = p[1] * n;
    u_hit[2] = p[2] * n;
    *t_out = t1;
    return true;
}

/* ---- cameras ----------------------------------------------------------------------------- */

bool make_rays(const rp_camera_t &cam, int ss, CamRays *out)
{
    if (ss < 1 || ss > 8 || rp_cam_check(&cam) != RP_OK) {
        return false;
    }
    out->w = cam.width;
    out->h = cam.height;
    out->ss = ss;
    out->n_fail = 0;
    const size_t per_px = (size_t)ss * ss;
    out->ray.assign((size_t)out->w * out->h * per_px * 3u, 0.0f);
    for (int v = 0; v < out->h; ++v) {
        for (int u = 0; u < out->w; ++u) {
            float *r = &out->ray[((size_t)v * out->w + u) * per_px * 3u];
            for (int b = 0; b < ss; ++b) {
                for (int a = 0; a < ss; ++a, r += 3) {
                    const rp_real uv[2] = {(rp_real)(u - 0.5 + (a + 0.5) / ss),
                                           (rp_real)(v - 0.5 + (b + 0.5) / ss)};
                    rp_real xn[2];
                    if (rp_cam_unproject(&cam, uv, xn) != RP_OK) {
                        ++out->n_fail; /* stays (0, 0, 0): rendered black */
                        continue;
                    }
                    const double x = (double)xn[0], y = (double)xn[1];
                    const double s = 1.0 / std::sqrt(x * x + y * y + 1.0);
                    r[0] = (float)(x * s);
                    r[1] = (float)(y * s);
                    r[2] = (float)s;
                }
            }
        }
    }
    return true;
}

void cam_in_world(const rp_rig_t &rig, int k, const double d[3], const double R[9], double C[3],
                  double M[9])
{
    const rp_rig_cam_t &rc = rig.cam[k];
    for (int i = 0; i < 3; ++i) {
        C[i] = d[i];
        for (int j = 0; j < 3; ++j) {
            C[i] += R[3 * i + j] * (double)rc.D[j];
            M[3 * i + j] = 0.0;
            for (int l = 0; l < 3; ++l) {
                M[3 * i + j] += R[3 * i + l] * (double)rc.R[3 * l + j];
            }
        }
    }
}

/* ---- the moving object ------------------------------------------------------------------ */

bool ObjView::hit_t(const float r[3], double *t) const
{
    const double b = r[0] * c[0] + r[1] * c[1] + r[2] * c[2];
    const double cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    const double disc = b * b - (cc - radius * radius);
    if (!(disc >= 0.0)) {
        return false;
    }
    const double tt = b - std::sqrt(disc);
    if (!(tt > 0.0)) {
        return false;
    }
    *t = tt;
    return true;
}

float ObjView::albedo_at(const float r[3], double t) const
{
    const double X[3] = {t * r[0] - c[0], t * r[1] - c[1], t * r[2] - c[2]};
    double x[3]; /* Q^T X: the object's own frame */
    for (int i = 0; i < 3; ++i) {
        x[i] = Q[i] * X[0] + Q[3 + i] * X[1] + Q[6 + i] * X[2];
    }
    return obj->albedo(x);
}

namespace {

/* Rotation by angle a about unit axis u (Rodrigues), row-major. */
void axis_angle(const double u[3], double a, double R[9])
{
    const double c = std::cos(a), s = std::sin(a), v = 1.0 - c;
    R[0] = c + u[0] * u[0] * v;        R[1] = u[0] * u[1] * v - u[2] * s; R[2] = u[0] * u[2] * v + u[1] * s;
    R[3] = u[1] * u[0] * v + u[2] * s; R[4] = c + u[1] * u[1] * v;        R[5] = u[1] * u[2] * v - u[0] * s;
    R[6] = u[2] * u[0] * v - u[1] * s; R[7] = u[2] * u[1] * v + u[0] * s; R[8] = c + u[2] * u[2] * v;
}

void mul3(const double A[9], const double B[9], double C[9])
{
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
        }
    }
}

void random_unit(Stream &st, double u[3])
{
    const double z = 2.0 * st.next() - 1.0, ph = 2.0 * M_PI * st.next();
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    u[0] = rho * std::cos(ph);
    u[1] = rho * std::sin(ph);
    u[2] = z;
}

} /* namespace */

MovingObject::MovingObject(const ObjectCfg &cfg, const rp_camera_t &cam)
    : cfg_(cfg), base_(key(cfg.seed, DOM_ALBEDO)), stain1_(key(cfg.seed, DOM_STAIN1)),
      stain2_(key(cfg.seed, DOM_STAIN2))
{
    const double W = cam.width, H = cam.height, fx = (double)cam.fx, fy = (double)cam.fy;
    const double rho_px = std::sqrt(cfg.cover * W * H / M_PI); /* the disc's radius, px */
    const double a = rho_px / fx;
    radius_ = cfg.depth * a / std::sqrt(1.0 + a * a); /* its silhouette's half-angle is atan(a) */
    Stream st{key(cfg.seed, 0x0B1EC7)};
    amp_[0] = 0.6 * std::max(0.0, 0.5 * W - rho_px) * cfg.depth / fx;
    amp_[1] = 0.6 * std::max(0.0, 0.5 * H - rho_px) * cfg.depth / fy;
    w_[0] = 2.0 * M_PI / (3.0 + 2.0 * st.next());
    w_[1] = 2.0 * M_PI / (2.0 + 2.0 * st.next());
    ph_[0] = 2.0 * M_PI * st.next();
    ph_[1] = 2.0 * M_PI * st.next();
    random_unit(st, axis_);
    double u0[3];
    random_unit(st, u0);
    axis_angle(u0, 2.0 * M_PI * st.next(), Q0_);
    tex_scale_ = 0.8335 / cfg.depth; /* the scene's texture scale at the shell's mid radius */
}

void MovingObject::rel_pose(double t, double p[3], double Q[9]) const
{
    p[0] = amp_[0] * std::sin(w_[0] * t + ph_[0]);
    p[1] = amp_[1] * std::sin(w_[1] * t + ph_[1]);
    p[2] = cfg_.depth;
    double S[9];
    axis_angle(axis_, spin_ * t, S);
    mul3(S, Q0_, Q);
}

float MovingObject::albedo(const double x[3]) const
{
    /* The scene's albedo formula (Scene::Scene) at the scaled point, with the object's seeds. */
    const double P[3] = {tex_scale_ * x[0], tex_scale_ * x[1], tex_scale_ * x[2]};
    const int n_oct = 6;
    double amp_sum = 0.0, f = 0.0;
    for (int o = 0; o < n_oct; ++o) {
        amp_sum += std::sqrt(std::ldexp(1.0, -o));
        const double inv_l = std::ldexp(1.0, o) / 0.25;
        const double off = 17.31 * o;
        f += std::sqrt(std::ldexp(1.0, -o)) *
             base_(P[0] * inv_l + off, P[1] * inv_l - off, P[2] * inv_l + 0.5 * off);
    }
    f *= 1.8 / amp_sum;
    const double s1 = smoothstep(0.08, 0.16, stain1_(P[0] / 0.05, P[1] / 0.05, P[2] / 0.05));
    const double s2 = smoothstep(0.15, 0.22, stain2_(P[0] / 0.015, P[1] / 0.015, P[2] / 0.015));
    const double a = 0.5 + 0.4 * f - 0.16 * s1 + 0.16 * s2;
    return (float)std::min(0.97, std::max(0.03, a));
}

void render_albedo(const Scene &scene, const rp_rig_t &rig, int k, const double d[3],
                   const double R[9], const CamRays &rays, cv::Mat *out, const ObjView *ov)
{
    double C[3], M[9];
    cam_in_world(rig, k, d, R, C, M);
    out->create(rays.h, rays.w, CV_32F);
    const int per_px = rays.ss * rays.ss;
    const float inv = 1.0f / (float)per_px;
    cv::parallel_for_(cv::Range(0, rays.h), [&](const cv::Range &rr) {
        for (int v = rr.start; v < rr.end; ++v) {
            float *dst = out->ptr<float>(v);
            for (int u = 0; u < rays.w; ++u) {
                const float *r = &rays.ray[((size_t)v * rays.w + u) * per_px * 3u];
                float acc = 0.0f;
                for (int s = 0; s < per_px; ++s, r += 3) {
                    if (r[2] == 0.0f) {
                        continue;
                    }
                    double dw[3];
                    for (int i = 0; i < 3; ++i) {
                        dw[i] = M[3 * i] * r[0] + M[3 * i + 1] * r[1] + M[3 * i + 2] * r[2];
                    }
                    double t, uh[3], t_obj;
                    const bool hit = scene.intersect(C, dw, &t, uh);
                    if (ov && ov->hit_t(r, &t_obj) && (!hit || t_obj < t)) {
                        acc += ov->albedo_at(r, t_obj); /* the object, in front */
                    } else if (hit) {
                        acc += scene.albedo(uh);
                    }
                }
                dst[u] = acc * inv;
            }
        }
    });
}

void finish_image(const cv::Mat &albedo, const Effects &fx, cv::Mat *out8)
{
    cv::Mat img = albedo * (255.0 * fx.gain) + fx.offset;
    if (fx.blur_sigma > 0.0) {
        cv::GaussianBlur(img, img, cv::Size(0, 0), fx.blur_sigma, fx.blur_sigma,
                         cv::BORDER_REFLECT_101);
    }
    if (fx.noise_grey > 0.0) {
        cv::Mat noise(img.size(), CV_32F);
        cv::RNG rng(fx.noise_key | 1u);
        rng.fill(noise, cv::RNG::NORMAL, 0.0, fx.noise_grey);
        img += noise;
    }
    img.convertTo(*out8, CV_8U); /* rounds and saturates */
}

} /* namespace rpr */

/* ---- a rendered run ---------------------------------------------------------------------- */

namespace rpr {

Sequence::Sequence(const SeqCfg &cfg) : cfg_(cfg)
{
    std::memset(&rig_, 0, sizeof rig_);
    if (cfg.width < 32 || cfg.height < 32 || cfg.width > 4096 || cfg.height > 4096) {
        why_ = "image size out of range (32..4096)";
        return;
    }
    if (cfg.frames < 1 || cfg.ss < 1 || cfg.ss > 8 || cfg.face_px < 64 || cfg.face_px > 8192) {
        why_ = "frames >= 1, ss 1..8, face_px 64..8192";
        return;
    }
    if (cfg.motion < 0 || cfg.motion > 3) {
        why_ = "unknown motion";
        return;
    }
    if (cfg.moving_object &&
        (cfg.object_cam < 0 || cfg.object_cam >= RP_SIM_NCAMS ||
         !(cfg.object_cover > 0.0 && cfg.object_cover <= 0.6))) {
        why_ = "moving object: camera 0..5, cover in (0, 0.6]";
        return;
    }
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.motion = (rp_sim_motion_t)cfg.motion;
    sc.width = (uint16_t)cfg.width;
    sc.height = (uint16_t)cfg.height;
    sc.focal_px = cfg.focal_px > 0.0 ? cfg.focal_px : 800.0 * cfg.width / 640.0;
    sc.n_frames = cfg.frames;
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        sc.cam_offset_s[k] = cfg.cam_offset_s[k];
    }
    sc.jitter_s = cfg.jitter_s;
    if (!cfg.points) {
        sc.n_points = 0; /* the shell replaces the point cloud */
    } else if (!(cfg.disc_radius > 0.0 && cfg.disc_radius <= 0.05)) {
        why_ = "disc radius out of range (0..0.05 m)";
        return;
    }
    frame_dt_ = sc.frame_dt;
    rp_sim_run_t sr;
    const int st = rp_sim_run_init(&sr, &sc, cfg.seed, cfg.run);
    if (st != 0) {
        why_ = st == -2 ? "camera clocks need a continuous motion (turn, pitch, smooth), offsets "
                          "within 1 s, jitter 0..0.1 s"
                        : "out of memory";
        return;
    }
    if (sr.clocked && cfg.moving_object) {
        rp_sim_run_free(&sr);
        why_ = "the moving object is not simulated with camera clocks";
        return;
    }
    rig_ = sr.rig;
    truth_.assign(sr.truth, sr.truth + 6u * cfg.frames);
    truth_R_.assign(sr.truth_R, sr.truth_R + 9u * cfg.frames);
    if (sr.clocked) {
        cam_d_.assign(3u * RP_SIM_NCAMS * cfg.frames, 0.0);
        cam_R_.assign(9u * RP_SIM_NCAMS * cfg.frames, 0.0);
        for (uint32_t j = 0; j < cfg.frames; ++j) {
            for (int k = 0; k < RP_SIM_NCAMS; ++k) {
                rp_sim_cam_frame_t cf; /* every camera at the rig's rate: always present */
                rp_sim_cam_frame(&sr, j, k, &cf);
                const size_t i = (size_t)j * RP_SIM_NCAMS + (size_t)k;
                /* ignored: 0, the clocks were accepted with a continuous motion */
                (void)rp_sim_pose(&sr, cf.t_true, &cam_d_[3u * i], &cam_R_[9u * i]);
            }
        }
    }
    if (cfg.points) {
        cloud_.assign(sr.points, sr.points + 3u * sc.n_points);
    }
    rp_sim_run_free(&sr);
    for (int k = 0; k < rig_.n_cams; ++k) {
        rp_camera_t &c = rig_.cam[k].cam;
        c.k1 = (rp_real)cfg.dist[0];
        c.k2 = (rp_real)cfg.dist[1];
        c.p1 = (rp_real)cfg.dist[2];
        c.p2 = (rp_real)cfg.dist[3];
        c.k3 = (rp_real)cfg.dist[4];
    }
    if (rp_rig_check(&rig_) != RP_OK) {
        why_ = "bad camera parameters";
        return;
    }
    /* Cameras with equal intrinsics share one ray table. */
    rays_.resize(1);
    if (!make_rays(rig_.cam[0].cam, cfg.ss, &rays_[0])) {
        why_ = "bad camera parameters";
        return;
    }
    if (cfg.moving_object) {
        ObjectCfg oc;
        oc.seed = key(cfg.seed, cfg.run, 0x0B1EC7);
        oc.cam = cfg.object_cam;
        oc.cover = cfg.object_cover;
        object_.reset(new MovingObject(oc, rig_.cam[oc.cam].cam));
        obj_c_.assign(3u * cfg.frames, 0.0);
        obj_Q_.assign(9u * cfg.frames, 0.0);
        for (uint32_t j = 0; j < cfg.frames; ++j) {
            const Pose ps = pose(j);
            double C[3], M[9], p[3], Qr[9];
            cam_in_world(rig_, oc.cam, ps.d, ps.R, C, M);
            object_->rel_pose(j * frame_dt_, p, Qr);
            for (int i = 0; i < 3; ++i) {
                obj_c_[3u * j + i] = C[i] + M[3 * i] * p[0] + M[3 * i + 1] * p[1] + M[3 * i + 2] * p[2];
            }
            mul3(M, Qr, &obj_Q_[9u * j]);
        }
    }
    if (cfg.points) {
        DiscCfg dc;
        dc.radius_m = cfg.disc_radius;
        dc.seed = key(cfg.seed, cfg.run, 0xD15C);
        discs_.reset(new DiscScene(cloud_, dc));
        return;
    }
    SceneCfg scfg;
    scfg.seed = key(cfg.seed, cfg.run, 0x5CE4E);
    scfg.face_px = cfg.face_px;
    if (cfg.flat) {
        scfg.r_amp = 0.0;
    }
    scene_.reset(new Scene(scfg));
}

Pose Sequence::pose(uint32_t j) const
{
    Pose p;
    std::memcpy(p.d, &truth_[6u * j], sizeof p.d);
    std::memcpy(p.R, &truth_R_[9u * j], sizeof p.R);
    return p;
}

Pose Sequence::cam_pose(uint32_t j, int k) const
{
    if (cam_d_.empty()) {
        return pose(j);
    }
    Pose p;
    const size_t i = (size_t)j * RP_SIM_NCAMS + (size_t)k;
    std::memcpy(p.d, &cam_d_[3u * i], sizeof p.d);
    std::memcpy(p.R, &cam_R_[9u * i], sizeof p.R);
    return p;
}

int64_t Sequence::utime(uint32_t j) const { return (int64_t)std::llround(j * frame_dt_ * 1e6); }

void Sequence::render(uint32_t j, int k, cv::Mat *out8) const
{
    const Pose p = cam_pose(j, k);
    cv::Mat alb;
    ObjView ov;
    const ObjView *ovp = object_view(j, k, &ov) ? &ov : nullptr;
    if (discs_) {
        discs_->render(rig_, k, p.d, p.R, rays_[0], &alb, ovp);
    } else {
        render_albedo(*scene_, rig_, k, p.d, p.R, rays_[0], &alb, ovp);
    }
    Effects fx;
    fx.gain = 1.0 + cfg_.brightness * std::sin(2.0 * M_PI * j / 40.0 + k);
    fx.blur_sigma = cfg_.blur_sigma;
    fx.noise_grey = cfg_.noise_grey;
    fx.noise_key = key(cfg_.seed, cfg_.run, j, (uint64_t)k + 1u);
    finish_image(alb, fx, out8);
}

bool Sequence::object_view(uint32_t j, int k, ObjView *ov) const
{
    if (!object_ || j >= cfg_.frames || k < 0 || k >= rig_.n_cams) {
        return false;
    }
    const Pose p = cam_pose(j, k);
    double C[3], M[9];
    cam_in_world(rig_, k, p.d, p.R, C, M);
    const double *oc = &obj_c_[3u * j], *Q = &obj_Q_[9u * j];
    const double rel[3] = {oc[0] - C[0], oc[1] - C[1], oc[2] - C[2]};
    ov->obj = object_.get();
    ov->radius = object_->radius();
    for (int i = 0; i < 3; ++i) { /* c = M^T rel, Q_cam = M^T Q */
        ov->c[i] = M[i] * rel[0] + M[3 + i] * rel[1] + M[6 + i] * rel[2];
        for (int q = 0; q < 3; ++q) {
            ov->Q[3 * i + q] = M[i] * Q[q] + M[3 + i] * Q[3 + q] + M[6 + i] * Q[6 + q];
        }
    }
    return true;
}

bool Sequence::world_point_at(uint32_t j, int k, const rp_real uv[2], double X[3]) const
{
    if (j >= cfg_.frames || k < 0 || k >= rig_.n_cams) {
        return false;
    }
    rp_real xn[2];
    if (rp_cam_unproject(&rig_.cam[k].cam, uv, xn) != RP_OK) {
        return false;
    }
    /* The pixel's ray in the world: from the camera's centre C along M (xn, 1). */
    const Pose p = cam_pose(j, k);
    double C[3], M[9], dw[3];
    cam_in_world(rig_, k, p.d, p.R, C, M);
    for (int i = 0; i < 3; ++i) {
        dw[i] = M[3 * i] * (double)xn[0] + M[3 * i + 1] * (double)xn[1] + M[3 * i + 2];
    }
    if (discs_) {
        size_t idx;
        return discs_->pick(C, dw, &idx, X);
    }
    const double n = std::sqrt(dw[0] * dw[0] + dw[1] * dw[1] + dw[2] * dw[2]);
    const double du[3] = {dw[0] / n, dw[1] / n, dw[2] / n};
    double t, uh[3];
    if (!scene_->intersect(C, du, &t, uh)) {
        return false;
    }
    for (int i = 0; i < 3; ++i) {
        X[i] = C[i] + t * du[i];
    }
    return true;
}

std::vector<double> surface_points(const Scene &scene, int n, uint64_t seed_key)
{
    std::mt19937_64 rng(seed_key);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<double> pts;
    pts.reserve(3u * (size_t)(n > 0 ? n : 0));
    for (int i = 0; i < n; ++i) {
        double u[3] = {g(rng), g(rng), g(rng)}, M[3];
        if (u[0] == 0.0 && u[1] == 0.0 && u[2] == 0.0) {
            u[2] = 1.0;
        }
        scene.surface_point(u, M);
        pts.insert(pts.end(), M, M + 3);
    }
    return pts;
}

void surface_features(const Sequence &seq, const std::vector<double> &pts, int n_cams,
                      uint32_t j, double noise_px, uint64_t noise_key, rp_frameset_t *fs)
{
    const rp_rig_t &rig = seq.rig();
    rp_real tp[6];
    for (int c = 0; c < 6; ++c) {
        tp[c] = (rp_real)seq.truth(j)[c];
    }
    rp_pose_lin_t pl;
    rp_frameset_reset(fs, seq.utime(j));
    if (rp_pose_lin_set(&pl, tp) != RP_OK) {
        return;
    }
    for (int k = 0; k < n_cams && k < rig.n_cams; ++k) {
        const rp_camera_t &cam = rig.cam[k].cam;
        if (seq.clocked()) {
            /* the camera's own capture time (cam_pose), its angles as rp_sim's truth has them */
            const Pose cp = seq.cam_pose(j, k);
            rp_real Rr[9], abg[3], tk[6];
            for (int i = 0; i < 9; ++i) {
                Rr[i] = (rp_real)cp.R[i];
            }
            if (rp_rot_to_angles(Rr, abg) != RP_OK) {
                continue;
            }
            for (int i = 0; i < 3; ++i) {
                tk[i] = (rp_real)cp.d[i];
                tk[3 + i] = abg[i];
            }
            if (rp_pose_lin_set(&pl, tk) != RP_OK) {
                continue;
            }
        }
        std::mt19937_64 rng(key(noise_key, j, (uint64_t)k));
        std::normal_distribution<double> g(0.0, noise_px > 0.0 ? noise_px : 1.0);
        const double amp = noise_px > 0.0 ? 1.0 : 0.0;
        for (size_t i = 0; 3 * i + 2 < pts.size() && fs->n[k] < RP_MAX_FEATS_PER_CAM; ++i) {
            const rp_real M[3] = {(rp_real)pts[3 * i], (rp_real)pts[3 * i + 1],
                                  (rp_real)pts[3 * i + 2]};
            rp_real P[3], uv[2];
            if (rp_rig_cam_point(&rig, (uint8_t)k, &pl, M, P) != RP_OK || P[2] < (rp_real)0.05 ||
                rp_rig_project(&rig, (uint8_t)k, &pl, M, uv, nullptr, nullptr) != RP_OK ||
                !(uv[0] >= -0.5 && uv[0] < cam.width - 0.5 && uv[1] >= -0.5 &&
                  uv[1] < cam.height - 0.5)) {
                continue;
            }
            rp_feat_t &f = fs->f[k][fs->n[k]++];
            f.id = (uint32_t)i;
            f.uv[0] = uv[0] + (rp_real)(amp * g(rng));
            f.uv[1] = uv[1] + (rp_real)(amp * g(rng));
        }
    }
}

} /* namespace rpr */
