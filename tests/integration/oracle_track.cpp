/*
 * oracle_track.cpp - rigpose's tracker (rp_track.h) against OpenCV on the same images:
 * cv::goodFeaturesToTrack (blockSize 3, min eigenvalue) and cv::calcOpticalFlowPyrLK with the
 * same window (21x21), levels (maxLevel 3), 30 iterations, eps 0.01 px, minEigThreshold 1e-4.
 *
 * Scenes: a smooth random texture (seeded), warped by cv::warpAffine with a small rotation about
 * the centre plus a translation. Both trackers start from rigpose's detected corners; the check is
 * the mean distance between their tracked positions (< 0.1 px), each one's error against the
 * known warp, and the overlap of the two detectors. Ends with "oracle_track: N passed, M failed"
 * and exit status 0 when M is 0.
 */
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "rigpose/rp_track.h"
#include "../../host_tools/common/rp_cv.hpp"

static int n_pass = 0, n_fail = 0;

static void check(bool ok, const char *what)
{
    std::printf("%s %s\n", ok ? "[       OK ]" : "[  FAILED  ]", what);
    (ok ? n_pass : n_fail)++;
}

static cv::Mat texture(int w, int h, uint64_t seed)
{
    cv::RNG rng(seed);
    cv::Mat noise(h, w, CV_32F), out;
    rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
    cv::Mat fine, coarse;
    cv::GaussianBlur(noise, fine, cv::Size(0, 0), 1.5);
    cv::GaussianBlur(noise, coarse, cv::Size(0, 0), 5.0);
    cv::Mat t = fine + 2.0 * coarse;
    cv::normalize(t, t, 10, 245, cv::NORM_MINMAX);
    t.convertTo(out, CV_8U);
    return out;
}


static rp_tracker_t trk;
static rp_feat_t f0[RP_MAX_FEATS_PER_CAM], f1[RP_MAX_FEATS_PER_CAM];

static void run_scene(int w, int h, uint64_t seed, double deg, double tx, double ty)
{
    char what[256];
    const cv::Mat a = texture(w, h, seed);
    const cv::Mat M = cv::getRotationMatrix2D(cv::Point2f((float)(w - 1) / 2, (float)(h - 1) / 2),
                                              deg, 1.0);
    cv::Mat Mt = M.clone();
    Mt.at<double>(0, 2) += tx;
    Mt.at<double>(1, 2) += ty;
    cv::Mat b;
    cv::warpAffine(a, b, Mt, a.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);

    rp_track_cfg_t cfg;
    rp_track_default_cfg(&cfg);
    rp_track_init(&trk, &cfg);
    uint16_t n0 = 0, n1 = 0;
    rp_track_info_t info;
    rp_image_t va = rp_cv_view(a), vb = rp_cv_view(b);
    const auto t0 = std::chrono::steady_clock::now();
    const rp_status_t s0 = rp_track_process(&trk, &va, 0, f0, RP_MAX_FEATS_PER_CAM, &n0, &info);
    const auto t1 = std::chrono::steady_clock::now();
    const rp_status_t s1 = rp_track_process(&trk, &vb, 1, f1, RP_MAX_FEATS_PER_CAM, &n1, &info);
    const auto t2 = std::chrono::steady_clock::now();
    std::snprintf(what, sizeof what, "%dx%d: rigpose detect + track run (%d, %d features)", w, h,
                  n0, n1);
    check(s0 == RP_OK && s1 == RP_OK && n0 >= 100, what);

    /* OpenCV's detector on the same image */
    std::vector<cv::Point2f> cvc;
    const auto c0 = std::chrono::steady_clock::now();
    cv::goodFeaturesToTrack(a, cvc, cfg.target, 0.01, cfg.min_dist, cv::noArray(), 3, false);
    const auto c1 = std::chrono::steady_clock::now();
    int near = 0;
    for (int i = 0; i < n0; ++i) {
        for (const auto &p : cvc) {
            if (std::hypot(p.x - f0[i].uv[0], p.y - f0[i].uv[1]) <= 1.5) {
                ++near;
                break;
            }
        }
    }
    /* OpenCV's LK from rigpose's corners */
    std::vector<cv::Point2f> p0, p1;
    for (int i = 0; i < n0; ++i) {
        p0.push_back(cv::Point2f((float)f0[i].uv[0], (float)f0[i].uv[1]));
    }
    std::vector<uchar> st;
    std::vector<float> err;
    const auto c2 = std::chrono::steady_clock::now();
    cv::calcOpticalFlowPyrLK(a, b, p0, p1, st, err, cv::Size(cfg.win, cfg.win), cfg.levels - 1,
                             cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30,
                                              0.01),
                             0, 1e-4);
    const auto c3 = std::chrono::steady_clock::now();
    double sum_d = 0, max_d = 0, sum_rp = 0, sum_cv = 0;
    int m = 0;
    const double margin = 25;
    for (int i = 0; i < n0; ++i) {
        if (!st[i]) {
            continue;
        }
        const rp_feat_t *g = nullptr;
        for (int j = 0; j < n1; ++j) {
            if (f1[j].id == f0[i].id) {
                g = &f1[j];
                break;
            }
        }
        const double u = f0[i].uv[0], v = f0[i].uv[1];
        if (g == nullptr || u < margin || v < margin || u > w - 1 - margin || v > h - 1 - margin) {
            continue;
        }
        const double tu = Mt.at<double>(0, 0) * u + Mt.at<double>(0, 1) * v + Mt.at<double>(0, 2);
        const double tv = Mt.at<double>(1, 0) * u + Mt.at<double>(1, 1) * v + Mt.at<double>(1, 2);
        const double d = std::hypot(g->uv[0] - p1[i].x, g->uv[1] - p1[i].y);
        sum_d += d;
        max_d = d > max_d ? d : max_d;
        sum_rp += std::hypot(g->uv[0] - tu, g->uv[1] - tv);
        sum_cv += std::hypot(p1[i].x - tu, p1[i].y - tv);
        ++m;
    }
    const auto us = [](std::chrono::steady_clock::duration d) {
        return (double)std::chrono::duration_cast<std::chrono::microseconds>(d).count();
    };
    std::printf("%dx%d rot %.2f deg shift (%.2f, %.2f): %d common interior tracks; "
                "rigpose vs OpenCV mean %.4f px max %.4f px; error vs truth: rigpose %.4f px, "
                "OpenCV %.4f px\n",
                w, h, deg, tx, ty, m, sum_d / m, max_d, sum_rp / m, sum_cv / m);
    std::printf("  detection: %d of %d rigpose corners within 1.5 px of OpenCV's %zu; time: "
                "rigpose detect %.0f us, track %.0f us (fwd+bwd, top-up); OpenCV gftt %.0f us, "
                "LK %.0f us (fwd only)\n",
                near, n0, cvc.size(), us(t1 - t0), us(t2 - t1), us(c1 - c0), us(c3 - c2));
    std::snprintf(what, sizeof what, "%dx%d: mean tracking difference to OpenCV < 0.1 px", w, h);
    check(m >= 50 && sum_d / m < 0.1, what);
    std::snprintf(what, sizeof what, "%dx%d: rigpose error vs truth < 0.1 px", w, h);
    check(m >= 50 && sum_rp / m < 0.1, what);
}

int main()
{
    cv::setNumThreads(1);
    run_scene(320, 240, 1, 1.0, 2.3, -1.7);
    run_scene(640, 480, 2, -1.5, -4.6, 3.1);
    run_scene(640, 480, 3, 0.5, 8.2, 6.4);
    if (n_fail == 0) {
        std::printf("[  PASSED  ] %d test(s).\n", n_pass);
    } else {
        std::printf("[  FAILED  ] %d test(s)\n", n_fail);
    }
    std::printf("oracle_track: %d passed, %d failed\n", n_pass, n_fail);
    return n_fail == 0 ? 0 : 1;
}
