/*
 * rigpose-realdata - rigpose's stereo layout on real camera data: a KITTI odometry or EuRoC MAV
 * folder (rp_realdata.hpp: calibration -> a rig of one stereo pair, ground truth in rigpose's
 * conventions) -> the core's image pipeline (rp_pipe.h, layout stereo2: trackers, stereo
 * matching, the pose EKF) -> poses, scored against the ground truth frame by frame:
 * translation error |d_est - d_true| (m) and rotation error (angle of R_est^T R_true), no
 * alignment beyond the shared start (frame 0 is the world in both). The summary gives the
 * absolute trajectory error (ATE: RMSE of the translation errors over the frames) in metres
 * and in percent of the true path's length.
 *
 * Each dataset has its own settings ("profile", printed at start): the EKF's plant noise suits
 * its motion (a car at 10 Hz: smooth, small angular acceleration; a hand-held sensor at 20 Hz:
 * shaking, strong angular acceleration), the tracker's features, grid and pyramid suit its
 * images, the stereo search range suits its baseline and scene depths. Options override them.
 *
 * usage: rigpose-realdata (--kitti DIR | --euroc DIR) [--frames N] [--first K] [--name NAME]
 *            [--quiet] [--json-out FILE] [--check-ate-m X] [--check-ate-percent X]
 *            [--replay-out DIR [--copy-images]] [--no-run] [profile overrides, see --help]
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

#include "rigpose/rp_pipe.h"
#include "rp_direct.hpp"
#include "rp_realdata.hpp"
#include "../../common/rp_cfg_diff.h"
#include "../../common/rp_cv.hpp"

namespace fs = std::filesystem;

namespace {

/* The per-dataset settings of the pipeline. */
struct Profile {
    double q_trans, q_rot; /* EKF plant noise, m^2/s^3 and rad^2/s^3 */
    double sigma_px;       /* measurement noise, px */
    int target;            /* features per camera */
    int levels, win, min_dist, grid_x, grid_y;
    double match_min_depth_m, match_max_depth_m; /* stereo search along the ray */
    int match_half_win;    /* stereo patch half side, px */
    int match_subpix;      /* stereo: 1-D LK iterations after the parabola (0: parabola only) */
    double fb_max_px;      /* tracker's forward-backward tolerance, px */
    double match_min_zncc; /* stereo: lowest accepted patch score */
    double max_depth_m;    /* triangulated landmarks kept up to this depth */
    int min_tracked;       /* re-initialise under this many landmarks */
    int refine;            /* structure EKF per landmark (1) or the first triangulation (0) */
    int iterations;        /* Gauss-Newton iterations of the EKF update */
    double gate_chi2;      /* per-feature Mahalanobis gate */
    double dt_s;           /* nominal frame interval */
};

/* KITTI: a car at 8 m/s, 10 Hz, 1241x376, baseline 0.54 m; near points move tens of pixels a
 * frame (4 pyramid levels), depths 3..80 m. Plant noise: accelerations of a car (about 1 m/s^2,
 * yaw acceleration well under 1 rad/s^2). */
Profile kitti_profile()
{
    Profile p;
    p.q_trans = 1.0;
    p.q_rot = 0.05;
    p.sigma_px = 0.5;
    p.target = 300;
    p.levels = 4;
    p.win = 21;
    p.min_dist = 12;
    p.grid_x = 12;
    p.grid_y = 4;
    p.match_min_depth_m = 2.0;
    p.match_max_depth_m = 100.0;
    p.match_half_win = 4;
    p.match_subpix = 5;
    p.fb_max_px = 1.0;
    p.match_min_zncc = 0.8;
    p.max_depth_m = 80.0;
    p.min_tracked = 80;
    p.refine = 1;
    p.iterations = 3;
    p.gate_chi2 = 13.8;
    p.dt_s = 0.1;
    return p;
}

/* EuRoC MH01: hand-held shaking at 20 Hz, 752x480 with strong radial distortion, baseline
 * 0.11 m, depths 1..15 m. Plant noise: a shaken sensor (accelerations of several m/s^2 and
 * rad/s^2). */
Profile euroc_profile()
{
    Profile p;
    p.q_trans = 4.0;
    p.q_rot = 4.0;
    p.sigma_px = 0.5;
    p.target = 250;
    p.levels = 4;
    p.win = 21;
    p.min_dist = 12;
    p.grid_x = 8;
    p.grid_y = 6;
    p.match_min_depth_m = 0.5;
    p.match_max_depth_m = 30.0;
    p.match_half_win = 4;
    p.match_subpix = 5;
    p.fb_max_px = 1.0;
    p.match_min_zncc = 0.8;
    p.max_depth_m = 30.0;
    p.min_tracked = 60;
    p.refine = 1;
    p.iterations = 3;
    p.gate_chi2 = 13.8;
    p.dt_s = 0.05;
    return p;
}

void print_profile(const char *name, const Profile &p)
{
    std::printf("profile %s: EKF q_trans %g m^2/s^3, q_rot %g rad^2/s^3, sigma %g px; "
                "tracker %d features, %d levels, window %d, min dist %d px, grid %dx%d; "
                "stereo search %g..%g m, patch %dx%d, ZNCC >= %g, landmarks to %g m, re-init under %d\n",
                name, p.q_trans, p.q_rot, p.sigma_px, p.target, p.levels, p.win, p.min_dist,
                p.grid_x, p.grid_y, p.match_min_depth_m, p.match_max_depth_m, 2 * p.match_half_win + 1,
                2 * p.match_half_win + 1, p.match_min_zncc, p.max_depth_m,
                p.min_tracked);
}

rp_status_t make_cfg(const Profile &pr, rp_pipe_cfg_t *cfg)
{
    rp_status_t st = rp_pipe_default_cfg(RP_PIPE_STEREO2, cfg);
    if (st != RP_OK) {
        return st;
    }
    /* the rig: camera 0 left (cam1), camera 1 right */
    cfg->stereo.n_pairs = 1;
    cfg->stereo.pair_a[0] = 0;
    cfg->stereo.pair_b[0] = 1;
    cfg->stereo.ekf.q_trans = (rp_real)pr.q_trans;
    cfg->stereo.ekf.q_rot = (rp_real)pr.q_rot;
    cfg->stereo.ekf.sigma_px = (rp_real)pr.sigma_px;
    cfg->stereo.max_depth_m = (rp_real)pr.max_depth_m;
    cfg->stereo.min_tracked = (uint16_t)pr.min_tracked;
    cfg->stereo.refine_structure = (uint8_t)pr.refine;
    cfg->stereo.ekf.iterations = (uint8_t)pr.iterations;
    cfg->stereo.ekf.gate_chi2 = (rp_real)pr.gate_chi2;
    cfg->stereo.default_dt_s = (rp_real)pr.dt_s;
    cfg->track.target = (uint16_t)pr.target;
    cfg->track.topup_below = (uint16_t)(pr.target * 4 / 5);
    cfg->track.levels = (uint8_t)pr.levels;
    cfg->track.win = (uint8_t)pr.win;
    cfg->track.min_dist = (uint16_t)pr.min_dist;
    cfg->track.grid_x = (uint8_t)pr.grid_x;
    cfg->track.grid_y = (uint8_t)pr.grid_y;
    cfg->track.cell_cap = 0;
    cfg->smatch.min_depth_m = (rp_real)pr.match_min_depth_m;
    cfg->smatch.max_depth_m = (rp_real)pr.match_max_depth_m;
    cfg->smatch.half_win = (uint8_t)pr.match_half_win;
    cfg->smatch.subpix_iter = (uint8_t)pr.match_subpix;
    cfg->track.fb_max_q16 = (uint32_t)std::lround(pr.fb_max_px * 65536.0);
    cfg->smatch.min_zncc_q15 = (int16_t)std::lround(pr.match_min_zncc * 32767.0);
    return RP_OK;
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
bool write_replay(const std::string &out, const rprd::Sequence &seq, const Profile &pr,
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
                         (int)std::lround(1.0 / pr.dt_s), (double)c.cam.fx, (double)c.cam.fy,
                         (double)c.cam.cx, (double)c.cam.cy, (double)c.cam.k1, (double)c.cam.k2,
                         (double)c.cam.p1, (double)c.cam.p2, (double)c.cam.k3, (double)c.D[0],
                         (double)c.D[1], (double)c.D[2], (double)c.R[0], (double)c.R[1],
                         (double)c.R[2], (double)c.R[3], (double)c.R[4], (double)c.R[5],
                         (double)c.R[6], (double)c.R[7], (double)c.R[8]);
        }
        std::fprintf(fy,
                     "\nestimator:\n  method: stereo2\n  pairs: [[left, right]]\n"
                     "  sigma_px: %g\n  q_trans: %g\n  q_rot: %g\n  min_tracked: %d\n"
                     "  max_depth_m: %g\n  default_dt_s: %g\n\n"
                     "tracker:\n  target: %d\n  levels: %d\n  win: %d\n  min_dist: %d\n"
                     "  grid: [%d, %d]\n",
                     pr.sigma_px, pr.q_trans, pr.q_rot, pr.min_tracked, pr.max_depth_m, pr.dt_s,
                     pr.target, pr.levels, pr.win, pr.min_dist, pr.grid_x, pr.grid_y);
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
        "  --frames N           N frames (default: all)\n"
        "  --first K            start at frame K (frames, not file lines: EuRoC counts the\n"
        "                       timestamps both cameras list; its left camera is the world)\n"
        "  --name NAME          prefix of the JSON figures (default kitti00 / euroc_mh01)\n"
        "  --quiet              no per-frame lines\n"
        "  --json-out FILE      write the figures as one flat JSON object\n"
        "  --check-ate-m X      exit 1 unless the ATE is at most X metres\n"
        "  --check-ate-percent X  exit 1 unless the ATE is at most X %% of the path\n"
        "  --replay-out DIR     write a replay folder (frames.csv, truth.csv, rig.yaml); image\n"
        "                       paths relative to DIR, or copies with --copy-images\n"
        "  --no-run             only load (and write the replay folder)\n"
        "  --opencv-ref         also run plain OpenCV stereo odometry (rectified pairs only)\n"
        "                       as a yardstick of the ground truth\n"
        "  --direct-ref         also run dense direct stereo odometry (rp_direct.hpp:\n"
        "                       SGBM depth + photometric alignment, no features; rectified\n"
        "                       pairs only, about 1 s per frame) as a second yardstick\n"
        "  --steps              print each frame-to-frame step (length, rotation, direction)\n"
        "                       of the truth, rigpose and the yardsticks run\n"
        "  --direct-rows A,B    the direct yardstick uses image rows A..B-1 only (e.g. the\n"
        "                       road below the horizon, or the scene above it)\n"
        "  --splice K           with --direct-ref: also score the yardstick's steps up to\n"
        "                       frame K followed by the truth's own steps (what an estimator\n"
        "                       exact from frame K on but true to the images before scores)\n"
        "profile overrides: --q-trans Q --q-rot Q --sigma-px S --features N --levels L --win W\n"
        "  --min-dist D --grid X,Y --max-depth M --match-depth MIN,MAX --match-win H\n"
        "  --match-zncc Z --match-subpix N --fb-max PX --min-tracked N --refine 0|1\n"
        "  --iterations N --gate CHI2\n");
}

}  // namespace

int main(int argc, char **argv)
{
    std::string kitti, euroc, name, json_out, replay_out;
    size_t frames = 0, first = 0;
    rprd::LoadOpts lo;
    bool quiet = false, copy_images = false, no_run = false, opencv_ref = false;
    bool direct_ref = false, steps = false;
    size_t splice = 0;
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
        } else if (a == "--steps") {
            steps = true;
        } else if (!has_val) {
            std::fprintf(stderr, "rigpose-realdata: %s: unknown option or missing value\n",
                         a.c_str());
            usage(stderr);
            return 2;
        } else if (a == "--kitti") {
            kitti = argv[++i];
        } else if (a == "--euroc") {
            euroc = argv[++i];
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
        } else if (a == "--truth") {
            lo.truth = argv[++i];
        } else if (a == "--name") {
            name = argv[++i];
        } else if (a == "--json-out") {
            json_out = argv[++i];
        } else if (a == "--replay-out") {
            replay_out = argv[++i];
        } else if (a == "--direct-rows") {
            if (std::sscanf(argv[++i], "%d,%d", &dopts.row_min, &dopts.row_max) != 2 ||
                dopts.row_min < 0 || dopts.row_max <= dopts.row_min) {
                std::fprintf(stderr, "rigpose-realdata: --direct-rows A,B with 0 <= A < B\n");
                return 2;
            }
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
    seq.name = !name.empty() ? name : (is_kitti ? "kitti00" : "euroc_mh01");
    Profile pr = is_kitti ? kitti_profile() : euroc_profile();
    for (const auto &o : over) {
        const char *v = o.second.c_str();
        int n1 = 0, n2 = 0;
        double d1 = 0, d2 = 0;
        if (o.first == "--q-trans") {
            pr.q_trans = std::atof(v);
        } else if (o.first == "--q-rot") {
            pr.q_rot = std::atof(v);
        } else if (o.first == "--sigma-px") {
            pr.sigma_px = std::atof(v);
        } else if (o.first == "--features") {
            pr.target = std::atoi(v);
        } else if (o.first == "--levels") {
            pr.levels = std::atoi(v);
        } else if (o.first == "--win") {
            pr.win = std::atoi(v);
        } else if (o.first == "--min-dist") {
            pr.min_dist = std::atoi(v);
        } else if (o.first == "--min-tracked") {
            pr.min_tracked = std::atoi(v);
        } else if (o.first == "--refine") {
            pr.refine = std::atoi(v);
        } else if (o.first == "--iterations") {
            pr.iterations = std::atoi(v);
        } else if (o.first == "--gate") {
            pr.gate_chi2 = std::atof(v);
        } else if (o.first == "--match-subpix") {
            pr.match_subpix = std::atoi(v);
        } else if (o.first == "--fb-max") {
            pr.fb_max_px = std::atof(v);
        } else if (o.first == "--match-win") {
            pr.match_half_win = std::atoi(v);
        } else if (o.first == "--match-zncc") {
            pr.match_min_zncc = std::atof(v);
        } else if (o.first == "--max-depth") {
            pr.max_depth_m = std::atof(v);
        } else if (o.first == "--grid" && std::sscanf(v, "%d,%d", &n1, &n2) == 2) {
            pr.grid_x = n1;
            pr.grid_y = n2;
        } else if (o.first == "--match-depth" && std::sscanf(v, "%lf,%lf", &d1, &d2) == 2) {
            pr.match_min_depth_m = d1;
            pr.match_max_depth_m = d2;
        } else {
            std::fprintf(stderr, "rigpose-realdata: %s %s: unknown option or bad value\n",
                         o.first.c_str(), v);
            return 2;
        }
    }
    const rp_camera_t &c0 = seq.rig.cam[0].cam;
    std::printf("%s: %zu frames from frame %zu of %s; %ux%u, fx %.3f, baseline %.4f m\n", seq.name.c_str(),
                seq.utime.size(), first, seq.dir.c_str(), (unsigned)c0.width, (unsigned)c0.height,
                (double)c0.fx,
                std::sqrt((double)(seq.rig.cam[1].D[0] * seq.rig.cam[1].D[0] +
                                   seq.rig.cam[1].D[1] * seq.rig.cam[1].D[1] +
                                   seq.rig.cam[1].D[2] * seq.rig.cam[1].D[2])));
    print_profile(is_kitti ? "kitti" : "euroc", pr);
    if (!replay_out.empty()) {
        if (!write_replay(replay_out, seq, pr, copy_images)) {
            return 1;
        }
        std::printf("replay folder: %s\n", replay_out.c_str());
    }
    if (no_run) {
        return 0;
    }

    static rp_pipe_t pipe; /* large (trackers' pyramids): static */
    rp_pipe_cfg_t cfg;
    rp_status_t st = make_cfg(pr, &cfg);
    if (st == RP_OK) {
        /* the per-format profile (README.md; its removal is a later issue), the rig's numbering
         * (0 left, 1 right) and --set options: one line per change from the core's default */
        char why[64];
        std::snprintf(why, sizeof why, "profile %s", is_kitti ? "kitti" : "euroc");
        const char *const table[][2] = {{"stereo.pair_", "the dataset's numbering: 0 left, 1 right"},
                                        {"", why},
                                        {nullptr, nullptr}};
        (void)rp_cfg_diff_print(stderr, "rigpose-realdata", &cfg, table);
        st = rp_pipe_init(&pipe, &seq.rig, &cfg);
    }
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
    size_t lost = 0, reinit = 0;
    for (size_t j = 0; j < seq.utime.size(); ++j) {
        cv::Mat im[2];
        rp_image_t v[2];
        const rp_image_t *ptr[2];
        for (int k = 0; k < 2; ++k) {
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
        st = rp_pipe_step(&pipe, ptr, 2, seq.utime[j], &est);
        step_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        double p[6];
        for (int i = 0; i < 6; ++i) {
            p[i] = (double)est.p[i];
        }
        if (j == 0 && st != RP_OK) {
            std::fprintf(stderr, "rigpose-realdata: first frame: %s\n", rp_status_str(st));
        }
        lost += (est.flags & RP_EST_LOST) ? 1u : 0u;
        reinit += (est.flags & RP_EST_REINIT) ? 1u : 0u;
        const rprd::FrameErr e = rprd::frame_error(p, seq.truth[j]);
        est_pose.push_back(rprd::pose_from_vec(p));
        if (!quiet) {
            std::printf("%5zu %9.4f %9.4f %9.4f %9.4f %9.4f %9.4f %8.4f %7.3f %4u %4u %4u %s%s%s\n",
                        j, p[0], p[1], p[2], seq.truth[j].t[0], seq.truth[j].t[1],
                        seq.truth[j].t[2], e.trans_m, e.rot_rad * 180.0 / M_PI,
                        (unsigned)est.n_used[0], (unsigned)est.n_used[1],
                        (unsigned)est.n_landmarks, flag_text(est.flags).c_str(),
                        st == RP_OK ? "" : " ", st == RP_OK ? "" : rp_status_str(st));
        }
    }
    const rprd::Summary s = rprd::summarise(est_pose, seq.truth);
    const double ms = 1e3 * step_s / (double)s.frames;
    std::printf("\n%s, %zu frames, stereo2 through rp_pipe (%s):\n", seq.name.c_str(), s.frames,
                is_kitti ? "KITTI rectified pair" : "EuRoC cam0/cam1, distorted");
    std::printf("| figure | value |\n|---|---|\n");
    std::printf("| true path length | %.3f m |\n", s.path_m);
    std::printf("| ATE (RMSE, no alignment) | %.4f m |\n", s.ate_m);
    std::printf("| ATE / path | %.3f %% |\n", s.ate_percent);
    std::printf("| largest / final error | %.4f m / %.4f m |\n", s.max_m, s.final_m);
    std::printf("| rotation error (RMSE) | %.3f deg |\n", s.rot_rmse_deg);
    std::printf("| frame-to-frame drift (RPE / path) | %.3f %% |\n", s.rpe_percent);
    std::printf("| frames lost / re-initialised | %zu / %zu |\n", lost, reinit);
    std::printf("| pipeline time per frame set | %.2f ms |\n", ms);
    rprd::Summary ref, dref, spliced;
    const bool rectified = is_kitti;
    std::vector<rprd::Pose> traj, dtraj;
    if (opencv_ref && rectified) {
        bool ok = false;
        try {
            ok = opencv_reference(seq, &traj);
        } catch (const cv::Exception &e) {
            std::printf("yardstick: OpenCV raised: %s\n", e.what());
        }
        if (ok) {
            ref = rprd::summarise(traj, seq.truth);
            std::printf("| yardstick: OpenCV frame-to-frame stereo PnP, ATE / path | %.3f %% "
                        "(%.4f m) |\n| yardstick: its RPE / path | %.3f %% |\n",
                        ref.ate_percent, ref.ate_m, ref.rpe_percent);
        } else {
            std::printf("yardstick: OpenCV stereo odometry failed\n");
            traj.clear();
        }
    }
    if (direct_ref) {
        if (rprd::direct_reference(seq, dopts, &dtraj, nullptr, &err)) {
            dref = rprd::summarise(dtraj, seq.truth);
            std::printf("| yardstick 2: dense direct stereo odometry, ATE / path | %.3f %% "
                        "(%.4f m) |\n| yardstick 2: its RPE / path | %.3f %% |\n",
                        dref.ate_percent, dref.ate_m, dref.rpe_percent);
        } else {
            std::printf("%s\n", err.c_str());
            dtraj.clear();
        }
    }
    if (splice > 0 && splice < dtraj.size()) {
        std::vector<rprd::Pose> mix(dtraj.begin(), dtraj.begin() + (long)splice + 1);
        for (size_t j = splice + 1; j < seq.truth.size(); ++j) {
            mix.push_back(rprd::pose_mul(mix.back(), step_of(seq.truth, j)));
        }
        spliced = rprd::summarise(mix, seq.truth);
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
                     "\"%s_frames_lost\": %zu, \"%s_ms_per_frame\": %.3f",
                     n, s.ate_m, n, s.ate_percent, n, s.path_m, n, s.max_m, n, s.rot_rmse_deg, n, s.rpe_percent, n,
                     s.frames, n, lost, n, ms);
        if (ref.frames) {
            std::fprintf(f,
                         ", \"%s_opencv_ref_ate_percent\": %.6f, \"%s_opencv_ref_rpe_percent\": "
                         "%.5f",
                         n, ref.ate_percent, n, ref.rpe_percent);
        }
        if (dref.frames) {
            std::fprintf(f,
                         ", \"%s_direct_ref_ate_percent\": %.6f, \"%s_direct_ref_rpe_percent\": "
                         "%.5f",
                         n, dref.ate_percent, n, dref.rpe_percent);
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
