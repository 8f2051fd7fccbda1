/*
 * rigpose-realdata - rigpose's layouts on real camera data: a KITTI odometry or EuRoC MAV
 * folder (rp_realdata.hpp: calibration -> a rig of one stereo pair, ground truth in rigpose's
 * conventions) -> the core's image pipeline (rp_pipe.h; layout stereo2 by default: trackers,
 * stereo matching, the pose EKF; or the two cameras as single cameras: gc, rc, cam1, cam2)
 * -> poses of the left camera, scored against the ground truth frame by frame:
 * translation error |d_est - d_true| (m) and rotation error (angle of R_est^T R_true), no
 * alignment beyond the shared start (frame 0 is the world in both). The summary gives the
 * absolute trajectory error (ATE: RMSE of the translation errors over the frames) in metres
 * and in percent of the true path's length.
 *
 * The settings are the core's defaults (rp_pipe_default_cfg), whatever the dataset, or those of
 * a configuration file (--config FILE, the daemon's parser); command-line options override
 * single settings. Every setting that differs from the core's default is printed on stderr.
 * The only per-dataset inputs are the calibration and the frame times.
 *
 * usage: rigpose-realdata (--kitti DIR | --euroc DIR) [--layout L] [--config FILE] [--frames N] [--first K]
 *            [--name NAME] [--quiet] [--json-out FILE] [--tracks-out FILE] [--check-ate-m X]
 *            [--check-ate-percent X]
 *            [--replay-out DIR [--copy-images]] [--no-run] [settings, see --help]
 * Exit status: 0 done (and checks passed), 1 a check failed or the run broke, 2 bad usage/data.
 */
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "rigpose/rp_config.h"
#include "rigpose/rp_pipe.h"
#include "rp_direct.hpp"
#include "rp_mirror.hpp"
#include "rp_rectify.hpp"
#include "rp_realdata.hpp"
#include "../../calib/rp_timesync.hpp"
#include "../../common/rp_cfg_diff.h"
#include "../../common/rp_cv.hpp"
#include "../../ba/rp_tracks.hpp"

namespace fs = std::filesystem;

namespace {

/* The pipeline's settings: the core's defaults for the layout (rp_pipe_default_cfg), or the
 * estimator and tracker sections of a rigpose configuration file (config/README.md, read by the
 * daemon's parser rp_config_load, which starts from the same defaults; its method must be the
 * layout's). The file's cameras, source and lcm sections are not used: the rig is the dataset's
 * calibration, camera 0 the left (the reference), camera 1 the right. The layout's cameras:
 * stereo2 the pair (0, 1); gc and rc both cameras as single cameras (no stereo matching);
 * cam1 / cam2 camera 0 / 1 alone (the pose still that of camera 0, through the extrinsics). */
bool base_cfg(const std::string &config, rp_pipe_layout_t layout, rp_pipe_cfg_t *cfg,
              std::string *err)
{
    if (config.empty()) {
        if (rp_pipe_default_cfg(layout, cfg) != RP_OK) {
            *err = std::string("rp_pipe_default_cfg(") + rp_pipe_layout_name(layout) + ") failed";
            return false;
        }
    } else {
        static rp_config_t file; /* large (the rig, the HAL's paths): static */
        char msg[RP_CFG_ERR_MAX];
        if (rp_config_load(config.c_str(), &file, msg, sizeof msg) != RP_CFG_OK) {
            *err = msg;
            return false;
        }
        if (file.pipe.layout != layout) {
            *err = config + ": estimator.method is " + rp_pipe_layout_name(file.pipe.layout) +
                   "; this run is " + rp_pipe_layout_name(layout) + " (--layout)";
            return false;
        }
        *cfg = file.pipe;
    }
    cfg->stereo.n_pairs = 1;
    cfg->stereo.pair_a[0] = 0;
    cfg->stereo.pair_b[0] = 1;
    cfg->gc.n_cams = 2;
    std::memset(cfg->gc.cams, 0, sizeof cfg->gc.cams);
    cfg->gc.cams[1] = 1;
    cfg->rc_n = 2;
    std::memset(cfg->rc_cams, 0, sizeof cfg->rc_cams);
    cfg->rc_cams[1] = 1;
    cfg->mono.cam = layout == RP_PIPE_CAM2 ? 1 : 0;
    return true;
}

/* One setting of the command line (--q-trans 1 ...) over cfg; the fields it sets go to
 * *fields (their reason in the deviations printed). False for an unknown option or value. */
bool apply_override(const std::string &opt, const char *v, rp_pipe_cfg_t *cfg,
                    std::vector<const char *> *fields)
{
    int n1 = 0, n2 = 0;
    double d1 = 0, d2 = 0;
    const double x = std::atof(v);
    const int i = std::atoi(v);
    if (opt == "--q-trans") { /* every estimator's, as the file's key */
        cfg->stereo.ekf.q_trans = cfg->gc.ekf.q_trans = cfg->mono.ekf.q_trans = (rp_real)x;
        fields->push_back("stereo.ekf.q_trans");
        fields->push_back("gc.ekf.q_trans");
        fields->push_back("mono.ekf.q_trans");
    } else if (opt == "--q-rot") { /* every estimator's, as the file's key */
        cfg->stereo.ekf.q_rot = cfg->gc.ekf.q_rot = cfg->mono.ekf.q_rot = (rp_real)x;
        fields->push_back("stereo.ekf.q_rot");
        fields->push_back("gc.ekf.q_rot");
        fields->push_back("mono.ekf.q_rot");
    } else if (opt == "--sigma-px") { /* every estimator's, as the file's key */
        cfg->stereo.ekf.sigma_px = cfg->gc.ekf.sigma_px = cfg->mono.ekf.sigma_px = (rp_real)x;
        fields->push_back("stereo.ekf.sigma_px");
        fields->push_back("gc.ekf.sigma_px");
        fields->push_back("mono.ekf.sigma_px");
    } else if (opt == "--estimate-offsets") { /* every estimator's, as the file's key */
        if (i != 0 && i != 1) {
            return false;
        }
        cfg->stereo.ekf.toff_estimate = cfg->gc.ekf.toff_estimate = cfg->mono.ekf.toff_estimate =
            (uint8_t)i;
        fields->push_back("stereo.ekf.toff_estimate");
        fields->push_back("gc.ekf.toff_estimate");
        fields->push_back("mono.ekf.toff_estimate");
    } else if (opt == "--offset-sigma") { /* every estimator's, as the file's key */
        cfg->stereo.ekf.toff_sigma_s = cfg->gc.ekf.toff_sigma_s = cfg->mono.ekf.toff_sigma_s =
            (rp_real)x;
        fields->push_back("stereo.ekf.toff_sigma_s");
        fields->push_back("gc.ekf.toff_sigma_s");
        fields->push_back("mono.ekf.toff_sigma_s");
    } else if (opt == "--offset-ms") { /* the right camera's configured clock offset */
        cfg->stereo.ekf.toff0_s[1] = cfg->gc.ekf.toff0_s[1] = cfg->mono.ekf.toff0_s[1] =
            (rp_real)(1e-3 * x);
        fields->push_back("stereo.ekf.toff0_s");
        fields->push_back("gc.ekf.toff0_s");
        fields->push_back("mono.ekf.toff0_s");
    } else if (opt == "--max-pair-skew") {
        cfg->stereo.max_pair_skew_s = (rp_real)x;
        fields->push_back("stereo.max_pair_skew_s");
    } else if (opt == "--features") {
        cfg->track.target = (uint16_t)i;
        cfg->track.topup_below = (uint16_t)(i * 4 / 5);
        fields->push_back("track.target");
        fields->push_back("track.topup_below");
    } else if (opt == "--levels") {
        cfg->track.levels = (uint8_t)i;
        fields->push_back("track.levels");
    } else if (opt == "--add-landmarks") {
        if (i != 0 && i != 1) {
            return false;
        }
        cfg->stereo.add_landmarks = (uint8_t)i;
        fields->push_back("stereo.add_landmarks");
    } else if (opt == "--win") {
        cfg->track.win = (uint8_t)i;
        fields->push_back("track.win");
    } else if (opt == "--min-dist") {
        cfg->track.min_dist = (uint16_t)i;
        fields->push_back("track.min_dist");
    } else if (opt == "--min-tracked") {
        cfg->stereo.min_tracked = (uint16_t)i;
        fields->push_back("stereo.min_tracked");
    } else if (opt == "--refine") {
        cfg->stereo.refine_structure = (uint8_t)i;
        fields->push_back("stereo.refine_structure");
    } else if (opt == "--iterations") { /* every estimator's, as the file's key */
        cfg->stereo.ekf.iterations = cfg->gc.ekf.iterations = cfg->mono.ekf.iterations = (uint8_t)i;
        fields->push_back("stereo.ekf.iterations");
        fields->push_back("gc.ekf.iterations");
        fields->push_back("mono.ekf.iterations");
    } else if (opt == "--gate") { /* every estimator's, as the file's key */
        cfg->stereo.ekf.gate_chi2 = cfg->gc.ekf.gate_chi2 = cfg->mono.ekf.gate_chi2 = (rp_real)x;
        fields->push_back("stereo.ekf.gate_chi2");
        fields->push_back("gc.ekf.gate_chi2");
        fields->push_back("mono.ekf.gate_chi2");
    } else if (opt == "--match-subpix") {
        cfg->smatch.subpix_iter = (uint8_t)i;
        fields->push_back("smatch.subpix_iter");
    } else if (opt == "--fb-max") {
        cfg->track.fb_max_q16 = (uint32_t)std::lround(x * 65536.0);
        fields->push_back("track.fb_max_q16");
    } else if (opt == "--match-win") {
        cfg->smatch.half_win = (uint8_t)i;
        fields->push_back("smatch.half_win");
    } else if (opt == "--match-zncc") {
        cfg->smatch.min_zncc_q15 = (int16_t)std::lround(x * 32767.0);
        fields->push_back("smatch.min_zncc_q15");
    } else if (opt == "--max-depth") {
        cfg->stereo.max_depth_m = (rp_real)x;
        fields->push_back("stereo.max_depth_m");
    } else if (opt == "--grid" && std::sscanf(v, "%d,%d", &n1, &n2) == 2) {
        cfg->track.grid_x = (uint8_t)n1;
        cfg->track.grid_y = (uint8_t)n2;
        fields->push_back("track.grid_");
    } else if (opt == "--match-depth" && std::sscanf(v, "%lf,%lf", &d1, &d2) == 2) {
        cfg->smatch.min_depth_m = (rp_real)d1;
        cfg->smatch.max_depth_m = (rp_real)d2;
        fields->push_back("smatch.min_depth_m");
        fields->push_back("smatch.max_depth_m");
    } else {
        return false;
    }
    return true;
}

void print_settings(const char *from, const rp_pipe_cfg_t &c)
{
    std::printf("settings (%s): EKF q_trans %g m^2/s^3, q_rot %g rad^2/s^3, sigma %g px; "
                "tracker %u features, %u levels, window %u, min dist %u px, grid %ux%u; "
                "stereo search %g..%g m, patch %dx%d, ZNCC >= %.3g, landmarks to %g m, re-init "
                "under %u\n",
                from, (double)c.stereo.ekf.q_trans, (double)c.stereo.ekf.q_rot,
                (double)c.stereo.ekf.sigma_px, (unsigned)c.track.target, (unsigned)c.track.levels,
                (unsigned)c.track.win, (unsigned)c.track.min_dist, (unsigned)c.track.grid_x,
                (unsigned)c.track.grid_y, (double)c.smatch.min_depth_m,
                (double)c.smatch.max_depth_m, 2 * c.smatch.half_win + 1, 2 * c.smatch.half_win + 1,
                c.smatch.min_zncc_q15 / 32767.0, (double)c.stereo.max_depth_m,
                (unsigned)c.stereo.min_tracked);
}

/* The frame rate of a sequence: its median frame interval (the replay folder's fps). */
double seq_fps(const rprd::Sequence &seq)
{
    std::vector<int64_t> d;
    for (size_t j = 1; j < seq.utime.size(); ++j) {
        d.push_back(seq.utime[j] - seq.utime[j - 1]);
    }
    if (d.empty()) {
        return 30.0;
    }
    std::nth_element(d.begin(), d.begin() + (long)(d.size() / 2), d.end());
    return 1e6 / (double)d[d.size() / 2];
}

std::string flag_text(uint32_t f)
{
    static const char *const names[] = {"init", "track", "reinit", "degraded",
                                        "lost", "gated", "covreset", "scaleweak"};
    std::string s;
    for (int i = 0; i < 8; ++i) {
        if (f & (1u << i)) {
            s += (s.empty() ? "" : ",") + std::string(names[i]);
        }
    }
    return s.empty() ? "-" : s;
}

/* A replay folder (the shared format): frames.csv, truth.csv, rig.yaml (config/README.md). */
bool write_replay(const std::string &out, const rprd::Sequence &seq, const rp_pipe_cfg_t &cfg,
                  bool copy_images)
{
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec) {
        std::fprintf(stderr, "%s: %s\n", out.c_str(), ec.message().c_str());
        return false;
    }
    const fs::path base = fs::absolute(out);
    FILE *ff = std::fopen((out + "/frames.csv").c_str(), "w");
    FILE *ft = std::fopen((out + "/truth.csv").c_str(), "w");
    FILE *fy = std::fopen((out + "/rig.yaml").c_str(), "w");
    bool ok = ff && ft && fy;
    if (ok) {
        std::fprintf(ff, "utime_us,cam0,cam1\n");
        std::fprintf(ft, "utime_us,tx,ty,tz,alpha,beta,gamma\n");
    }
    for (size_t j = 0; ok && j < seq.utime.size(); ++j) {
        std::string rel[2];
        for (int k = 0; k < 2; ++k) {
            if (copy_images) {
                char name[48];
                std::snprintf(name, sizeof name, "cam%d/%06zu.png", k, j);
                fs::create_directories(base / ("cam" + std::to_string(k)), ec);
                const cv::Mat im = cv::imread(seq.img[k][j], cv::IMREAD_GRAYSCALE);
                if (ec || im.empty() || !cv::imwrite((base / name).string(), im)) {
                    std::fprintf(stderr, "%s: cannot copy\n", seq.img[k][j].c_str());
                    ok = false;
                    break;
                }
                rel[k] = name;
            } else {
                rel[k] = fs::relative(fs::absolute(seq.img[k][j]), base, ec).string();
                ok = ok && !ec && !rel[k].empty();
            }
        }
        double p[6];
        rprd::pose_to_vec(seq.truth[j], p);
        std::fprintf(ff, "%lld,%s,%s\n", (long long)seq.utime[j], rel[0].c_str(), rel[1].c_str());
        std::fprintf(ft, "%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n", (long long)seq.utime[j], p[0],
                     p[1], p[2], p[3], p[4], p[5]);
    }
    if (ok) {
        const char *names[2] = {"left", "right"};
        std::fprintf(fy,
                     "# rig.yaml: %s as a replay folder (written by rigpose-realdata from %s).\n"
                     "# Schema: config/README.md. The images are larger than the default build's\n"
                     "# RP_TRACK_MAX_W x RP_TRACK_MAX_H (640x480): the daemon that replays them\n"
                     "# needs a core built with larger limits (as rigpose-realdata's).\n"
                     "version: 1\n\nsource:\n  kind: replay\n  replay_index: frames.csv\n"
                     "  realtime: false\n\ncameras:\n",
                     seq.name.c_str(), seq.dir.c_str());
        for (int k = 0; k < 2; ++k) {
            const rp_rig_cam_t &c = seq.rig.cam[k];
            std::fprintf(fy,
                         "  - name: %s\n    device: cam%d\n    width: %u\n    height: %u\n"
                         "    fps: %d\n    intrinsics: [%.9g, %.9g, %.9g, %.9g]\n"
                         "    distortion: [%.9g, %.9g, %.9g, %.9g, %.9g]\n"
                         "    position: [%.12g, %.12g, %.12g]\n"
                         "    rotation: [%.12g, %.12g, %.12g,\n"
                         "               %.12g, %.12g, %.12g,\n"
                         "               %.12g, %.12g, %.12g]\n",
                         names[k], k, (unsigned)c.cam.width, (unsigned)c.cam.height,
                         (int)std::lround(seq_fps(seq)), (double)c.cam.fx, (double)c.cam.fy,
                         (double)c.cam.cx, (double)c.cam.cy, (double)c.cam.k1, (double)c.cam.k2,
                         (double)c.cam.p1, (double)c.cam.p2, (double)c.cam.k3, (double)c.D[0],
                         (double)c.D[1], (double)c.D[2], (double)c.R[0], (double)c.R[1],
                         (double)c.R[2], (double)c.R[3], (double)c.R[4], (double)c.R[5],
                         (double)c.R[6], (double)c.R[7], (double)c.R[8]);
        }
        /* the settings this run used, where they differ from the core's defaults (a key
         * left out keeps the default of the core that reads the file) */
        rp_pipe_cfg_t d;
        (void)rp_pipe_default_cfg(RP_PIPE_STEREO2, &d);
        const rp_vo_stereo_cfg_t &e = cfg.stereo, &de = d.stereo;
        const rp_track_cfg_t &t = cfg.track, &dt = d.track;
        const rp_pipe_layout_t l = cfg.layout;
        std::fprintf(fy, "\nestimator:\n  method: %s\n  %s\n", rp_pipe_layout_name(l),
                     l == RP_PIPE_STEREO2                        ? "pairs: [[left, right]]"
                     : l == RP_PIPE_GC || l == RP_PIPE_RC        ? "cams: [left, right]"
                     : l == RP_PIPE_CAM2                         ? "cams: [right]"
                                                                 : "cams: [left]");

#define RD_KEY(cond, ...) if (cond) { std::fprintf(fy, __VA_ARGS__); }
        RD_KEY(e.ekf.sigma_px != de.ekf.sigma_px, "  sigma_px: %g\n", (double)e.ekf.sigma_px)
        RD_KEY(e.ekf.q_trans != de.ekf.q_trans, "  q_trans: %g\n", (double)e.ekf.q_trans)
        RD_KEY(e.ekf.q_rot != de.ekf.q_rot, "  q_rot: %g\n", (double)e.ekf.q_rot)
        RD_KEY(e.ekf.gate_chi2 != de.ekf.gate_chi2, "  gate_chi2: %g\n", (double)e.ekf.gate_chi2)
        RD_KEY(e.ekf.iterations != de.ekf.iterations, "  iterations: %u\n", (unsigned)e.ekf.iterations)
        RD_KEY(e.min_tracked != de.min_tracked, "  min_tracked: %u\n", (unsigned)e.min_tracked)
        RD_KEY(e.min_depth_m != de.min_depth_m, "  min_depth_m: %g\n", (double)e.min_depth_m)
        RD_KEY(e.max_depth_m != de.max_depth_m, "  max_depth_m: %g\n", (double)e.max_depth_m)
        RD_KEY(e.refine_structure != de.refine_structure, "  refine_structure: %s\n",
               e.refine_structure ? "true" : "false")
        std::fprintf(fy, "  default_dt_s: %g\n", 1.0 / seq_fps(seq));
        /* the tracker section only with a key in it (an empty one is not a mapping) */
        if (t.target != dt.target || t.levels != dt.levels || t.win != dt.win ||
            t.min_dist != dt.min_dist || t.fb_max_q16 != dt.fb_max_q16 ||
            t.grid_x != dt.grid_x || t.grid_y != dt.grid_y) {
            std::fprintf(fy, "\ntracker:\n");
        }
        RD_KEY(t.target != dt.target, "  target: %u\n", (unsigned)t.target)
        RD_KEY(t.levels != dt.levels, "  levels: %u\n", (unsigned)t.levels)
        RD_KEY(t.win != dt.win, "  win: %u\n", (unsigned)t.win)
        RD_KEY(t.min_dist != dt.min_dist, "  min_dist: %u\n", (unsigned)t.min_dist)
        RD_KEY(t.fb_max_q16 != dt.fb_max_q16, "  fb_max_px: %g\n", t.fb_max_q16 / 65536.0)
        RD_KEY(t.grid_x != dt.grid_x || t.grid_y != dt.grid_y, "  grid: [%u, %u]\n",
               (unsigned)t.grid_x, (unsigned)t.grid_y)
#undef RD_KEY
        if (std::memcmp(&cfg.smatch, &d.smatch, sizeof d.smatch) != 0) {
            std::fprintf(fy, "# (this run's stereo matcher settings differ from the core's; the "
                             "schema has no keys for them)\n");
        }
    }
    ok = ok && (!ff || std::fclose(ff) == 0);
    ok = ok && (!ft || std::fclose(ft) == 0);
    ok = ok && (!fy || std::fclose(fy) == 0);
    if (!ok) {
        std::fprintf(stderr, "%s: cannot write the replay folder\n", out.c_str());
    }
    return ok;
}

/* A yardstick that does not use rigpose: plain OpenCV frame-to-frame stereo odometry on a
 * rectified pair (KITTI). Per frame j: goodFeaturesToTrack in the left image (500, quality
 * 0.01, 10 px), pyramidal LK into the right image (depth from the disparity, rows within 1 px)
 * and into the next left image, solvePnPRansac (1 px), chained. Its trajectory tells how far
 * the ground truth itself is from what the images show. Returns false if a step fails. */
bool opencv_reference(const rprd::Sequence &seq, std::vector<rprd::Pose> *traj)
{
    const rp_camera_t &c = seq.rig.cam[0].cam;
    const double b = (double)seq.rig.cam[1].D[0];
    const cv::Mat K = (cv::Mat_<double>(3, 3) << (double)c.fx, 0, (double)c.cx, 0, (double)c.fy,
                       (double)c.cy, 0, 0, 1);
    traj->assign(1, rprd::Pose());
    for (size_t j = 0; j + 1 < seq.utime.size(); ++j) {
        const cv::Mat L = cv::imread(seq.img[0][j], cv::IMREAD_GRAYSCALE);
        const cv::Mat R = cv::imread(seq.img[1][j], cv::IMREAD_GRAYSCALE);
        const cv::Mat N = cv::imread(seq.img[0][j + 1], cv::IMREAD_GRAYSCALE);
        if (L.empty() || R.empty() || N.empty()) {
            return false;
        }
        std::vector<cv::Point2f> a, r, n;
        std::vector<uchar> sr, sn;
        std::vector<float> e;
        cv::goodFeaturesToTrack(L, a, 500, 0.01, 10);
        if (a.size() < 6) {
            return false;
        }
        cv::calcOpticalFlowPyrLK(L, R, a, r, sr, e, cv::Size(21, 21), 3);
        cv::calcOpticalFlowPyrLK(L, N, a, n, sn, e, cv::Size(21, 21), 3);
        std::vector<cv::Point3f> obj;
        std::vector<cv::Point2f> img;
        for (size_t i = 0; i < a.size(); ++i) {
            const double d = (double)(a[i].x - r[i].x);
            if (!sr[i] || !sn[i] || d < 1.0 || std::fabs(a[i].y - r[i].y) > 1.0f) {
                continue;
            }
            const double z = (double)c.fx * b / d;
            obj.emplace_back((float)(((double)a[i].x - (double)c.cx) * z / (double)c.fx),
                             (float)(((double)a[i].y - (double)c.cy) * z / (double)c.fy),
                             (float)z);
            img.push_back(n[i]);
        }
        cv::Mat rv, tv, Rm;
        if (obj.size() < 6 ||
            !cv::solvePnPRansac(obj, img, K, cv::noArray(), rv, tv, false, 300, 1.0f, 0.999)) {
            return false;
        }
        cv::Rodrigues(rv, Rm);
        rprd::Pose T; /* points of frame j's camera into frame j+1's */
        for (int i = 0; i < 9; ++i) {
            T.R[i] = Rm.at<double>(i / 3, i % 3);
        }
        for (int i = 0; i < 3; ++i) {
            T.t[i] = tv.at<double>(i);
        }
        traj->push_back(rprd::pose_mul(traj->back(), rprd::pose_inv(T)));
    }
    return true;
}

/* One frame-to-frame step of a trajectory: T(j-1)^-1 T(j) (frame j's camera in frame j-1's). */
rprd::Pose step_of(const std::vector<rprd::Pose> &traj, size_t j)
{
    return rprd::pose_mul(rprd::pose_inv(traj[j - 1]), traj[j]);
}

/* "length m, rotation angle deg, direction x/len y/len" of a step. */
void print_step(const rprd::Pose &T)
{
    const double len = std::sqrt(T.t[0] * T.t[0] + T.t[1] * T.t[1] + T.t[2] * T.t[2]);
    const double c = std::min(1.0, std::max(-1.0, (T.R[0] + T.R[4] + T.R[8] - 1.0) / 2.0));
    std::printf(" | %6.4f %6.3f %7.4f %7.4f", len, std::acos(c) * 180.0 / M_PI,
                len > 0.0 ? T.t[0] / len : 0.0, len > 0.0 ? T.t[1] / len : 0.0);
}

/* The --steps table: per frame, each trajectory's step (what the ground truth and the images
 * say the camera did between two frames, whatever happened before). */
void print_steps(const rprd::Sequence &seq, const std::vector<rprd::Pose> &est,
                 const std::vector<rprd::Pose> &cv_ref, const std::vector<rprd::Pose> &direct)
{
    std::printf("\nsteps: length m, rotation deg, direction x/len y/len (camera frame j-1)\n"
                "frame | truth | rigpose%s%s\n",
                cv_ref.empty() ? "" : " | OpenCV PnP", direct.empty() ? "" : " | direct");
    for (size_t j = 1; j < seq.truth.size() && j < est.size(); ++j) {
        std::printf("%5zu", j);
        print_step(step_of(seq.truth, j));
        print_step(step_of(est, j));
        if (j < cv_ref.size()) {
            print_step(step_of(cv_ref, j));
        }
        if (j < direct.size()) {
            print_step(step_of(direct, j));
        }
        std::printf("\n");
    }
}

void usage(FILE *f)
{
    std::fprintf(
        f,
        "usage: rigpose-realdata (--kitti DIR | --euroc DIR) [options]\n"
        "  --kitti DIR          KITTI odometry folder: calib.txt (P0 left, P1 right: lines\n"
        "                       \"P0: <12 numbers>\", \"P1: ...\" or P_rect_00 / P_rect_01, or\n"
        "                       without labels the first two lines of 12 numbers, 3x4 row-\n"
        "                       major), poses.txt (per frame 12 numbers: 3x4 [R|t] row-major,\n"
        "                       the left camera at frame j in frame 0's), times.txt (s per\n"
        "                       frame; or --fps), images NNNNNN.png in image_0/ + image_1/,\n"
        "                       image_l/ + image_r/ or left/ + right/ (first found; --images)\n"
        "  --euroc DIR          EuRoC MAV folder (or its mav0/): cam0/ (left), cam1/ (right)\n"
        "                       with sensor.yaml and data.csv (t[ns],file; every listed image\n"
        "                       must exist); the body's ground truth: groundtruth.txt, TUM\n"
        "                       \"t[s] tx ty tz qx qy qz qw\" (qw LAST), else EuRoC's own\n"
        "                       state_groundtruth_estimate0/data.csv \"t[ns], px, py, pz, qw,\n"
        "                       qx, qy, qz, ...\" (qw FIRST); told apart by the time column\n"
        "                       (over 1e12: ns). The first pose read is printed: check it\n"
        "  --truth FILE         the ground-truth file (KITTI poses / TUM / EuRoC csv format)\n"
        "  --images L,R         KITTI: the left and right image folders under DIR\n"
        "  --fps HZ             KITTI: frame j at j / HZ s (times.txt not read; for folders\n"
        "                       without it)\n"
        "  --layout L           stereo2 (default: the pair, stereo matching), gc, rc (both\n"
        "                       cameras as single cameras of a non-overlapping rig, no\n"
        "                       matching), cam1 / cam2 (the left / right camera alone); the\n"
        "                       pose is the left camera's in every layout\n"
        "  --trace-scale        gc: per frame, the metric scale's state (rp_vo_gc.h step 6)\n"
        "  --sync-rotation      before the run, estimate the right camera's clock offset from\n"
        "                       the two cameras' rotation rates (rp_timesync.hpp) and start\n"
        "                       the estimator from it (cameras[1].time_offset_s; with\n"
        "                       --estimate-offsets 1 the offset state starts with its sigma)\n"
        "  --regroup            pair each left image with the right image captured nearest\n"
        "                       to it (stamp + the right camera's offset: --sync-rotation or\n"
        "                       --offset-ms), within half a frame interval (else the right\n"
        "                       camera has no image in that set); each keeps its own stamp\n"
        "  --pair-shift K       pair the right camera's image j + K with the left's j, stamped\n"
        "                       as simultaneous (a right camera K frames late: the\n"
        "                       clock-offset experiment; --estimate-offsets 1 to estimate it)\n"
        "  --frames N           N frames (default: all)\n"
        "  --first K            start at frame K (frames, not file lines: EuRoC counts the\n"
        "                       timestamps both cameras list; its left camera is the world)\n"
        "  --name NAME          prefix of the JSON figures (default kitti00 / euroc_mh01)\n"
        "  --quiet              no per-frame lines\n"
        "  --json-out FILE      write the figures as one flat JSON object\n"
        "  --tracks-out FILE    write the rig and, per frame set, the features the estimator\n"
        "                       received (rp_pipe_frameset), its pose and the truth\n"
        "                       (host_tools/ba/rp_tracks.hpp; rigpose-ba --tracks reads it)\n"
        "  --check-ate-m X      exit 1 unless the ATE is at most X metres\n"
        "  --check-ate-percent X  exit 1 unless the ATE is at most X %% of the path\n"
        "  --replay-out DIR     write a replay folder (frames.csv, truth.csv, rig.yaml); image\n"
        "                       paths relative to DIR, or copies with --copy-images\n"
        "  --no-run             only load (and write the replay folder)\n"
        "  --opencv-ref         also run plain OpenCV stereo odometry (a distorted or verged\n"
        "                       pair, EuRoC's, is rectified for it: rp_rectify.hpp)\n"
        "                       as a yardstick of the ground truth\n"
        "  --direct-ref         also run dense direct stereo odometry (rp_direct.hpp:\n"
        "                       SGBM depth + photometric alignment, no features; about 1 s\n"
        "                       per frame; rectified as for --opencv-ref) as a second yardstick\n"
        "  --mirror             run on the clip's mirror image instead (cameras swapped, images\n"
        "                       flipped left-right, calibration and truth mirrored: rp_mirror.hpp),\n"
        "                       written to a temporary folder removed at exit\n"
        "  --mirror-out DIR     the same, the mirror image written to DIR (kept; the same format\n"
        "                       as the input; with --no-run only written)\n"
        "  --steps              print each frame-to-frame step (length, rotation, direction)\n"
        "                       of the truth, rigpose and the yardsticks run\n"
        "  --direct-rows A,B    the direct yardstick uses image rows A..B-1 only (e.g. the\n"
        "                       road below the horizon, or the scene above it)\n"
        "  --splice K           with --direct-ref: also score the yardstick's steps up to\n"
        "                       frame K followed by the truth's own steps (what an estimator\n"
        "                       exact from frame K on but true to the images before scores)\n"
        "  --config FILE        the estimator and tracker settings of a rigpose configuration\n"
        "                       file (config/README.md; its method the run's --layout; its cameras, source\n"
        "                       and lcm are not used: the rig is the dataset's calibration).\n"
        "                       Without it: the core's defaults (rp_pipe_default_cfg). The\n"
        "                       settings that differ from the defaults are printed on stderr.\n"
        "                       Example files: host_tools/research/realdata/profiles/\n"
        "settings (over the defaults or FILE): --q-trans Q --q-rot Q --sigma-px S --features N --levels L --win W\n"
        "  --min-dist D --grid X,Y --max-depth M --match-depth MIN,MAX --match-win H\n"
        "  --match-zncc Z --match-subpix N --fb-max PX --min-tracked N --refine 0|1\n"
        "  --iterations N --gate CHI2 --estimate-offsets 0|1 --offset-sigma S --add-landmarks 0|1\n"
        "  --offset-ms MS (the right camera's clock offset: capture = stamp + MS)\n"
        "  --max-pair-skew S\n");
}

}  // namespace

int main(int argc, char **argv)
{
    std::string kitti, euroc, name, json_out, replay_out, config, mirror_out, tracks_out;
    rp_pipe_layout_t layout = RP_PIPE_STEREO2;
    bool mirror = false;
    size_t frames = 0, first = 0;
    rprd::LoadOpts lo;
    bool quiet = false, copy_images = false, no_run = false, opencv_ref = false;
    bool direct_ref = false, steps = false, trace_scale = false, sync_rotation = false;
    bool regroup = false;
    size_t splice = 0, pair_shift = 0;
    rprd::DirectOpts dopts;
    double check_m = -1.0, check_pct = -1.0;
    std::vector<std::pair<std::string, std::string>> over;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has_val = i + 1 < argc;
        if (a == "--help" || a == "-h") {
            usage(stdout);
            return 0;
        } else if (a == "--quiet") {
            quiet = true;
        } else if (a == "--copy-images") {
            copy_images = true;
        } else if (a == "--no-run") {
            no_run = true;
        } else if (a == "--opencv-ref") {
            opencv_ref = true;
        } else if (a == "--direct-ref") {
            direct_ref = true;
        } else if (a == "--mirror") {
            mirror = true;
        } else if (a == "--steps") {
            steps = true;
        } else if (a == "--trace-scale") {
            trace_scale = true;
        } else if (a == "--sync-rotation") {
            sync_rotation = true;
        } else if (a == "--regroup") {
            regroup = true;
        } else if (!has_val) {
            std::fprintf(stderr, "rigpose-realdata: %s: unknown option or missing value\n",
                         a.c_str());
            usage(stderr);
            return 2;
        } else if (a == "--kitti") {
            kitti = argv[++i];
        } else if (a == "--euroc") {
            euroc = argv[++i];
        } else if (a == "--layout") {
            if (rp_pipe_layout_from_name(argv[++i], &layout) != RP_OK ||
                !(layout == RP_PIPE_STEREO2 || layout == RP_PIPE_GC || layout == RP_PIPE_CAM1 ||
                  layout == RP_PIPE_CAM2 || layout == RP_PIPE_RC)) {
                std::fprintf(stderr, "rigpose-realdata: --layout stereo2 | gc | cam1 | cam2 | rc "
                                     "(a rig of two cameras)\n");
                return 2;
            }
        } else if (a == "--frames") {
            frames = (size_t)std::strtoul(argv[++i], nullptr, 10);
        } else if (a == "--first") {
            first = (size_t)std::strtoul(argv[++i], nullptr, 10);
        } else if (a == "--images") {
            const std::string v = argv[++i];
            const size_t comma = v.find(',');
            if (comma == std::string::npos || comma == 0 || comma + 1 >= v.size()) {
                std::fprintf(stderr, "rigpose-realdata: --images LEFT,RIGHT (folder names)\n");
                return 2;
            }
            lo.left = v.substr(0, comma);
            lo.right = v.substr(comma + 1);
        } else if (a == "--fps") {
            lo.fps = std::atof(argv[++i]);
            if (!(lo.fps > 0.0 && lo.fps < 1e4)) {
                std::fprintf(stderr, "rigpose-realdata: --fps HZ: a frame rate > 0\n");
                return 2;
            }
        } else if (a == "--mirror-out") {
            mirror_out = argv[++i];
            mirror = true;
        } else if (a == "--config") {
            config = argv[++i];
        } else if (a == "--truth") {
            lo.truth = argv[++i];
        } else if (a == "--name") {
            name = argv[++i];
        } else if (a == "--json-out") {
            json_out = argv[++i];
        } else if (a == "--tracks-out") {
            tracks_out = argv[++i];
        } else if (a == "--replay-out") {
            replay_out = argv[++i];
        } else if (a == "--direct-rows") {
            if (std::sscanf(argv[++i], "%d,%d", &dopts.row_min, &dopts.row_max) != 2 ||
                dopts.row_min < 0 || dopts.row_max <= dopts.row_min) {
                std::fprintf(stderr, "rigpose-realdata: --direct-rows A,B with 0 <= A < B\n");
                return 2;
            }
        } else if (a == "--pair-shift") {
            pair_shift = (size_t)std::strtoul(argv[++i], nullptr, 10);
        } else if (a == "--splice") {
            splice = (size_t)std::strtoul(argv[++i], nullptr, 10);
        } else if (a == "--check-ate-m") {
            check_m = std::atof(argv[++i]);
        } else if (a == "--check-ate-percent") {
            check_pct = std::atof(argv[++i]);
        } else if (a.compare(0, 2, "--") == 0) {
            over.emplace_back(a, argv[++i]);
        } else {
            std::fprintf(stderr, "rigpose-realdata: %s: unknown argument\n", a.c_str());
            return 2;
        }
    }
    if (kitti.empty() == euroc.empty()) {
        std::fprintf(stderr, "rigpose-realdata: give one of --kitti DIR, --euroc DIR\n");
        usage(stderr);
        return 2;
    }
    rprd::Sequence seq;
    std::string err;
    const bool is_kitti = !kitti.empty();
    lo.first = first;
    lo.max_frames = frames;
    if (!(is_kitti ? rprd::load_kitti(kitti, lo, &seq, &err)
                   : rprd::load_euroc(euroc, lo, &seq, &err))) {
        std::fprintf(stderr, "rigpose-realdata: %s\n", err.c_str());
        return 2;
    }
    for (const std::string &n : seq.notes) {
        std::printf("read %s\n", n.c_str());
    }
    /* --pair-shift K: the right camera's image j + K with the left's j, stamped with the left's
     * time: a right camera whose clock runs t(j + K) - t(j) behind (capture = stamp + offset,
     * the offset positive), the experiment of the unsynchronised-cameras issue */
    double true_offset_s = 0.0;
    if (pair_shift > 0) {
        const size_t n = seq.utime.size();
        if (pair_shift >= n || n - pair_shift < 2) {
            std::fprintf(stderr, "rigpose-realdata: --pair-shift %zu: the clip has %zu frames\n",
                         pair_shift, n);
            return 2;
        }
        true_offset_s = 1e-6 * (double)(seq.utime[pair_shift] - seq.utime[0]);
        for (size_t j = 0; j + pair_shift < n; ++j) {
            seq.img[1][j] = seq.img[1][j + pair_shift];
        }
        seq.img[0].resize(n - pair_shift);
        seq.img[1].resize(n - pair_shift);
        seq.utime.resize(n - pair_shift);
        seq.truth.resize(n - pair_shift);
        std::printf("pair shift %zu: the right camera's image j + %zu with the left's j, stamped as "
                    "simultaneous (true offset of the right camera %.1f ms at the start)\n",
                    pair_shift, pair_shift, 1e3 * true_offset_s);
    }
    /* --mirror: write the clip's mirror image (rp_mirror.hpp) and run on that instead */
    /* a temporary folder under $TMPDIR (or /tmp), removed at exit */
    struct TmpDir {
        std::string path;
        bool make(const char *prefix)
        {
            const char *td = std::getenv("TMPDIR");
            std::string tmpl = std::string(td && *td ? td : "/tmp") + "/" + prefix + "_XXXXXX";
            if (!mkdtemp(&tmpl[0])) {
                std::fprintf(stderr, "rigpose-realdata: %s: cannot make a temporary folder\n",
                             tmpl.c_str());
                return false;
            }
            path = tmpl;
            return true;
        }
        ~TmpDir()
        {
            std::error_code ec;
            if (!path.empty()) {
                fs::remove_all(path, ec);
            }
        }
    } tmp, rect_tmp;
    if (mirror) {
        std::string out = mirror_out;
        if (out.empty()) {
            if (!tmp.make("rigpose_mirror")) {
                return 1;
            }
            out = tmp.path;
        }
        rprd::Sequence m;
        if (!rprd::write_sequence(rprd::mirror_sequence(seq), out, true, &err) ||
            !(is_kitti ? rprd::load_kitti(out, 0, 0, &m, &err)
                       : rprd::load_euroc(out, 0, 0, &m, &err))) {
            std::fprintf(stderr, "rigpose-realdata: mirror image: %s\n", err.c_str());
            return 1;
        }
        std::printf("mirror image of frames %zu..%zu of %s (cameras swapped, images flipped, "
                    "calibration and truth mirrored) in %s%s\n",
                    first, first + seq.utime.size() - 1, seq.dir.c_str(), out.c_str(),
                    tmp.path.empty() ? "" : " (removed at exit)");
        seq = m;
        first = 0;
    }
    const bool stereo = layout == RP_PIPE_STEREO2;
    seq.name = !name.empty() ? name
                             : std::string(is_kitti ? "kitti00" : "euroc_mh01") +
                                   (stereo ? "" : std::string("_") + rp_pipe_layout_name(layout)) +
                                   (mirror ? "_mirror" : "");
    static rp_pipe_cfg_t cfg;
    if (!base_cfg(config, layout, &cfg, &err)) {
        std::fprintf(stderr, "rigpose-realdata: %s\n", err.c_str());
        return 2;
    }
    std::vector<const char *> cli_fields;
    for (const auto &o : over) {
        if (!apply_override(o.first, o.second.c_str(), &cfg, &cli_fields)) {
            std::fprintf(stderr, "rigpose-realdata: %s %s: unknown option or bad value\n",
                         o.first.c_str(), o.second.c_str());
            return 2;
        }
    }
    double sync_offset_s = 0.0, sync_sigma_s = 0.0;
    if (sync_rotation) {
        std::vector<rpts::RateSample> w0, w1;
        rpts::OffsetFit fit;
        if (!rpts::camera_rates(seq.img[0], seq.utime, seq.rig.cam[0], &w0, &err) ||
            !rpts::camera_rates(seq.img[1], seq.utime, seq.rig.cam[1], &w1, &err) ||
            !rpts::fit_offset(w0, w1, 0.2, 0.001, &fit)) {
            std::fprintf(stderr, "rigpose-realdata: --sync-rotation: %s\n",
                         err.empty() ? "the rates do not overlap" : err.c_str());
            return 1;
        }
        std::printf("clock offset of the right camera from the rotation rates: %.2f +- %.2f ms "
                    "(%zu of %zu / %zu intervals; rms rate difference %.4f rad/s at lag 0, "
                    "%.4f at the fit; the rate varies %.1f times that)\n",
                    1e3 * fit.offset_s, 1e3 * fit.sigma_s, fit.n, w0.size(), w1.size(),
                    fit.rms_zero, fit.rms_fit, fit.snr);
        if (!std::isfinite(fit.sigma_s)) {
            std::fprintf(stderr, "rigpose-realdata: --sync-rotation: the clip's rotation rate "
                                 "hardly varies: no offset can be told\n");
            return 1;
        }
        sync_offset_s = fit.offset_s;
        sync_sigma_s = fit.sigma_s;
        cfg.stereo.ekf.toff0_s[1] = cfg.gc.ekf.toff0_s[1] = cfg.mono.ekf.toff0_s[1] =
            (rp_real)fit.offset_s;
        /* an estimated offset state starts with the fit's own uncertainty */
        cfg.stereo.ekf.toff_sigma_s = cfg.gc.ekf.toff_sigma_s = cfg.mono.ekf.toff_sigma_s =
            (rp_real)fit.sigma_s;
        for (const char *f : {"stereo.ekf.toff0_s", "gc.ekf.toff0_s", "mono.ekf.toff0_s",
                              "stereo.ekf.toff_sigma_s", "gc.ekf.toff_sigma_s",
                              "mono.ekf.toff_sigma_s"}) {
            cli_fields.push_back(f);
        }
    }
    /* what differs from the core's defaults, one line each on stderr: the rig's numbering, the
     * settings of the command line, those of the configuration file */
    const std::string why_file = config.empty() ? "" : "config " + config;
    const char *const numbering = "the dataset's numbering: 0 left, 1 right";
    const char *table[48][2] = {{"stereo.pair_", numbering}, {"gc.n_cams", numbering},
                                {"gc.cams", numbering},      {"rc_", numbering},
                                {"mono.cam", numbering}};
    size_t nt = 5;
    for (size_t k = 0; k < cli_fields.size() && nt < 46; ++k, ++nt) {
        table[nt][0] = cli_fields[k];
        table[nt][1] = "command line";
    }
    table[nt][0] = "";
    table[nt][1] = why_file.c_str();
    table[nt + 1][0] = nullptr;
    table[nt + 1][1] = nullptr;
    (void)rp_cfg_diff_print(stderr, "rigpose-realdata", &cfg, table);
    const rp_camera_t &c0 = seq.rig.cam[0].cam;
    std::printf("%s: %zu frames from frame %zu of %s; %ux%u, fx %.3f, baseline %.4f m, %.2f Hz\n",
                seq.name.c_str(), seq.utime.size(), first, seq.dir.c_str(), (unsigned)c0.width,
                (unsigned)c0.height, (double)c0.fx,
                std::sqrt((double)(seq.rig.cam[1].D[0] * seq.rig.cam[1].D[0] +
                                   seq.rig.cam[1].D[1] * seq.rig.cam[1].D[1] +
                                   seq.rig.cam[1].D[2] * seq.rig.cam[1].D[2])),
                seq_fps(seq));
    print_settings(config.empty() ? "the core's defaults" : why_file.c_str(), cfg);
    /* each camera's stamp per frame (the set's time unless regrouped) */
    std::vector<int64_t> cam_t[2] = {seq.utime, seq.utime};
    if (regroup) {
        /* sets by capture time (stamp + offset): the left image j with the right image whose
         * capture is nearest to it, within half the median frame interval */
        const double off_us = 1e6 * (double)cfg.stereo.ekf.toff0_s[1];
        const double half_us = 0.5e6 / seq_fps(seq);
        const std::vector<std::string> right = seq.img[1];
        size_t paired = 0;
        for (size_t j = 0; j < seq.utime.size(); ++j) {
            size_t best = 0;
            double gap = INFINITY;
            for (size_t i = 0; i < right.size(); ++i) {
                const double g = std::fabs((double)seq.utime[i] + off_us - (double)seq.utime[j]);
                if (g < gap) {
                    gap = g;
                    best = i;
                }
            }
            const bool ok = gap <= half_us;
            seq.img[1][j] = ok ? right[best] : std::string();
            cam_t[1][j] = ok ? seq.utime[best] : seq.utime[j];
            paired += ok ? 1u : 0u;
        }
        /* leading left images without a partner cannot start the stereo layout: the run starts
         * at the first pair, its world the left camera there (the truth re-based on it) */
        size_t lead = 0;
        while (lead < seq.utime.size() && seq.img[1][lead].empty()) {
            ++lead;
        }
        if (lead > 0 && lead + 2 <= seq.utime.size()) {
            const rprd::Pose w = rprd::pose_inv(seq.truth[lead]);
            for (size_t j = lead; j < seq.utime.size(); ++j) {
                seq.truth[j - lead] = rprd::pose_mul(w, seq.truth[j]);
            }
            for (int k = 0; k < 2; ++k) {
                seq.img[k].erase(seq.img[k].begin(), seq.img[k].begin() + (long)lead);
                cam_t[k].erase(cam_t[k].begin(), cam_t[k].begin() + (long)lead);
            }
            seq.utime.erase(seq.utime.begin(), seq.utime.begin() + (long)lead);
            seq.truth.resize(seq.utime.size());
        }
        std::printf("regrouped by capture time (right camera's offset %.2f ms): %zu of %zu left "
                    "images paired, the others without a right image; the run starts at the "
                    "first pair (%zu left image%s before it left out)\n",
                    1e-3 * off_us, paired, seq.utime.size() + lead, lead, lead == 1 ? "" : "s");
    }
    if (!replay_out.empty()) {
        if (!write_replay(replay_out, seq, cfg, copy_images)) {
            return 1;
        }
        std::printf("replay folder: %s\n", replay_out.c_str());
    }
    if (no_run) {
        return 0;
    }

    static rp_pipe_t pipe; /* large (trackers' pyramids): static */
    rp_status_t st = rp_pipe_init(&pipe, &seq.rig, &cfg);
    if (st != RP_OK) {
        std::fprintf(stderr, "rigpose-realdata: pipeline set-up: %s (image %ux%u; this build "
                             "takes at most %dx%d)\n",
                     rp_status_str(st), (unsigned)c0.width, (unsigned)c0.height, RP_TRACK_MAX_W,
                     RP_TRACK_MAX_H);
        return 2;
    }
    if (!quiet) {
        std::printf("%5s %9s %9s %9s %9s %9s %9s %8s %7s %4s %4s %4s %s\n", "frame", "tx", "ty",
                    "tz", "true_tx", "true_ty", "true_tz", "err_m", "rot_deg", "nL", "nR", "lm",
                    "flags/status");
    }
    std::vector<rprd::Pose> est_pose;
    double step_s = 0.0;
    std::FILE *tracks = nullptr;
    if (!tracks_out.empty()) {
        tracks = std::fopen(tracks_out.c_str(), "w");
        if (!tracks || !rptk::write_header(tracks, seq.name, seq.rig, &err)) {
            std::fprintf(stderr, "rigpose-realdata: %s: cannot write %s\n", tracks_out.c_str(),
                         err.c_str());
            return 1;
        }
    }
    size_t lost = 0, reinit = 0, weak = 0;
    for (size_t j = 0; j < seq.utime.size(); ++j) {
        cv::Mat im[2];
        rp_image_t v[2];
        const rp_image_t *ptr[2] = {nullptr, nullptr};
        const int64_t ct[2] = {cam_t[0][j], cam_t[1][j]};
        for (int k = 0; k < 2; ++k) {
            if (seq.img[k][j].empty()) {
                continue; /* --regroup: no right image captured near this one */
            }
            im[k] = cv::imread(seq.img[k][j], cv::IMREAD_GRAYSCALE);
            if (im[k].empty()) {
                std::fprintf(stderr, "rigpose-realdata: %s: cannot read\n", seq.img[k][j].c_str());
                return 2;
            }
            v[k] = rp_cv_view(im[k]);
            ptr[k] = &v[k];
        }
        rp_estimate_t est;
        const auto t0 = std::chrono::steady_clock::now();
        st = rp_pipe_step_timed(&pipe, ptr, ct, 2, seq.utime[j], &est);
        step_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        double p[6];
        for (int i = 0; i < 6; ++i) {
            p[i] = (double)est.p[i];
        }
        if (j == 0 && st != RP_OK) {
            std::fprintf(stderr, "rigpose-realdata: first frame: %s\n", rp_status_str(st));
        }
        lost += (est.flags & RP_EST_LOST) ? 1u : 0u;
        weak += (est.flags & RP_EST_SCALE_WEAK) ? 1u : 0u;
        reinit += (est.flags & RP_EST_REINIT) ? 1u : 0u;
        const rprd::FrameErr e = rprd::frame_error(p, seq.truth[j]);
        est_pose.push_back(rprd::pose_from_vec(p));
        if (tracks) {
            const rp_frameset_t *fs = nullptr;
            double tv[6];
            rprd::pose_to_vec(seq.truth[j], tv);
            if (rp_pipe_frameset(&pipe, &fs) != RP_OK ||
                !rptk::write_frame(tracks, (uint32_t)j, *fs, est, tv, &err)) {
                std::fprintf(stderr, "rigpose-realdata: %s: %s\n", tracks_out.c_str(), err.c_str());
                return 1;
            }
        }
        if (trace_scale && layout == RP_PIPE_GC) {
            /* gc's step 6 (rp_vo_gc.h): the map's unit and the last window adjustment */
            const rp_vo_gc_t &g = pipe.est.gc;
            const rp_gcba_result_t &r = g.ba_last;
            std::printf("scale %zu: mu %.4f +- %.4f, fused %u refused %u; last window mu %.4f +- "
                        "%.4f, %u landmarks %u obs %u keyframes, rms %.3f -> %.3f px\n",
                        j, (double)g.mu, std::sqrt((double)g.mu_var), (unsigned)g.n_ba,
                        (unsigned)g.n_ba_rejected, (double)r.mu, std::sqrt((double)r.mu_var),
                        (unsigned)r.n_lm, (unsigned)r.n_obs, (unsigned)r.n_kf,
                        (double)r.rms0_px, (double)r.rms_px);
        }
        if (!quiet) {
            std::printf("%5zu %9.4f %9.4f %9.4f %9.4f %9.4f %9.4f %8.4f %7.3f %4u %4u %4u %s%s%s\n",
                        j, p[0], p[1], p[2], seq.truth[j].t[0], seq.truth[j].t[1],
                        seq.truth[j].t[2], e.trans_m, e.rot_rad * 180.0 / M_PI,
                        (unsigned)est.n_used[0], (unsigned)est.n_used[1],
                        (unsigned)est.n_landmarks, flag_text(est.flags).c_str(),
                        st == RP_OK ? "" : " ", st == RP_OK ? "" : rp_status_str(st));
        }
    }
    if (tracks && std::fclose(tracks) != 0) {
        std::fprintf(stderr, "rigpose-realdata: %s: write failed\n", tracks_out.c_str());
        return 1;
    }
    const rprd::Summary s = rprd::summarise(est_pose, seq.truth);
    const double ms = 1e3 * step_s / (double)s.frames;
    std::printf("\n%s, %zu frames, %s through rp_pipe (%s):\n", seq.name.c_str(), s.frames,
                rp_pipe_layout_name(layout),
                is_kitti ? "KITTI rectified pair" : "EuRoC cam0/cam1, distorted");
    std::printf("| figure | value |\n|---|---|\n");
    std::printf("| true path length | %.3f m |\n", s.path_m);
    std::printf("| ATE (RMSE, no alignment) | %.4f m |\n", s.ate_m);
    std::printf("| ATE / path | %.3f %% |\n", s.ate_percent);
    std::printf("| largest / final error | %.4f m / %.4f m |\n", s.max_m, s.final_m);
    std::printf("| rotation error (RMSE) | %.3f deg |\n", s.rot_rmse_deg);
    std::printf("| frame-to-frame drift (RPE / path) | %.3f %% |\n", s.rpe_percent);
    std::printf("| scale of the positions (est / true, least squares) | %.4f |\n", s.scale);
    /* the same trajectory with its positions divided by that scale: what is left when the
     * scale is set aside (a layout without metric scale: cam1, cam2, rc's fallback) */
    std::vector<rprd::Pose> unscaled = est_pose;
    for (rprd::Pose &T : unscaled) {
        for (double &t : T.t) {
            t = s.scale > 0.0 ? t / s.scale : t;
        }
    }
    const rprd::Summary su = rprd::summarise(unscaled, seq.truth);
    std::printf("| ATE with the positions divided by that scale | %.4f m (%.3f %%) |\n", su.ate_m,
                su.ate_percent);
    std::printf("| frames flagged scaleweak (metric scale poorly determined) | %zu of %zu |\n",
                weak, s.frames);
    rp_real off_s[RP_MAX_CAMS], off_sd[RP_MAX_CAMS];
    if (rp_pipe_time_offsets(&pipe, off_s, off_sd) == RP_OK) {
        std::printf("| right camera's clock offset (capture = stamp + it), estimated | %.2f +- %.2f "
                    "ms%s |\n",
                    1e3 * (double)off_s[1], 1e3 * (double)off_sd[1],
                    off_sd[1] > 0 ? "" : " (not estimated: the configured value)");
        if (pair_shift > 0) {
            std::printf("| its true value (--pair-shift) | %.2f ms |\n", 1e3 * true_offset_s);
        }
    }
    if (layout == RP_PIPE_GC) {
        const rp_vo_gc_t &g = pipe.est.gc;
        std::printf("| gc metric scale (step 6): map units per metre, adjustments fused / refused "
                    "| %.4f +- %.4f, %u / %u |\n",
                    (double)g.mu, std::sqrt((double)g.mu_var), (unsigned)g.n_ba,
                    (unsigned)g.n_ba_rejected);
    }
    std::printf("| frames lost / re-initialised | %zu / %zu |\n", lost, reinit);
    std::printf("| pipeline time per frame set | %.2f ms |\n", ms);
    rprd::Summary ref, dref, spliced;
    /* the yardsticks need a rectified pair: a distorted or verged one (EuRoC) is rectified for
     * them into a temporary folder (rp_rectify.hpp), scored against its truth in that frame */
    rprd::Sequence rseq;
    bool rectified = rprd::is_rectified(seq);
    if ((opencv_ref || direct_ref) && !rectified) {
        if (!rect_tmp.make("rigpose_rect")) {
            return 1;
        }
        const std::string &tmpl = rect_tmp.path;
        if (!rprd::rectify_sequence(seq, tmpl, &rseq, &err)) {
            std::fprintf(stderr, "rigpose-realdata: yardsticks: %s\n", err.c_str());
            return 1;
        }
        std::printf("yardsticks: the pair rectified (cv::stereoRectify; fx %.3f, baseline %.4f m) "
                    "in %s (removed at exit)\n",
                    (double)rseq.rig.cam[0].cam.fx, (double)rseq.rig.cam[1].D[0], tmpl.c_str());
        rectified = true;
    }
    const rprd::Sequence &yseq = rseq.img[0].empty() ? seq : rseq;
    std::vector<rprd::Pose> traj, dtraj;
    if (opencv_ref && rectified) {
        bool ok = false;
        try {
            ok = opencv_reference(yseq, &traj);
        } catch (const cv::Exception &e) {
            std::printf("yardstick: OpenCV raised: %s\n", e.what());
        }
        if (ok) {
            ref = rprd::summarise(traj, yseq.truth);
            std::printf("| yardstick: OpenCV frame-to-frame stereo PnP, ATE / path | %.3f %% "
                        "(%.4f m) |\n| yardstick: its RPE / path | %.3f %% |\n"
                        "| yardstick: its scale | %.4f |\n",
                        ref.ate_percent, ref.ate_m, ref.rpe_percent, ref.scale);
        } else {
            std::printf("yardstick: OpenCV stereo odometry failed\n");
            traj.clear();
        }
    }
    if (direct_ref) {
        if (rprd::direct_reference(yseq, dopts, &dtraj, nullptr, &err)) {
            dref = rprd::summarise(dtraj, yseq.truth);
            std::printf("| yardstick 2: dense direct stereo odometry, ATE / path | %.3f %% "
                        "(%.4f m) |\n| yardstick 2: its RPE / path | %.3f %% |\n"
                        "| yardstick 2: its scale | %.4f |\n",
                        dref.ate_percent, dref.ate_m, dref.rpe_percent, dref.scale);
        } else {
            std::printf("%s\n", err.c_str());
            dtraj.clear();
        }
    }
    if (splice > 0 && splice < dtraj.size()) {
        std::vector<rprd::Pose> mix(dtraj.begin(), dtraj.begin() + (long)splice + 1);
        for (size_t j = splice + 1; j < yseq.truth.size(); ++j) {
            mix.push_back(rprd::pose_mul(mix.back(), step_of(yseq.truth, j)));
        }
        spliced = rprd::summarise(mix, yseq.truth);
        std::printf("| yardstick 2 to frame %zu, then the truth's own steps: ATE / path | %.3f %% "
                    "(%.4f m) |\n",
                    splice, spliced.ate_percent, spliced.ate_m);
    }
    if (steps) {
        print_steps(seq, est_pose, traj, dtraj);
    }
    if (!json_out.empty()) {
        FILE *f = std::fopen(json_out.c_str(), "w");
        if (!f) {
            std::fprintf(stderr, "rigpose-realdata: %s: cannot write\n", json_out.c_str());
            return 1;
        }
        const char *n = seq.name.c_str();
        std::fprintf(f,
                     "{\"%s_ate_m\": %.6f, \"%s_ate_percent\": %.6f, \"%s_path_m\": %.4f, "
                     "\"%s_max_err_m\": %.6f, \"%s_rot_rmse_deg\": %.5f, \"%s_rpe_percent\": %.5f, \"%s_frames\": %zu, "
                     "\"%s_frames_lost\": %zu, \"%s_ms_per_frame\": %.3f, \"%s_scale\": %.5f, "
                     "\"%s_unscaled_ate_m\": %.6f, \"%s_scale_weak_share\": %.4f",
                     n, s.ate_m, n, s.ate_percent, n, s.path_m, n, s.max_m, n, s.rot_rmse_deg, n, s.rpe_percent, n,
                     s.frames, n, lost, n, ms, n, s.scale, n, su.ate_m, n,
                     s.frames ? (double)weak / (double)s.frames : 0.0);
        if (rp_pipe_time_offsets(&pipe, off_s, off_sd) == RP_OK) {
            std::fprintf(f, ", \"%s_offset_cam2_ms\": %.4f, \"%s_offset_cam2_sigma_ms\": %.4f", n,
                         1e3 * (double)off_s[1], n, 1e3 * (double)off_sd[1]);
        }
        if (sync_rotation) {
            std::fprintf(f, ", \"%s_sync_rotation_ms\": %.4f, \"%s_sync_rotation_sigma_ms\": %.4f",
                         n, 1e3 * sync_offset_s, n, 1e3 * sync_sigma_s);
        }
        if (pair_shift > 0) {
            std::fprintf(f, ", \"%s_true_offset_cam2_ms\": %.4f", n, 1e3 * true_offset_s);
        }
        if (ref.frames) {
            std::fprintf(f,
                         ", \"%s_opencv_ref_ate_percent\": %.6f, \"%s_opencv_ref_rpe_percent\": "
                         "%.5f, \"%s_opencv_ref_scale\": %.5f, \"%s_opencv_ref_ate_m\": %.6f",
                         n, ref.ate_percent, n, ref.rpe_percent, n, ref.scale, n, ref.ate_m);
        }
        if (dref.frames) {
            std::fprintf(f,
                         ", \"%s_direct_ref_ate_percent\": %.6f, \"%s_direct_ref_rpe_percent\": "
                         "%.5f, \"%s_direct_ref_scale\": %.5f, \"%s_direct_ref_ate_m\": %.6f",
                         n, dref.ate_percent, n, dref.rpe_percent, n, dref.scale, n, dref.ate_m);
        }
        if (spliced.frames) {
            std::fprintf(f, ", \"%s_direct_to%zu_then_truth_ate_percent\": %.6f", n, splice,
                         spliced.ate_percent);
        }
        std::fprintf(f, "}\n");
        std::fclose(f);
    }
    int rc = 0;
    if (check_m >= 0.0 && !(s.ate_m <= check_m)) {
        std::printf("CHECK FAILED: ATE %.4f m > %.4f m\n", s.ate_m, check_m);
        rc = 1;
    }
    if (check_pct >= 0.0 && !(s.ate_percent <= check_pct)) {
        std::printf("CHECK FAILED: ATE %.3f %% > %.3f %% of the path\n", s.ate_percent, check_pct);
        rc = 1;
    }
    if (rc == 0 && (check_m >= 0.0 || check_pct >= 0.0)) {
        std::printf("check passed\n");
    }
    return rc;
}
