/*
 * test_render.cpp - rigpose-render's scene and ray caster (rp_render.hpp), run by `make test`:
 *  - determinism: the same (seed, run) renders the same bytes; another seed does not;
 *  - ray consistency: the surface point hit by a pixel centre's ray projects back (rp_rig_project,
 *    with distortion) onto that pixel centre, in all six cameras;
 *  - image content: a Gaussian spot painted on the surface renders with its centroid where
 *    rp_rig_project puts its centre, in all six cameras, with and without distortion;
 *  - the scene's radii span the simulation's shell (0.667..1 m);
 *  - the points scene: its discs sit on rp_sim's points of the run, it renders the same bytes
 *    for the same (seed, run), and a lone disc renders where rp_rig_project puts it: the pixel
 *    values equal the disc's albedo at the point its ray crosses (look), background outside.
 *  - the moving object: drawn exactly where its sphere meets the pixels' rays (shell and points
 *    scenes), covering 30 +- 3 % of the chosen camera, nothing in a camera that does not see it,
 *    nothing when off, the same bytes for the same seed.
 *  - camera clocks: with an offset on one camera, that camera's image is the synchronised
 *    sequence's camera rendered at the pose of set time + offset (rp_sim_pose), the others'
 *    images and every stamp and truth are unchanged.
 * Prints the measured figures; ends with "[  PASSED  ] N test(s)." and exit 0 when all pass.
 */
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/core.hpp>

#include "rigpose/rp_rig.h"
#include "rp_render.hpp"
#include "rp_sim.h"

static int n_pass = 0, n_fail = 0;

static void check(bool ok, const char *what)
{
    std::printf("%s %s\n", ok ? "[       OK ]" : "[  FAILED  ]", what);
    (ok ? n_pass : n_fail)++;
}

static rpr::SeqCfg small_cfg(uint64_t seed)
{
    rpr::SeqCfg c;
    c.width = 320;
    c.height = 240;
    c.frames = 3;
    c.seed = seed;
    c.face_px = 256; /* small texture: fast, enough for determinism */
    c.noise_grey = 1.0;
    c.blur_sigma = 0.5;
    c.brightness = 0.2;
    return c;
}

static void test_determinism()
{
    rpr::Sequence a(small_cfg(7)), b(small_cfg(7)), c(small_cfg(8));
    check(a.ok() && b.ok() && c.ok(), "sequences set up");
    bool same = true, differs = false, textured = true;
    for (int k = 0; k < 6; ++k) {
        cv::Mat ia, ib, ic;
        a.render(2, k, &ia);
        b.render(2, k, &ib);
        c.render(2, k, &ic);
        same = same && cv::norm(ia, ib, cv::NORM_INF) == 0.0;
        differs = differs || cv::norm(ia, ic, cv::NORM_INF) > 0.0;
        cv::Scalar mean, sd;
        cv::meanStdDev(ia, mean, sd);
        textured = textured && sd[0] > 15.0;
        if (k == 0) {
            std::printf("  cam0 frame 2: mean %.1f, std %.1f grey levels\n", mean[0], sd[0]);
        }
    }
    check(same, "same seed: identical images in all six cameras");
    check(differs, "other seed: different images");
    check(textured, "images are textured (std > 15 grey levels)");
}

/* Pixel centres -> ray -> surface hit -> rp_rig_project: back on the pixel centre. */
static void test_ray_consistency()
{
    rpr::SeqCfg cfg = small_cfg(3);
    cfg.face_px = 64;
    cfg.dist[0] = -0.25;
    cfg.dist[1] = 0.08;
    cfg.dist[2] = 1e-3;
    cfg.dist[3] = -5e-4;
    rpr::Sequence seq(cfg);
    check(seq.ok(), "distorted sequence set up");
    const rp_rig_t &rig = seq.rig();
    rpr::CamRays rays;
    check(rpr::make_rays(rig.cam[0].cam, 1, &rays) && rays.n_fail == 0, "rays of every pixel");
    double worst = 0.0;
    int n = 0, misses = 0;
    for (uint32_t j = 0; j < cfg.frames; ++j) {
        const rpr::Pose p = seq.pose(j);
        rp_pose_lin_t pl;
        rp_real pr[6];
        for (int i = 0; i < 6; ++i) {
            pr[i] = (rp_real)seq.truth(j)[i];
        }
        rp_pose_lin_set(&pl, pr);
        for (int k = 0; k < rig.n_cams; ++k) {
            const rp_rig_cam_t &rc = rig.cam[k];
            double C[3], M[9];
            for (int i = 0; i < 3; ++i) {
                C[i] = p.d[i];
                for (int l = 0; l < 3; ++l) {
                    C[i] += p.R[3 * i + l] * rc.D[l];
                }
                for (int c = 0; c < 3; ++c) {
                    M[3 * i + c] = 0.0;
                    for (int l = 0; l < 3; ++l) {
                        M[3 * i + c] += p.R[3 * i + l] * rc.R[3 * l + c];
                    }
                }
            }
            for (int v = 0; v < rays.h; v += 17) {
                for (int u = 0; u < rays.w; u += 23) {
                    const float *r = &rays.ray[((size_t)v * rays.w + u) * 3u];
                    double dw[3], t, uh[3];
                    for (int i = 0; i < 3; ++i) {
                        dw[i] = M[3 * i] * r[0] + M[3 * i + 1] * r[1] + M[3 * i + 2] * r[2];
                    }
                    if (!seq.scene().intersect(C, dw, &t, uh)) {
                        ++misses;
                        continue;
                    }
                    rp_real Mw[3], uv[2];
                    for (int i = 0; i < 3; ++i) {
                        Mw[i] = (rp_real)(C[i] + t * dw[i]);
                    }
                    if (rp_rig_project(&rig, (uint8_t)k, &pl, Mw, uv, NULL, NULL) != RP_OK) {
                        ++misses;
                        continue;
                    }
                    worst = std::max(worst, std::hypot((double)uv[0] - u, (double)uv[1] - v));
                    ++n;
                }
            }
        }
    }
    std::printf("  %d pixel centres (6 cameras, 3 frames, distortion k1 -0.25): worst "
                "reprojection %.2e px, %d misses\n", n, worst, misses);
    check(misses == 0 && n > 0, "every pixel's ray hits the surface");
    check(worst < 1e-4, "surface hits project back onto their pixel centres (< 1e-4 px)");
}

/* A painted spot's image centroid against rp_rig_project of its centre. */
static void test_marker(const double dist[5], const char *label)
{
    rpr::SeqCfg cfg = small_cfg(5);
    for (int i = 0; i < 5; ++i) {
        cfg.dist[i] = dist[i];
    }
    rpr::Sequence seq(cfg); /* for the rig and the trajectory */
    const rp_rig_t &rig = seq.rig();
    const uint32_t j = 2;
    const rpr::Pose p = seq.pose(j);
    rp_pose_lin_t pl;
    rp_real pr[6];
    for (int i = 0; i < 6; ++i) {
        pr[i] = (rp_real)seq.truth(j)[i];
    }
    rp_pose_lin_set(&pl, pr);

    /* One spot per camera, off the optical axis (so distortion matters): the direction from
     * the origin to a point 0.8 m along the camera's ray through normalised (0.25, -0.15). */
    rpr::SceneCfg sc;
    sc.plain = true;
    sc.face_px = 1024;
    sc.r_amp = 0.1665;
    sc.seed = 11;
    for (int k = 0; k < rig.n_cams; ++k) {
        const rp_rig_cam_t &rc = rig.cam[k];
        const double dc[3] = {0.25, -0.15, 1.0};
        rpr::Marker mk;
        for (int i = 0; i < 3; ++i) {
            double C = p.d[i], dw = 0.0;
            for (int l = 0; l < 3; ++l) {
                C += p.R[3 * i + l] * rc.D[l];
                double Ml = 0.0;
                for (int c = 0; c < 3; ++c) {
                    Ml += rc.R[3 * l + c] * dc[c];
                }
                dw += p.R[3 * i + l] * Ml;
            }
            mk.u[i] = C + 0.8 * dw;
        }
        mk.sigma_rad = 0.006;
        mk.amp = 0.6;
        sc.markers.push_back(mk);
    }
    rpr::Scene scene(sc);
    rpr::CamRays rays;
    rpr::make_rays(rig.cam[0].cam, 4, &rays);
    double worst = 0.0;
    bool all = true;
    for (int k = 0; k < rig.n_cams; ++k) {
        double M[3];
        scene.surface_point(sc.markers[k].u, M);
        const rp_real Mr[3] = {(rp_real)M[0], (rp_real)M[1], (rp_real)M[2]};
        rp_real uv[2];
        all = all && rp_rig_project(&rig, (uint8_t)k, &pl, Mr, uv, NULL, NULL) == RP_OK;
        cv::Mat img;
        rpr::render_albedo(scene, rig, k, p.d, p.R, rays, &img);
        const int u0 = (int)std::lround((double)uv[0]), v0 = (int)std::lround((double)uv[1]);
        double sw = 0.0, su = 0.0, sv = 0.0;
        for (int v = v0 - 14; v <= v0 + 14; ++v) {
            for (int u = u0 - 14; u <= u0 + 14; ++u) {
                if (u < 0 || v < 0 || u >= img.cols || v >= img.rows) {
                    all = false;
                    continue;
                }
                const double w = std::max(0.0, (double)img.at<float>(v, u) - 0.2);
                sw += w;
                su += w * u;
                sv += w * v;
            }
        }
        const double e = sw > 0.0 ? std::hypot(su / sw - (double)uv[0], sv / sw - (double)uv[1])
                                   : 1e9;
        worst = std::max(worst, e);
    }
    std::printf("  spots, %s: worst centroid - projection %.4f px (6 cameras, 320x240)\n", label,
                worst);
    check(all && worst < 0.05, "rendered spots land where rp_camera projects them (< 0.05 px)");
}

static void test_depths()
{
    rpr::SceneCfg sc;
    sc.face_px = 64;
    sc.seed = 2;
    rpr::Scene scene(sc);
    double lo = 1e9, hi = 0.0;
    for (int i = 0; i < 20000; ++i) { /* a Fibonacci sphere of directions */
        const double z = 1.0 - (i + 0.5) / 10000.0, ph = i * 2.399963229728653;
        const double rho = std::sqrt(1.0 - z * z);
        const double u[3] = {rho * std::cos(ph), rho * std::sin(ph), z};
        const double r = scene.radius(u);
        lo = std::min(lo, r);
        hi = std::max(hi, r);
    }
    std::printf("  shell radii %.3f..%.3f m (simulation: 0.667..1)\n", lo, hi);
    check(lo >= 0.667 - 1e-6 && hi <= 1.0 + 1e-6 && hi - lo > 0.15,
          "surface radii inside the simulation's shell, spanning it");
}

static void test_points_scene()
{
    rpr::SeqCfg c = small_cfg(5);
    c.points = true;
    c.run = 2;
    rpr::Sequence a(c), b(c);
    check(a.ok() && b.ok() && a.points(), "points sequences set up");
    /* The disc centres are rp_sim's points of the same run. */
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.width = 320;
    sc.height = 240;
    sc.focal_px = 400.0;
    sc.n_frames = c.frames;
    rp_sim_run_t sr;
    bool same_pts = rp_sim_run_init(&sr, &sc, c.seed, c.run) == 0 &&
                    a.point_cloud().size() == 3u * sc.n_points;
    for (size_t i = 0; same_pts && i < 3u * sc.n_points; ++i) {
        same_pts = a.point_cloud()[i] == sr.points[i];
    }
    rp_sim_run_free(&sr);
    check(same_pts, "points scene: the discs sit on rp_sim's 10,000 points of the run");
    bool same = true, textured = true;
    for (int k = 0; k < 6; ++k) {
        cv::Mat ia, ib;
        a.render(1, k, &ia);
        b.render(1, k, &ib);
        same = same && cv::norm(ia, ib, cv::NORM_INF) == 0.0;
        cv::Scalar mean, sd;
        cv::meanStdDev(ia, mean, sd);
        textured = textured && sd[0] > 15.0;
    }
    check(same && textured, "points scene: same (seed, run) renders the same bytes, textured");

    /* One disc 0.8 m in front of camera 0 (rig at the origin), off the axis, with distortion. */
    rp_rig_t rig = a.rig();
    rp_camera_t &cam = rig.cam[0].cam;
    cam.k1 = (rp_real)-0.2;
    cam.k2 = (rp_real)0.05;
    const double centre[3] = {0.12, -0.07, 0.8};
    rpr::DiscCfg dc;
    dc.seed = 3;
    rpr::DiscScene one(std::vector<double>(centre, centre + 3), dc);
    rpr::CamRays rays;
    const bool rays_ok = rpr::make_rays(cam, 1, &rays);
    const double d0[3] = {0, 0, 0}, I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    cv::Mat img;
    one.render(rig, 0, d0, I, rays, &img);
    /* Expected value of every pixel: alpha * albedo + (1 - alpha) * background, with look() at
     * the point where the pixel's ray crosses the disc's plane; the background off the disc. */
    const double *c0 = one.centre(0);
    double n[3], e1[3], e2[3];
    one.axes(0, n, e1, e2);
    double worst = 0.0;
    int on_disc = 0;
    for (int v = 0; v < img.rows; ++v) {
        for (int u = 0; u < img.cols; ++u) {
            const float *r = &rays.ray[((size_t)v * img.cols + u) * 3u];
            const double den = n[0] * r[0] + n[1] * r[1] + n[2] * r[2];
            const double t = (n[0] * c0[0] + n[1] * c0[1] + n[2] * c0[2]) / den;
            const double h[3] = {t * r[0] - c0[0], t * r[1] - c0[1], t * r[2] - c0[2]};
            const double da = h[0] * e1[0] + h[1] * e1[1] + h[2] * e1[2];
            const double db = h[0] * e2[0] + h[1] * e2[1] + h[2] * e2[2];
            double expect = dc.background;
            if (da * da + db * db < dc.radius_m * dc.radius_m) {
                float alb, alpha;
                one.look(0, da, db, &alb, &alpha);
                expect = alpha * alb + (1.0 - alpha) * dc.background;
                ++on_disc;
            }
            worst = std::max(worst, std::fabs((double)img.at<float>(v, u) - expect));
        }
    }
    /* The disc's footprint: pixels that differ from the background, their centroid against
     * rp_rig_project of the centre. */
    rp_real P[3] = {(rp_real)centre[0], (rp_real)centre[1], (rp_real)centre[2]}, uv[2];
    const bool proj = rp_cam_project(&cam, P, uv, NULL) == RP_OK;
    int changed = 0;
    double su = 0.0, sv = 0.0;
    for (int v = 0; v < img.rows; ++v) {
        for (int u = 0; u < img.cols; ++u) {
            if (img.at<float>(v, u) != dc.background) {
                ++changed;
                su += u;
                sv += v;
            }
        }
    }
    const double cu = changed ? su / changed : -1e9, cv_ = changed ? sv / changed : -1e9;
    std::printf("  lone disc: %d px inside its rim, %d px not background, worst |value - "
                "expected| %.2g; footprint centre off the "
                "projection by %.3f px (k1 -0.2)\n",
                on_disc, changed, worst, std::hypot(cu - (double)uv[0], cv_ - (double)uv[1]));
    check(rays_ok && proj && on_disc > 50 && changed > 0 && changed <= on_disc && worst < 1e-5 &&
              std::hypot(cu - (double)uv[0], cv_ - (double)uv[1]) < 1.0,
          "lone disc: every pixel is the disc's look() where its ray crosses it, background "
          "elsewhere; footprint centred on the projection (< 1 px)");
}

/* The moving object (--moving-object): drawn exactly where its sphere meets the pixels' rays,
 * covering about 30 % of the chosen camera, nothing elsewhere or when off; deterministic. */
static void object_frame(const rpr::Sequence &with, const rpr::Sequence &without, uint32_t j,
                         int k, double *cover, bool *subset, double *drawn_share)
{
    cv::Mat a, b;
    with.render(j, k, &a);
    without.render(j, k, &b);
    rpr::ObjView ov;
    const bool has = with.object_view(j, k, &ov);
    rpr::CamRays rays;
    rpr::make_rays(with.rig().cam[k].cam, 1, &rays); /* ss 1: a pixel is its centre's ray */
    long hit = 0, diff = 0, diff_outside = 0;
    for (int v = 0; v < rays.h; ++v) {
        for (int u = 0; u < rays.w; ++u) {
            const float *r = &rays.ray[((size_t)v * rays.w + u) * 3u];
            double t;
            const bool h = has && r[2] != 0.0f && ov.hit_t(r, &t);
            const bool d = a.at<uint8_t>(v, u) != b.at<uint8_t>(v, u);
            hit += h;
            diff += d && h;
            diff_outside += d && !h;
        }
    }
    *cover = (double)hit / ((double)rays.w * rays.h);
    *subset = diff_outside == 0;
    *drawn_share = hit ? (double)diff / hit : 1.0;
}

static void test_moving_object()
{
    rpr::SeqCfg c = small_cfg(5);
    c.ss = 1;
    c.blur_sigma = 0.0; /* a blur would spread the object by a pixel */
    c.frames = 30;
    rpr::SeqCfg co = c;
    co.moving_object = true;
    rpr::Sequence without(c), with(co), with2(co);
    check(without.ok() && with.ok() && with2.ok() && with.object(), "moving object set up");
    rpr::ObjView ov;
    check(!without.object_view(0, 0, &ov), "no object unless asked");
    double lo = 1.0, hi = 0.0, share_lo = 1.0;
    bool subset = true, same = true, others_same = true;
    for (uint32_t j = 0; j < c.frames; j += 7) {
        double cover, share;
        bool sub;
        object_frame(with, without, j, 0, &cover, &sub, &share);
        lo = std::min(lo, cover);
        hi = std::max(hi, cover);
        share_lo = std::min(share_lo, share);
        subset = subset && sub;
        cv::Mat x, y;
        with.render(j, 0, &x);
        with2.render(j, 0, &y);
        same = same && cv::norm(x, y, cv::NORM_INF) == 0.0;
        /* cam3 (back, rig index 2) never sees it: its images are the scene's bytes */
        with.render(j, 2, &x);
        without.render(j, 2, &y);
        others_same = others_same && cv::norm(x, y, cv::NORM_INF) == 0.0;
    }
    std::printf("  moving object in cam1: covers %.3f..%.3f of the image; %.1f %% of the covered "
                "pixels differ from the static render (the rest by chance equal)\n",
                lo, hi, 100.0 * share_lo);
    check(lo > 0.27 && hi < 0.33, "moving object covers 30 +- 3 % of cam1");
    check(subset && share_lo > 0.9,
          "moving object: drawn only where its sphere meets the pixels' rays, and there");
    check(same, "moving object: same seed, same bytes");
    check(others_same, "moving object: a camera that does not see it renders the static scene");

    /* Another camera, cam2 (rig index 1); and the points scene. */
    co.object_cam = 1;
    rpr::SeqCfg cp = c, cpo = co;
    cp.points = cpo.points = true;
    cp.frames = cpo.frames = 2;
    rpr::Sequence with1(co), pts(cp), pts_obj(cpo);
    double cover1, share1, cover_p, share_p;
    bool sub1, sub_p;
    object_frame(with1, without, 5, 1, &cover1, &sub1, &share1);
    object_frame(pts_obj, pts, 1, 1, &cover_p, &sub_p, &share_p);
    std::printf("  moving object in cam2: covers %.3f (shell), %.3f (points scene)\n", cover1,
                cover_p);
    check(cover1 > 0.27 && cover1 < 0.33 && sub1 && share1 > 0.9 && cover_p > 0.27 &&
              cover_p < 0.33 && sub_p && share_p > 0.9,
          "moving object in cam2, shell and points scenes: 30 +- 3 %, drawn where it is");
}

static bool same_pose(const rpr::Pose &a, const double d[3], const double R[9])
{
    bool same = true;
    for (int i = 0; i < 3; ++i) {
        same = same && a.d[i] == d[i];
    }
    for (int i = 0; i < 9; ++i) {
        same = same && a.R[i] == R[i];
    }
    return same;
}

static void test_camera_clocks()
{
    rpr::SeqCfg c = small_cfg(5);
    c.motion = RP_SIM_MOTION_SMOOTH;
    c.frames = 4;
    rpr::SeqCfg co = c;
    co.cam_offset_s[1] = 0.040; /* cam2 (rig camera 1) 40 ms late */
    rpr::Sequence sync(c), off(co);
    check(sync.ok() && off.ok(), "smooth sequences with and without an offset set up");
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.motion = RP_SIM_MOTION_SMOOTH;
    sc.n_frames = c.frames;
    rp_sim_run_t sr;
    check(rp_sim_run_init(&sr, &sc, c.seed, c.run) == 0, "the run set up");
    const uint32_t j = 3;
    double d[3], R[9];
    rp_sim_pose(&sr, rp_sim_set_time(&sr, j) + 0.040, d, R);
    const bool at_own_time = same_pose(off.cam_pose(j, 1), d, R);
    rp_sim_pose(&sr, rp_sim_set_time(&sr, j), d, R);
    const bool others_at_set_time = same_pose(off.cam_pose(j, 0), d, R) &&
                                    same_pose(off.pose(j), d, R) &&
                                    same_pose(sync.cam_pose(j, 1), d, R);
    rp_sim_run_free(&sr);
    check(at_own_time && others_at_set_time && off.utime(j) == sync.utime(j),
          "offset camera posed at set time + 40 ms, the others and the stamps at the set's");
    cv::Mat a0, b0, a1, b1;
    sync.render(j, 0, &a0);
    off.render(j, 0, &b0);
    sync.render(j, 1, &a1);
    off.render(j, 1, &b1);
    const double moved = cv::norm(a1, b1, cv::NORM_L1) / (double)a1.total();
    std::printf("  camera clocks: cam2 40 ms late changes its image by %.2f grey levels per "
                "pixel on average\n", moved);
    check(cv::norm(a0, b0, cv::NORM_INF) == 0.0 && moved > 1.0,
          "only the offset camera's image changes");
    rpr::SeqCfg cp = co;
    cp.motion = RP_SIM_MOTION_PAPER;
    check(!rpr::Sequence(cp).ok(), "offsets with the paper's motion are refused");
}

int main()
{
    test_determinism();
    test_ray_consistency();
    const double none[5] = {0, 0, 0, 0, 0}, barrel[5] = {-0.25, 0.08, 1e-3, -5e-4, 0};
    test_marker(none, "pinhole");
    test_marker(barrel, "k1 -0.25 k2 0.08 p1 1e-3 p2 -5e-4");
    test_depths();
    test_points_scene();
    test_moving_object();
    test_camera_clocks();
    if (n_fail == 0) {
        std::printf("[  PASSED  ] %d test(s).\n", n_pass);
        return 0;
    }
    std::printf("[  FAILED  ] %d test(s), %d passed.\n", n_fail, n_pass);
    return 1;
}
