/*
 * bench_track.cpp - rigpose's tracker (rp_track) against OpenCV's goodFeaturesToTrack +
 * calcOpticalFlowPyrLK (cv::setNumThreads(1)) on the same rendered frames, in one run.
 *
 * Frames: bt_scene (the paper's four single cameras in a textured box room on the simulated
 * trajectory), 320x240 and 640x480, rendered before timing. Both trackers do the same job per
 * camera and frame: track the previous frame's features (21x21 window, 4 levels, 30 iterations,
 * eps 0.01 px, min eigenvalue 1e-4), drop tracks failing a 1 px forward-backward check, and top up
 * to 150 features when fewer than 120 remain (minimum distance 10 px, quality 0.01; OpenCV with a
 * mask around the kept features, as its lk_track sample). OpenCV runs twice: with images (it
 * builds both pyramids in every call) and with pyramids built once per frame by
 * buildOpticalFlowPyramid (with derivatives) and shared by both directions; the ratio figures
 * are against the faster of the two. The three run interleaved, camera by camera; the time of
 * each (frame, camera) is its minimum over repetitions (the work is deterministic), summed over
 * frames 1..N-1 (frame 0, the first detection, is reported apart). Accuracy: "err", the mean
 * distance of every track to the true position of its first pixel (bt_scene_transfer), over all
 * frames (grows with track age), and "step", the mean distance of every track to where the truth
 * carries its previous position (one frame of tracking).
 *
 *   rigpose-bench-track [--frames N] [--reps R] [--seed S] [--out file.json]
 */
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "bt_scene.h"
#include "rigpose/rp_track.h"
#include "../../common/rp_cv.hpp"

namespace {

using clk = std::chrono::steady_clock;

double us_since(clk::time_point t0)
{
    return std::chrono::duration<double, std::micro>(clk::now() - t0).count();
}

/* A track as the accuracy check sees it: where and when it was born. */
struct birth {
    int frame;
    double uv[2];
    int last_frame;     /* where the track was in the frame before (step accuracy) */
    double last_uv[2];
};

/* Accuracy and cost of one tracker over one sequence. */
struct result {
    double us_frames = 0; /* total over frames 1..N-1 */
    double us_first = 0;  /* frame 0 (first detection) */
    double err_sum = 0;       /* distance to truth, px, summed over track-frames */
    long err_n = 0;
    double step_sum = 0;      /* frame-to-frame error, px: distance to where the truth carries
                               * the track's previous position */
    long step_n = 0;
    long feats = 0;           /* features output, summed over frames and cameras */
};

struct seq {
    int w, h, n;
    bt_scene_t *sc;
    std::vector<cv::Mat> img; /* [frame * 4 + cam] */
};

/* Errors of a track at frame j: against the truth of its birth pixel, and of its last step. */
void score(const seq &s, int cam, int j, birth &b, double u, double v, result &r)
{
    double t[2];
    if (b.frame != j && bt_scene_transfer(s.sc, cam, b.frame, b.uv, j, t)) {
        r.err_sum += std::hypot(u - t[0], v - t[1]);
        r.err_n++;
    }
    if (j > 0 && b.last_frame == j - 1 && bt_scene_transfer(s.sc, cam, j - 1, b.last_uv, j, t)) {
        r.step_sum += std::hypot(u - t[0], v - t[1]);
        r.step_n++;
    }
    b.last_frame = j;
    b.last_uv[0] = u;
    b.last_uv[1] = v;
}


/* rigpose's side: one rp_tracker_t per camera. */
struct rp_side {
    rp_tracker_t trk[BT_NCAMS];
    rp_feat_t out[RP_MAX_FEATS_PER_CAM];
    std::vector<birth> born[BT_NCAMS];

    void init()
    {
        rp_track_cfg_t cfg;
        rp_track_default_cfg(&cfg);
        for (int k = 0; k < BT_NCAMS; ++k) {
            cfg.cam = (uint8_t)k;
            rp_track_init(&trk[k], &cfg);
            born[k].clear();
        }
    }

    double step(const seq &s, int j, int k, result *r)
    {
        const rp_image_t im = rp_cv_view(s.img[(size_t)j * BT_NCAMS + k]);
        uint16_t n = 0;
        const auto t0 = clk::now();
        rp_track_process(&trk[k], &im, (int64_t)j * 33333, out, RP_MAX_FEATS_PER_CAM, &n,
                         nullptr);
        const double dt = us_since(t0);
        if (r != nullptr) {
            r->feats += n;
            for (int i = 0; i < n; ++i) {
                const uint32_t idx = rp_track_id_serial(out[i].id);
                if (idx >= born[k].size()) {
                    born[k].resize(idx + 1, birth{-1, {0, 0}, -9, {0, 0}});
                }
                birth &b = born[k][idx];
                if (b.frame < 0) {
                    b.frame = j;
                    b.uv[0] = out[i].uv[0];
                    b.uv[1] = out[i].uv[1];
                }
                score(s, k, j, b, out[i].uv[0], out[i].uv[1], *r);
            }
        }
        return dt;
    }
};

/* OpenCV's side, same job (see the top of the file); pyramids: built once per frame. */
struct cv_side {
    bool pyramids = false;
    struct cam {
        std::vector<cv::Point2f> pts;
        std::vector<birth> born;
        cv::Mat prev;
        std::vector<cv::Mat> prev_pyr;
    } cc[BT_NCAMS];
    std::vector<cv::Point2f> nxt, back, fresh;
    std::vector<uchar> st, st2;
    std::vector<float> err;

    void init()
    {
        for (auto &c : cc) {
            c = cam();
        }
    }

    double step(const seq &s, int j, int k, result *r)
    {
        const cv::Size win(21, 21);
        const int max_level = 3, target = 150, topup_below = 120;
        const double min_dist = 10, quality = 0.01;
        const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
        cam &c = cc[k];
        const cv::Mat &img = s.img[(size_t)j * BT_NCAMS + k];
        const auto t0 = clk::now();
        std::vector<cv::Mat> pyr;
        if (pyramids) {
            cv::buildOpticalFlowPyramid(img, pyr, win, max_level, true);
        }
        if (j > 0 && !c.pts.empty()) {
            if (pyramids) {
                cv::calcOpticalFlowPyrLK(c.prev_pyr, pyr, c.pts, nxt, st, err, win, max_level,
                                         crit, 0, 1e-4);
                cv::calcOpticalFlowPyrLK(pyr, c.prev_pyr, nxt, back, st2, err, win, max_level,
                                         crit, 0, 1e-4);
            } else {
                cv::calcOpticalFlowPyrLK(c.prev, img, c.pts, nxt, st, err, win, max_level, crit,
                                         0, 1e-4);
                cv::calcOpticalFlowPyrLK(img, c.prev, nxt, back, st2, err, win, max_level, crit,
                                         0, 1e-4);
            }
            size_t m = 0;
            for (size_t i = 0; i < c.pts.size(); ++i) {
                const cv::Point2f q = nxt[i];
                if (!st[i] || !st2[i] ||
                    std::hypot(back[i].x - c.pts[i].x, back[i].y - c.pts[i].y) > 1.0f ||
                    q.x < 0 || q.y < 0 || q.x > s.w - 1 || q.y > s.h - 1) {
                    continue;
                }
                c.pts[m] = q;
                c.born[m] = c.born[i];
                ++m;
            }
            c.pts.resize(m);
            c.born.resize(m);
        } else {
            c.pts.clear();
            c.born.clear();
        }
        if ((int)c.pts.size() < topup_below) {
            cv::Mat mask(img.size(), CV_8U, cv::Scalar(255));
            for (const auto &p : c.pts) {
                cv::circle(mask, cv::Point((int)std::lround(p.x), (int)std::lround(p.y)),
                           (int)min_dist, cv::Scalar(0), -1);
            }
            cv::goodFeaturesToTrack(img, fresh, target - (int)c.pts.size(), quality, min_dist,
                                    mask, 3, false);
            for (const auto &p : fresh) {
                c.pts.push_back(p);
                c.born.push_back(birth{j, {p.x, p.y}, -9, {0, 0}});
            }
        }
        c.prev = img;
        if (pyramids) {
            c.prev_pyr.swap(pyr);
        }
        const double dt = us_since(t0);
        if (r != nullptr) {
            r->feats += (long)c.pts.size();
            for (size_t i = 0; i < c.pts.size(); ++i) {
                score(s, k, j, c.born[i], c.pts[i].x, c.pts[i].y, *r);
            }
        }
        return dt;
    }
};

rp_side g_rp;
cv_side g_cvi, g_cvp;

/* Runs the three trackers interleaved camera by camera, reps times; per (frame, camera) each
 * one's time is the minimum over repetitions (the work is deterministic, so the minimum is the
 * least disturbed run on a shared machine); accuracy from the first repetition. */
void run_all(const seq &s, int reps, result &rp, result &cvi, result &cvp)
{
    const size_t units = (size_t)s.n * BT_NCAMS;
    std::vector<double> t_rp(units, 1e300), t_cvi(units, 1e300), t_cvp(units, 1e300);
    g_cvp.pyramids = true;
    for (int r = 0; r < reps; ++r) {
        g_rp.init();
        g_cvi.init();
        g_cvp.init();
        for (int j = 0; j < s.n; ++j) {
            for (int k = 0; k < BT_NCAMS; ++k) {
                const size_t u = (size_t)j * BT_NCAMS + k;
                t_rp[u] = std::min(t_rp[u], g_rp.step(s, j, k, r == 0 ? &rp : nullptr));
                t_cvi[u] = std::min(t_cvi[u], g_cvi.step(s, j, k, r == 0 ? &cvi : nullptr));
                t_cvp[u] = std::min(t_cvp[u], g_cvp.step(s, j, k, r == 0 ? &cvp : nullptr));
            }
        }
    }
    const std::vector<double> *t[3] = {&t_rp, &t_cvi, &t_cvp};
    result *res[3] = {&rp, &cvi, &cvp};
    for (int i = 0; i < 3; ++i) {
        res[i]->us_first = 0;
        res[i]->us_frames = 0;
        for (size_t u = 0; u < units; ++u) {
            (u < BT_NCAMS ? res[i]->us_first : res[i]->us_frames) += (*t[i])[u];
        }
    }
}

} // namespace

int main(int argc, char **argv)
{
    int frames = 60, reps = 5;
    uint64_t seed = 1;
    const char *out = nullptr;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--frames" && i + 1 < argc) {
            frames = std::atoi(argv[++i]);
        } else if (a == "--reps" && i + 1 < argc) {
            reps = std::atoi(argv[++i]);
        } else if (a == "--seed" && i + 1 < argc) {
            seed = std::strtoull(argv[++i], nullptr, 10);
        } else if (a == "--out" && i + 1 < argc) {
            out = argv[++i];
        } else {
            std::fprintf(stderr, "usage: %s [--frames N] [--reps R] [--seed S] [--out f.json]\n",
                         argv[0]);
            return 2;
        }
    }
    if (frames < 2 || reps < 1) {
        std::fprintf(stderr, "need --frames >= 2 and --reps >= 1\n");
        return 2;
    }
    cv::setNumThreads(1);
    std::string json = "{";
    std::printf("tracker: rigpose rp_track vs OpenCV gftt + calcOpticalFlowPyrLK (1 thread), 4 "
                "cameras, %d frames, seed %llu, min of %d repetitions\n",
                frames, (unsigned long long)seed, reps);
    std::printf("%-8s %-18s %12s %10s %10s %10s %10s\n", "size", "tracker", "us/frameset",
                "first us", "err px", "step px", "feats/cam");
    const int widths[2] = {320, 640};
    for (int wi = 0; wi < 2; ++wi) {
        seq s;
        s.w = widths[wi];
        s.h = s.w * 3 / 4;
        s.n = frames;
        s.sc = bt_scene_new(s.w, s.h, seed, frames);
        if (s.sc == nullptr) {
            std::fprintf(stderr, "out of memory\n");
            return 1;
        }
        for (int j = 0; j < frames; ++j) {
            for (int k = 0; k < BT_NCAMS; ++k) {
                cv::Mat m(s.h, s.w, CV_8U);
                bt_scene_render(s.sc, j, k, m.data);
                s.img.push_back(m);
            }
        }
        result rp, cvi, cvp;
        run_all(s, reps, rp, cvi, cvp);
        const double per = 1.0 / (frames - 1);
        const double nfc = (double)frames * BT_NCAMS;
        const struct {
            const char *name;
            const result *r;
        } rows[3] = {{"rigpose", &rp}, {"opencv (images)", &cvi}, {"opencv (pyramids)", &cvp}};
        for (const auto &row : rows) {
            std::printf("%dx%-4d %-18s %12.0f %10.0f %10.4f %10.4f %10.1f\n", s.w, s.h,
                        row.name, row.r->us_frames * per, row.r->us_first,
                        row.r->err_sum / (double)std::max(1L, row.r->err_n),
                        row.r->step_sum / (double)std::max(1L, row.r->step_n),
                        (double)row.r->feats / nfc);
        }
        const result &best = cvi.us_frames < cvp.us_frames ? cvi : cvp;
        const double ratio = rp.us_frames / best.us_frames;
        std::printf("%dx%d: rigpose / OpenCV (faster variant) time ratio %.3f; vs images %.3f, "
                    "vs pyramids %.3f; first frame (detection) ratio %.3f\n",
                    s.w, s.h, ratio, rp.us_frames / cvi.us_frames, rp.us_frames / cvp.us_frames,
                    rp.us_first / std::min(cvi.us_first, cvp.us_first));
        char buf[1024];
        const int W = s.w;
        std::snprintf(
            buf, sizeof buf,
            "%s\"tracker_vs_opencv_time_ratio_%d\": %.4f, \"tracker_us_per_frameset_%d\": %.1f, "
            "\"tracker_opencv_us_per_frameset_%d\": %.1f, "
            "\"tracker_opencv_images_us_per_frameset_%d\": %.1f, "
            "\"tracker_opencv_pyramids_us_per_frameset_%d\": %.1f, "
            "\"tracker_err_px_%d\": %.5f, \"tracker_opencv_err_px_%d\": %.5f, "
            "\"tracker_step_err_px_%d\": %.5f, \"tracker_opencv_step_err_px_%d\": %.5f, "
            "\"tracker_feats_per_cam_%d\": %.1f, \"tracker_opencv_feats_per_cam_%d\": %.1f, "
            "\"tracker_first_frame_vs_opencv_time_ratio_%d\": %.4f",
            wi ? ", " : "", W, ratio, W, rp.us_frames * per, W, best.us_frames * per, W,
            cvi.us_frames * per, W, cvp.us_frames * per, W,
            rp.err_sum / (double)std::max(1L, rp.err_n), W,
            best.err_sum / (double)std::max(1L, best.err_n), W,
            rp.step_sum / (double)std::max(1L, rp.step_n), W,
            best.step_sum / (double)std::max(1L, best.step_n), W, (double)rp.feats / nfc, W,
            (double)best.feats / nfc, W, rp.us_first / std::min(cvi.us_first, cvp.us_first));
        json += buf;
        bt_scene_free(s.sc);
    }
    json += "}\n";
    if (out != nullptr) {
        FILE *f = std::fopen(out, "w");
        if (f == nullptr || std::fputs(json.c_str(), f) < 0 || std::fclose(f) != 0) {
            std::fprintf(stderr, "cannot write %s\n", out);
            return 1;
        }
    }
    return 0;
}
