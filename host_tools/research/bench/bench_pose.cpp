/*
 * bench_pose.cpp - rigpose's benchmark program (`make bench`).
 *
 * The program is a list of sections. Each section measures something and adds named figures
 * (numbers only) to one map; at the end the map is written as one flat JSON object
 * (build/bench.json, docs/design.md "Benchmarks") and every section prints its own readable table.
 * A figure that could not be measured (no frame timed, non-finite value, a peer that never
 * produced a pose) is left out, never faked. To add a benchmark: write a section function and
 * add it to kSections.
 *
 * Section "stereo4": rigpose's stereo4 estimator (two back-to-back stereo pairs, one pose EKF)
 * against two peers a user would reach for instead, on the same simulated frames (rp_sim, the
 * paper's Table 1 protocol) in the same run:
 *   - OpenGV's generalised absolute pose for multi-camera rigs: gp3p inside RANSAC
 *     (sac::Ransac<AbsolutePoseSacProblem>, GP3P), then absolute_pose::optimize_nonlinear over
 *     the inliers of all cameras;
 *   - OpenCV's cv::solvePnP (SOLVEPNP_ITERATIVE, warm-started from the same camera's previous
 *     estimate) per camera, each camera's pose mapped to the rig (cam1) pose.
 * Fairness: the peers get the information rigpose has. Their 3-D points are triangulated by
 * the core's rp_stereo_triangulate from the frame-0 matches of each stereo pair (same epipolar
 * and reprojection checks as rigpose's defaults), expressed in the world (= cam1 at frame 0);
 * every frame they get the same noisy pixels of those points in the same 4 stereo cameras.
 * Unlike rigpose they do not re-triangulate later: points entering the view after frame 0 are
 * not used by them (over 100 frames the rig keeps most of the frame-0 points in view).
 * Timing: std::chrono::steady_clock around each method's work on one frame, frame generation
 * excluded; methods interleaved frame by frame; one thread (cv::setNumThreads(1)). Each
 * method's cost per frame is its total time over the sequence divided by the frames:
 * rigpose's includes its frame-0 triangulation and any re-initialisation, the peers' include
 * the frame-0 triangulation of their structure and building their own inputs (bearing vectors,
 * point lists) from the frame set.
 * Errors: mean absolute error of [tx ty tz alpha beta gamma] of cam1 over frames 1.. of every
 * run (frame 0 defines the world), angles wrapped to [-pi, pi]. When a method fails on a frame
 * its previous pose stands (and counts as a failure).
 *
 * Section "gc": rigpose's generalised-camera filter (the four single cameras cam1..cam4 of the
 * non-overlapping layout, no stereo) against OpenGV's generalised absolute pose (the same
 * gp3p + RANSAC + optimize_nonlinear as above) on the same frames, same run. OpenGV needs 3-D
 * points and this layout has no stereo, so it is given the 2-D/3-D correspondences the gc
 * filter's own map gives: before each frame, every mature landmark gc holds (its world
 * position as gc estimated it up to the previous frame) paired with this frame's pixel of the
 * same id. OpenGV's time includes building that list. For reference a third row gives OpenGV
 * the true 3-D points of the same features (an oracle structure no real system has).
 */
#include <opengv/absolute_pose/NoncentralAbsoluteAdapter.hpp>
#include <opengv/absolute_pose/methods.hpp>
#include <opengv/sac/Ransac.hpp>
#include <opengv/sac_problems/absolute_pose/AbsolutePoseSacProblem.hpp>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "rigpose/rp_status.h"
#include "rp_sim.h"
#include "rigpose/rp_camera.h"
#include "rigpose/rp_rig.h"
#include "rigpose/rp_rot.h"
#include "rigpose/rp_stereo.h"
#include "rigpose/rp_vo_gc.h"
#include "rigpose/rp_vo_stereo.h"

namespace {

/* ---- figures: one flat map of named numbers ----------------------------------------------- */

class Figures {
public:
    /* Record a figure; a non-finite value is not a measurement and is left out. */
    void set(const std::string &name, double value)
    {
        if (!std::isfinite(value)) return;
        for (auto &kv : items_) {
            if (kv.first == name) { kv.second = value; return; }
        }
        items_.emplace_back(name, value);
    }
    /* rigpose / peer, only when both are measured and the peer's is non-zero. */
    void set_ratio(const std::string &name, double num, double den)
    {
        if (std::isfinite(num) && std::isfinite(den) && den != 0.0) set(name, num / den);
    }
    bool write_json(const std::string &path) const
    {
        const std::string tmp = path + ".tmp";
        FILE *f = std::fopen(tmp.c_str(), "w");
        if (!f) return false;
        std::fprintf(f, "{");
        for (size_t i = 0; i < items_.size(); ++i) {
            std::fprintf(f, "%s\n  \"%s\": %.9g", i ? "," : "", items_[i].first.c_str(),
                         items_[i].second);
        }
        std::fprintf(f, "\n}\n");
        const bool ok = std::fclose(f) == 0;
        return ok && std::rename(tmp.c_str(), path.c_str()) == 0;
    }
    size_t size() const { return items_.size(); }

private:
    std::vector<std::pair<std::string, double>> items_;
};

struct BenchOpts {
    uint32_t runs = 20;
    uint32_t frames = 100;
    uint64_t seed = 1;
    double noise_px = 0.5;
    std::string out = "build/bench.json";
    std::string only; /* run only this section (empty: all) */
    double opengv_thr_px = 0.0; /* OpenGV RANSAC threshold, pixels (0: the default rule) */
};

/* ---- per-method accumulators --------------------------------------------------------------- */

struct MethodStats {
    std::string label;
    double time_us = 0.0;   /* total estimation time */
    uint64_t timed_frames = 0;
    double feats = 0.0;     /* total features (observations) used */
    uint64_t feat_frames = 0;
    double err[6] = {0, 0, 0, 0, 0, 0};
    uint64_t err_frames = 0;
    uint64_t fails = 0;
    double extra = 0.0;     /* method-specific count (OpenGV: RANSAC inliers) */

    explicit MethodStats(const char *l) : label(l) {}
    double us_per_frame() const { return timed_frames ? time_us / timed_frames : NAN; }
    double feats_per_frame() const { return feat_frames ? feats / feat_frames : NAN; }
    double mean_err(int i) const { return err_frames ? err[i] / err_frames : NAN; }
    void add_error(const double p[6], const double truth[6])
    {
        for (int i = 0; i < 6; ++i) {
            double e = p[i] - truth[i];
            if (i >= 3) e = std::remainder(e, 2.0 * M_PI); /* wrapped to [-pi, pi] */
            err[i] += std::fabs(e);
        }
        ++err_frames;
    }
    /* One frame of a rigpose estimator: its time; from frame 1 on its error, the features its
     * update used in cams, and a failure if it did not track. */
    void add_rigpose_frame(double us, uint32_t j, rp_status_t st, const rp_estimate_t &est,
                           const std::vector<int> &cams, const double truth[6])
    {
        time_us += us;
        ++timed_frames;
        if (j == 0) return;
        double p[6];
        for (int i = 0; i < 6; ++i) p[i] = (double)est.p[i];
        add_error(p, truth);
        uint32_t used = 0;
        for (int c : cams) used += est.n_used[c];
        feats += used;
        ++feat_frames;
        if (st != RP_OK || (est.flags & RP_EST_LOST)) ++fails;
    }
};

using Clock = std::chrono::steady_clock;
static double us_since(Clock::time_point t0)
{
    return std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
}

/* ---- pose helpers (row-major 3x3 as in rp_rot.h) -------------------------------------------- */

static void pose_from_R_d(const Eigen::Matrix3d &R, const Eigen::Vector3d &d, double p[6])
{
    rp_real Rr[9], abg[3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) Rr[3 * r + c] = (rp_real)R(r, c);
    rp_rot_to_angles(Rr, abg);
    for (int i = 0; i < 3; ++i) { p[i] = d[i]; p[3 + i] = (double)abg[i]; }
}

static Eigen::Matrix3d rig_R(const rp_rig_t &rig, int k)
{
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) R(r, c) = (double)rig.cam[k].R[3 * r + c];
    return R;
}

static Eigen::Vector3d rig_D(const rp_rig_t &rig, int k)
{
    return Eigen::Vector3d((double)rig.cam[k].D[0], (double)rig.cam[k].D[1],
                           (double)rig.cam[k].D[2]);
}

/* ---- the peers' structure: frame-0 stereo triangulation by the core ------------------------ */

struct Landmarks {
    std::unordered_map<uint32_t, Eigen::Vector3d> M; /* id -> world point */
};

/* Triangulate the matches (ids in both cameras) of each pair at frame 0, where the world is
 * cam1's frame, with rigpose's own checks (vo_cfg: epipolar band, depth range, reprojection). */
static void build_landmarks(const rp_rig_t &rig, const rp_vo_stereo_cfg_t &vo_cfg,
                            const rp_frameset_t &fs, Landmarks &lm)
{
    lm.M.clear();
    for (int pi = 0; pi < vo_cfg.n_pairs; ++pi) {
        const uint8_t a = vo_cfg.pair_a[pi], b = vo_cfg.pair_b[pi];
        rp_stereo_pair_t sp;
        if (rp_stereo_pair_init(&rig, a, b, &sp) != RP_OK) continue;
        std::unordered_map<uint32_t, int> in_b;
        in_b.reserve(fs.n[b] * 2u);
        for (int i = 0; i < fs.n[b]; ++i) in_b[fs.f[b][i].id] = i;
        const Eigen::Matrix3d Ra = rig_R(rig, a);
        const Eigen::Vector3d Da = rig_D(rig, a);
        for (int i = 0; i < fs.n[a]; ++i) {
            const rp_feat_t &fa = fs.f[a][i];
            auto it = in_b.find(fa.id);
            if (it == in_b.end() || lm.M.count(fa.id)) continue;
            const rp_feat_t &fb = fs.f[b][it->second];
            rp_real dist = 0, P[3], reproj = 0;
            if (rp_stereo_epipolar_px(&rig, &sp, fa.uv, fb.uv, &dist) != RP_OK ||
                dist > vo_cfg.max_epipolar_px)
                continue;
            if (rp_stereo_triangulate(&rig, &sp, fa.uv, fb.uv, P, &reproj) != RP_OK) continue;
            if (reproj > vo_cfg.max_reproj_px || P[2] < vo_cfg.min_depth_m ||
                P[2] > vo_cfg.max_depth_m)
                continue;
            const Eigen::Vector3d Pa((double)P[0], (double)P[1], (double)P[2]);
            lm.M.emplace(fa.id, Da + Ra * Pa); /* world = cam1 at frame 0 */
        }
    }
}

/* ---- peer 1: OpenGV, gp3p + RANSAC, then non-linear optimisation over all cameras --------- */

struct OpenGVPeer {
    const rp_rig_t *rig = nullptr;
    std::vector<int> cams;
    opengv::translations_t offsets; /* camera positions in the viewpoint (cam1) frame */
    opengv::rotations_t rotations;  /* camera-to-viewpoint rotations */
    double threshold = 0.0;         /* RANSAC threshold, 1 - cos(angle) */
    double ransac_us = 0.0, nonlin_us = 0.0; /* time split: RANSAC, non-linear optimisation */
    uint64_t ransac_iters = 0;
    int max_iterations = 1000;
    double probability = 0.99;
    /* scratch, reused across frames */
    opengv::bearingVectors_t bearings;
    opengv::points_t points;
    std::vector<int> cam_of;

    void init(const rp_rig_t *r, const std::vector<int> &c, double thr_px)
    {
        rig = r;
        cams = c;
        offsets.clear();
        rotations.clear();
        for (int k : cams) {
            offsets.push_back(rig_D(*rig, k));
            rotations.push_back(rig_R(*rig, k));
        }
        const double f = (double)rig->cam[cams[0]].cam.fx;
        threshold = 1.0 - std::cos(std::atan(thr_px / f));
    }

    /* Estimate cam1's pose; false (pose untouched) on failure. */
    bool estimate(const rp_frameset_t &fs, const Landmarks &lm, double p[6], size_t *n_corr,
                  size_t *n_inl)
    {
        bearings.clear();
        points.clear();
        cam_of.clear();
        for (size_t ci = 0; ci < cams.size(); ++ci) {
            const int k = cams[ci];
            for (int i = 0; i < fs.n[k]; ++i) {
                auto it = lm.M.find(fs.f[k][i].id);
                if (it == lm.M.end()) continue;
                rp_real xn[2];
                if (rp_cam_unproject(&rig->cam[k].cam, fs.f[k][i].uv, xn) != RP_OK) continue;
                bearings.push_back(Eigen::Vector3d((double)xn[0], (double)xn[1], 1.0).normalized());
                points.push_back(it->second);
                cam_of.push_back((int)ci);
            }
        }
        *n_corr = bearings.size();
        *n_inl = 0;
        if (bearings.size() < 6) return false;
        opengv::absolute_pose::NoncentralAbsoluteAdapter adapter(bearings, cam_of, points,
                                                                 offsets, rotations);
        using Problem = opengv::sac_problems::absolute_pose::AbsolutePoseSacProblem;
        opengv::sac::Ransac<Problem> ransac;
        /* randomSeed = false: a fixed seed, so runs are reproducible */
        ransac.sac_model_ = std::make_shared<Problem>(adapter, Problem::GP3P, false);
        ransac.threshold_ = threshold;
        ransac.max_iterations_ = max_iterations;
        ransac.probability_ = probability;
        Clock::time_point t0 = Clock::now();
        const bool found = ransac.computeModel();
        ransac_us += us_since(t0);
        ransac_iters += (uint64_t)std::max(ransac.iterations_, 0);
        if (!found || ransac.inliers_.size() < 6) return false;
        t0 = Clock::now();
        adapter.sett(ransac.model_coefficients_.col(3));
        adapter.setR(ransac.model_coefficients_.block<3, 3>(0, 0));
        const opengv::transformation_t T =
            opengv::absolute_pose::optimize_nonlinear(adapter, ransac.inliers_);
        nonlin_us += us_since(t0);
        if (!T.allFinite()) return false;
        /* T = [R | t]: the viewpoint (cam1) in the world, R viewpoint-to-world. */
        pose_from_R_d(T.block<3, 3>(0, 0), T.col(3), p);
        *n_inl = ransac.inliers_.size();
        return true;
    }
};

/* ---- peer 2: OpenCV solvePnP per camera, warm-started --------------------------------------- */

struct OpenCVPeer {
    const rp_rig_t *rig = nullptr;
    std::vector<int> cams;
    std::vector<cv::Mat> K, dist, rvec, tvec; /* per camera; rvec/tvec: the warm start */
    std::vector<cv::Point3d> obj;
    std::vector<cv::Point2d> img;

    /* Warm start at frame 0: each camera's pose in the world (= cam1 at frame 0). */
    void init(const rp_rig_t *r, const std::vector<int> &c)
    {
        rig = r;
        cams = c;
        K.clear(); dist.clear(); rvec.clear(); tvec.clear();
        for (int k : cams) {
            const rp_camera_t &cam = rig->cam[k].cam;
            K.push_back((cv::Mat_<double>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1));
            dist.push_back((cv::Mat_<double>(1, 5) << cam.k1, cam.k2, cam.p1, cam.p2, cam.k3));
            /* camera k in the world: R_cw = R_k^T, t = -R_k^T D_k */
            const Eigen::Matrix3d Rcw = rig_R(*rig, k).transpose();
            const Eigen::Vector3d t = -Rcw * rig_D(*rig, k);
            cv::Mat Rm(3, 3, CV_64F), rv, tv = (cv::Mat_<double>(3, 1) << t[0], t[1], t[2]);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) Rm.at<double>(i, j) = Rcw(i, j);
            cv::Rodrigues(Rm, rv);
            rvec.push_back(rv);
            tvec.push_back(tv);
        }
    }

    /* Per camera: solvePnP, then the rig pose it implies. ok[ci] false when the camera had too
     * few points or failed (its warm start is then kept). */
    void estimate(const rp_frameset_t &fs, const Landmarks &lm, std::vector<Eigen::Matrix3d> &Rj,
                  std::vector<Eigen::Vector3d> &dj, std::vector<char> &ok, size_t *n_corr)
    {
        *n_corr = 0;
        for (size_t ci = 0; ci < cams.size(); ++ci) {
            const int k = cams[ci];
            ok[ci] = 0;
            obj.clear();
            img.clear();
            for (int i = 0; i < fs.n[k]; ++i) {
                auto it = lm.M.find(fs.f[k][i].id);
                if (it == lm.M.end()) continue;
                obj.emplace_back(it->second[0], it->second[1], it->second[2]);
                img.emplace_back((double)fs.f[k][i].uv[0], (double)fs.f[k][i].uv[1]);
            }
            *n_corr += obj.size();
            if (obj.size() < 6) continue;
            cv::Mat rv = rvec[ci].clone(), tv = tvec[ci].clone();
            if (!cv::solvePnP(obj, img, K[ci], dist[ci], rv, tv, true, cv::SOLVEPNP_ITERATIVE))
                continue;
            if (!cv::checkRange(rv) || !cv::checkRange(tv)) continue;
            rvec[ci] = rv;
            tvec[ci] = tv;
            cv::Mat Rm;
            cv::Rodrigues(rv, Rm);
            Eigen::Matrix3d Rcw;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) Rcw(i, j) = Rm.at<double>(i, j);
            const Eigen::Vector3d t(tv.at<double>(0), tv.at<double>(1), tv.at<double>(2));
            /* camera k in the world: R_wk = R_cw^T = R_j R_k, c_k = -R_cw^T t = d_j + R_j D_k */
            const Eigen::Matrix3d Rwk = Rcw.transpose();
            Rj[ci] = Rwk * rig_R(*rig, k).transpose();
            dj[ci] = -Rwk * t - Rj[ci] * rig_D(*rig, k);
            ok[ci] = 1;
        }
    }
};

/* Mean of rig poses: translations averaged, rotations by the normalised sum of sign-aligned
 * quaternions (chordal mean; the per-camera estimates are close to each other). */
static bool mean_pose(const std::vector<Eigen::Matrix3d> &R, const std::vector<Eigen::Vector3d> &d,
                      const std::vector<char> &ok, double p[6])
{
    Eigen::Vector4d qs = Eigen::Vector4d::Zero(), q0 = Eigen::Vector4d::Zero();
    Eigen::Vector3d ds = Eigen::Vector3d::Zero();
    int n = 0;
    for (size_t i = 0; i < R.size(); ++i) {
        if (!ok[i]) continue;
        const Eigen::Quaterniond q(R[i]);
        Eigen::Vector4d v(q.w(), q.x(), q.y(), q.z());
        if (n == 0) q0 = v;
        if (v.dot(q0) < 0) v = -v;
        qs += v;
        ds += d[i];
        ++n;
    }
    if (n == 0) return false;
    qs.normalize();
    const Eigen::Quaterniond q(qs[0], qs[1], qs[2], qs[3]);
    pose_from_R_d(q.toRotationMatrix(), ds / n, p);
    return true;
}

/* ---- section: stereo4 vs OpenGV and OpenCV -------------------------------------------------- */

static void print_row(const MethodStats &m)
{
    std::printf("  %-34s %9.1f %9.1f  %.5f %.5f %.5f  %.5f %.5f %.5f  %6llu\n", m.label.c_str(),
                m.us_per_frame(), m.feats_per_frame(), m.mean_err(0), m.mean_err(1),
                m.mean_err(2), m.mean_err(3), m.mean_err(4), m.mean_err(5),
                (unsigned long long)m.fails);
}

static void put_method(Figures &fig, const std::string &prefix, const MethodStats &m)
{
    static const char *const names[6] = {"tx", "ty", "tz", "alpha", "beta", "gamma"};
    fig.set(prefix + "_us_per_frame", m.us_per_frame());
    fig.set(prefix + "_feats_per_frame", m.feats_per_frame());
    for (int i = 0; i < 6; ++i) fig.set(prefix + "_" + names[i] + "_err", m.mean_err(i));
}

static int section_stereo4(const BenchOpts &o, Figures &fig)
{
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.n_frames = o.frames;
    cfg.noise_px = o.noise_px;

    rp_vo_stereo_cfg_t vcfg = rp_vo_stereo_default_cfg();
    vcfg.n_pairs = 2;
    vcfg.pair_a[0] = RP_SIM_CAM1;
    vcfg.pair_b[0] = RP_SIM_CAM1B;
    vcfg.pair_a[1] = RP_SIM_CAM3;
    vcfg.pair_b[1] = RP_SIM_CAM3B;
    vcfg.ekf.sigma_px = (rp_real)o.noise_px;
    /* rigpose-sim's feature-level setting (its Table 1 figures), not the core's default 3,
     * which is chosen on rendered images (config/README.md) */
    const rp_vo_stereo_cfg_t core = rp_vo_stereo_default_cfg();
    vcfg.ekf.q_trans = (rp_real)1.0;
    vcfg.ekf.q_rot = (rp_real)1.0;
    std::fprintf(stderr,
                 "bench stereo4: ekf.q_trans=q_rot=%g (core default %g, %g): rigpose-sim's "
                 "feature-level setting, which its Table 1 figures use\n",
                 (double)vcfg.ekf.q_trans, (double)core.ekf.q_trans, (double)core.ekf.q_rot);
    if (vcfg.ekf.sigma_px != core.ekf.sigma_px) {
        std::fprintf(stderr, "bench stereo4: ekf.sigma_px=%g (core default %g): the simulation's "
                             "pixel noise\n",
                     (double)vcfg.ekf.sigma_px, (double)core.ekf.sigma_px);
    }
    const std::vector<int> cams = {RP_SIM_CAM1, RP_SIM_CAM1B, RP_SIM_CAM3, RP_SIM_CAM3B};

    /* 8 sigma of the pixel noise (4 px at 0.5 px): the residuals also carry the triangulated
     * structure's error, comparable to the pixel noise, and a minimal (3-point) model is itself
     * noisy; at 4 sigma (2 px) RANSAC rejects ~11% of these correct correspondences and the
     * non-linear step, run on the survivors, loses about half its accuracy. */
    const double ransac_thr_px =
        o.opengv_thr_px > 0.0 ? o.opengv_thr_px : std::max(2.0, 8.0 * o.noise_px);
    MethodStats s_rp("rigpose stereo4 (EKF)");
    MethodStats s_gv("OpenGV gp3p+RANSAC+nonlinear");
    MethodStats s_cv("OpenCV solvePnP, cam1's estimate");
    MethodStats s_cv4("OpenCV solvePnP, mean of 4 cams");

    std::unique_ptr<rp_vo_stereo_t> vo(new rp_vo_stereo_t());
    std::unique_ptr<rp_frameset_t> fs(new rp_frameset_t());
    Landmarks lm;
    OpenGVPeer gv;
    OpenCVPeer ocv;
    std::vector<Eigen::Matrix3d> cvR(cams.size());
    std::vector<Eigen::Vector3d> cvd(cams.size());
    std::vector<char> cvok(cams.size());
    double rig_cx = NAN, rig_cy = NAN, rig_f = NAN;
    uint64_t landmarks0 = 0;

    for (uint32_t r = 0; r < o.runs; ++r) {
        rp_sim_run_t sr;
        if (rp_sim_run_init(&sr, &cfg, o.seed, r) != 0) {
            std::fprintf(stderr, "bench stereo4: rp_sim_run_init failed (run %u)\n", r);
            return 1;
        }
        const rp_rig_t *rig = &sr.rig;
        rig_f = (double)rig->cam[RP_SIM_CAM1].cam.fx;
        rig_cx = (double)rig->cam[RP_SIM_CAM1].cam.cx;
        rig_cy = (double)rig->cam[RP_SIM_CAM1].cam.cy;
        rp_status_t st = rp_vo_stereo_init(vo.get(), rig, &vcfg);
        if (st != RP_OK) {
            std::fprintf(stderr, "bench stereo4: rp_vo_stereo_init: %s\n", rp_status_str(st));
            rp_sim_run_free(&sr);
            return 1;
        }
        gv.init(rig, cams, ransac_thr_px);
        ocv.init(rig, cams);
        double p_gv[6] = {0, 0, 0, 0, 0, 0}, p_cv[6] = {0, 0, 0, 0, 0, 0};
        double p_cv4[6] = {0, 0, 0, 0, 0, 0};

        for (uint32_t j = 0; j < cfg.n_frames; ++j) {
            rp_sim_frame(&sr, j, fs.get());
            const double *truth = sr.truth + 6u * j;

            /* rigpose */
            rp_estimate_t est;
            Clock::time_point t0 = Clock::now();
            st = rp_vo_stereo_step(vo.get(), fs.get(), &est);
            s_rp.add_rigpose_frame(us_since(t0), j, st, est, cams, truth);

            /* peers: frame 0 builds their structure (timed, charged to both); the pose at
             * frame 0 is the world by definition */
            if (j == 0) {
                t0 = Clock::now();
                build_landmarks(*rig, vcfg, *fs, lm);
                const double t_lm = us_since(t0);
                s_gv.time_us += t_lm;
                s_cv.time_us += t_lm;
                s_cv4.time_us += t_lm;
                ++s_gv.timed_frames;
                ++s_cv.timed_frames;
                ++s_cv4.timed_frames;
                landmarks0 += lm.M.size();
                continue;
            }

            /* OpenGV */
            size_t n_corr = 0, n_inl = 0;
            t0 = Clock::now();
            const bool gv_ok = gv.estimate(*fs, lm, p_gv, &n_corr, &n_inl);
            s_gv.time_us += us_since(t0);
            ++s_gv.timed_frames;
            s_gv.feats += (double)n_corr;
            s_gv.extra += (double)n_inl;
            ++s_gv.feat_frames;
            if (!gv_ok) ++s_gv.fails;
            s_gv.add_error(p_gv, truth);

            /* OpenCV: all 4 cameras are timed (that is the per-frame cost for the rig) */
            t0 = Clock::now();
            ocv.estimate(*fs, lm, cvR, cvd, cvok, &n_corr);
            const bool cv1_ok = cvok[0] != 0; /* cams[0] is cam1 */
            if (cv1_ok) pose_from_R_d(cvR[0], cvd[0], p_cv);
            const bool cv4_ok = mean_pose(cvR, cvd, cvok, p_cv4);
            const double t_cv = us_since(t0);
            for (MethodStats *m : {&s_cv, &s_cv4}) {
                m->time_us += t_cv;
                ++m->timed_frames;
                m->feats += (double)n_corr;
                ++m->feat_frames;
            }
            if (!cv1_ok) ++s_cv.fails;
            if (!cv4_ok) ++s_cv4.fails;
            s_cv.add_error(p_cv, truth);
            s_cv4.add_error(p_cv4, truth);
        }
        rp_sim_run_free(&sr);
    }

    /* table */
    std::printf("\n== stereo4: rigpose vs OpenGV and OpenCV on the same simulated frames ==\n");
    std::printf("  %u runs x %u frames, seed %llu; Table 1 protocol: fx = fy = %.0f px, principal "
                "point at the image centre (%.1f, %.1f), %.2f px noise\n",
                o.runs, o.frames, (unsigned long long)o.seed, rig_f, rig_cx, rig_cy, o.noise_px);
    std::printf("  cameras cam1, cam1b, cam3, cam3b; peers' structure: frame-0 stereo "
                "triangulation (rp_stereo_triangulate), %.0f points per run\n",
                o.runs ? (double)landmarks0 / o.runs : 0.0);
    std::printf("  OpenGV: RANSAC(GP3P) threshold %.1f px (1 - cos(atan(%.1f/f)) = %.3g), max "
                "%d iterations, p = %.2f, fixed seed; then optimize_nonlinear on the inliers\n",
                ransac_thr_px, ransac_thr_px, gv.threshold, gv.max_iterations, gv.probability);
    std::printf("  OpenCV: solvePnP SOLVEPNP_ITERATIVE, useExtrinsicGuess (previous estimate of "
                "the same camera), 1 thread; time = all 4 cameras\n");
    std::printf("  us/frame = total time over all frames (frame 0 included) / frames; errors = "
                "mean |error| over frames 1.. (m, rad)\n");
    std::printf("  feats/fr = rigpose: features used in its EKF update; peers: 2-D/3-D "
                "correspondences given (frames 1..)\n\n");
    std::printf("  %-34s %9s %9s  %-7s %-7s %-7s  %-7s %-7s %-7s  %6s\n", "method", "us/frame",
                "feats/fr", "tx", "ty", "tz", "alpha", "beta", "gamma", "fails");
    print_row(s_rp);
    print_row(s_gv);
    print_row(s_cv);
    print_row(s_cv4);
    const double gv_inl = s_gv.feat_frames ? s_gv.extra / s_gv.feat_frames : NAN;
    const double gv_frames = s_gv.feat_frames ? (double)s_gv.feat_frames : NAN;
    std::printf("  OpenGV per estimated frame: %.1f RANSAC inliers of %.1f, %.2f RANSAC "
                "iterations, %.1f us RANSAC + %.1f us optimize_nonlinear\n",
                gv_inl, s_gv.feats_per_frame(), (double)gv.ransac_iters / gv_frames,
                gv.ransac_us / gv_frames, gv.nonlin_us / gv_frames);

    put_method(fig, "stereo4", s_rp);
    put_method(fig, "stereo4_opengv", s_gv);
    put_method(fig, "stereo4_opencv", s_cv);
    put_method(fig, "stereo4_opencv_mean4", s_cv4);
    fig.set("stereo4_opengv_inliers_per_frame", gv_inl);
    fig.set("stereo4_opengv_ransac_us_per_frame", gv.ransac_us / gv_frames);
    fig.set("stereo4_opengv_nonlinear_us_per_frame", gv.nonlin_us / gv_frames);
    fig.set_ratio("stereo4_vs_opengv_time_ratio", s_rp.us_per_frame(), s_gv.us_per_frame());
    fig.set_ratio("stereo4_vs_opencv_time_ratio", s_rp.us_per_frame(), s_cv.us_per_frame());
    fig.set_ratio("stereo4_opengv_tx_err_ratio", s_rp.mean_err(0), s_gv.mean_err(0));
    fig.set_ratio("stereo4_opencv_tx_err_ratio", s_rp.mean_err(0), s_cv.mean_err(0));
    std::printf("\n  rigpose / peer:  time  OpenGV %.3f  OpenCV %.3f    tx error  OpenGV %.3f  "
                "OpenCV(cam1) %.3f\n",
                s_rp.us_per_frame() / s_gv.us_per_frame(),
                s_rp.us_per_frame() / s_cv.us_per_frame(), s_rp.mean_err(0) / s_gv.mean_err(0),
                s_rp.mean_err(0) / s_cv.mean_err(0));
    return 0;
}

/* ---- section: gc vs OpenGV -------------------------------------------------------------------- */

/* gc's map as OpenGV's structure: the mature landmarks (all of them if fewer than 6 are). */
static void landmarks_from_gc(const rp_vo_gc_t &vo, Landmarks &lm)
{
    lm.M.clear();
    for (int pass = 0; pass < 2 && lm.M.size() < 6; ++pass) {
        for (uint16_t s = 0; s < RP_IDMAP_MAX_SLOTS; ++s) {
            uint32_t id;
            if (rp_lmtab_slot(&vo.lm, s, &id, NULL, NULL) != RP_OK ||
                (pass == 0 && !vo.mature[s])) continue;
            const rp_real *M = vo.lm.pt[s].M;
            lm.M[id] = Eigen::Vector3d((double)M[0], (double)M[1], (double)M[2]);
        }
    }
}

/* The true points of the features in fs (ids are point indices in the simulation). */
static void landmarks_from_truth(const rp_sim_run_t &sr, const rp_frameset_t &fs,
                                 const std::vector<int> &cams, Landmarks &lm)
{
    lm.M.clear();
    for (int k : cams) {
        for (int i = 0; i < fs.n[k]; ++i) {
            const uint32_t id = fs.f[k][i].id;
            if (id < sr.cfg.n_points) {
                lm.M[id] = Eigen::Vector3d(sr.points[3u * id], sr.points[3u * id + 1],
                                           sr.points[3u * id + 2]);
            }
        }
    }
}

static int section_gc(const BenchOpts &o, Figures &fig)
{
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.n_frames = o.frames;
    cfg.noise_px = o.noise_px;

    const rp_vo_gc_cfg_t gcfg = rp_sim_gc_cfg(&cfg); /* as rigpose-sim runs gc */
    const rp_vo_gc_cfg_t core = rp_vo_gc_default_cfg();
    std::fprintf(stderr,
                 "bench gc: init_depth_m=%g init_depth_sigma_m=%g init_on_sphere=%d (core default "
                 "%g, %g, %d): rigpose-sim's simulated scene (rp_sim_gc_cfg)\n",
                 (double)gcfg.init_depth_m, (double)gcfg.init_depth_sigma_m, gcfg.init_on_sphere,
                 (double)core.init_depth_m, (double)core.init_depth_sigma_m, core.init_on_sphere);
    const std::vector<int> cams = {RP_SIM_CAM1, RP_SIM_CAM2, RP_SIM_CAM3, RP_SIM_CAM4};
    const double ransac_thr_px =
        o.opengv_thr_px > 0.0 ? o.opengv_thr_px : std::max(2.0, 8.0 * o.noise_px);

    MethodStats s_rp("rigpose gc (EKF, 4 single cameras)");
    MethodStats s_gv("OpenGV gp3p+RANSAC+nonlin, gc's map");
    MethodStats s_or("OpenGV, true 3-D points (oracle)");
    std::unique_ptr<rp_vo_gc_t> vo(new rp_vo_gc_t());
    std::unique_ptr<rp_frameset_t> fs(new rp_frameset_t());
    Landmarks lm;
    OpenGVPeer gv, gvo;

    for (uint32_t r = 0; r < o.runs; ++r) {
        rp_sim_run_t sr;
        if (rp_sim_run_init(&sr, &cfg, o.seed, r) != 0) {
            std::fprintf(stderr, "bench gc: rp_sim_run_init failed (run %u)\n", r);
            return 1;
        }
        rp_status_t st = rp_vo_gc_init(vo.get(), &sr.rig, &gcfg);
        if (st != RP_OK) {
            std::fprintf(stderr, "bench gc: rp_vo_gc_init: %s\n", rp_status_str(st));
            rp_sim_run_free(&sr);
            return 1;
        }
        gv.init(&sr.rig, cams, ransac_thr_px);
        gvo.init(&sr.rig, cams, ransac_thr_px);
        double p_gv[6] = {0, 0, 0, 0, 0, 0}, p_or[6] = {0, 0, 0, 0, 0, 0};

        for (uint32_t j = 0; j < cfg.n_frames; ++j) {
            rp_sim_frame(&sr, j, fs.get());
            const double *truth = sr.truth + 6u * j;
            size_t n_corr = 0, n_inl = 0;

            /* OpenGV first: it sees gc's map as it stood when the frame arrived */
            if (j > 0) {
                Clock::time_point t0 = Clock::now();
                landmarks_from_gc(*vo, lm);
                const bool ok = gv.estimate(*fs, lm, p_gv, &n_corr, &n_inl);
                s_gv.time_us += us_since(t0);
                ++s_gv.timed_frames;
                s_gv.feats += (double)n_corr;
                s_gv.extra += (double)n_inl;
                ++s_gv.feat_frames;
                if (!ok) ++s_gv.fails;
                s_gv.add_error(p_gv, truth);

                landmarks_from_truth(sr, *fs, cams, lm);
                t0 = Clock::now();
                const bool ok_or = gvo.estimate(*fs, lm, p_or, &n_corr, &n_inl);
                s_or.time_us += us_since(t0);
                ++s_or.timed_frames;
                s_or.feats += (double)n_corr;
                ++s_or.feat_frames;
                if (!ok_or) ++s_or.fails;
                s_or.add_error(p_or, truth);
            }

            rp_estimate_t est;
            Clock::time_point t0 = Clock::now();
            st = rp_vo_gc_step(vo.get(), fs.get(), &est);
            s_rp.add_rigpose_frame(us_since(t0), j, st, est, cams, truth);
        }
        rp_sim_run_free(&sr);
    }

    std::printf("\n== gc: rigpose's generalised camera vs OpenGV's generalised absolute pose ==\n");
    std::printf("  %u runs x %u frames, seed %llu; Table 1 protocol, non-overlapping cameras "
                "cam1..cam4 (no stereo), %.2f px noise\n",
                o.runs, o.frames, (unsigned long long)o.seed, o.noise_px);
    std::printf("  OpenGV: RANSAC(GP3P) threshold %.1f px, max %d iterations, then "
                "optimize_nonlinear on the inliers; 3-D points = gc's mature landmarks before "
                "the frame (time includes building the list); oracle row = true points\n",
                ransac_thr_px, gv.max_iterations);
    std::printf("  us/frame: rigpose over all frames, OpenGV over frames 1..; errors = mean "
                "|error| over frames 1.. (m, rad)\n\n");
    std::printf("  %-34s %9s %9s  %-7s %-7s %-7s  %-7s %-7s %-7s  %6s\n", "method", "us/frame",
                "feats/fr", "tx", "ty", "tz", "alpha", "beta", "gamma", "fails");
    print_row(s_rp);
    print_row(s_gv);
    print_row(s_or);

    put_method(fig, "gc", s_rp);
    put_method(fig, "gc_opengv", s_gv);
    put_method(fig, "gc_opengv_oracle", s_or);
    fig.set_ratio("gc_vs_opengv_time_ratio", s_rp.us_per_frame(), s_gv.us_per_frame());
    fig.set_ratio("gc_opengv_tx_err_ratio", s_rp.mean_err(0), s_gv.mean_err(0));
    fig.set_ratio("gc_opengv_oracle_tx_err_ratio", s_rp.mean_err(0), s_or.mean_err(0));
    std::printf("\n  rigpose / OpenGV:  time %.3f    tx error %.3f (oracle points: %.3f)\n",
                s_rp.us_per_frame() / s_gv.us_per_frame(), s_rp.mean_err(0) / s_gv.mean_err(0),
                s_rp.mean_err(0) / s_or.mean_err(0));
    return 0;
}

/* ---- the sections ---------------------------------------------------------------------------- */

struct Section {
    const char *name;
    const char *what;
    int (*run)(const BenchOpts &, Figures &);
};

static const Section kSections[] = {
    {"stereo4", "rigpose stereo4 vs OpenGV (gp3p+RANSAC+nonlinear) and OpenCV solvePnP",
     section_stereo4},
    {"gc", "rigpose gc (non-overlapping, 4 single cameras) vs OpenGV generalised absolute pose",
     section_gc},
};

static void usage(const char *argv0)
{
    std::printf("usage: %s [--runs N] [--frames N] [--seed S] [--noise PX] [--out FILE] "
                "[--only SECTION] [--quick] [--opengv-thr-px PX]\nsections:\n",
                argv0);
    for (const Section &s : kSections) std::printf("  %-10s %s\n", s.name, s.what);
}

} // namespace

int main(int argc, char **argv)
{
    BenchOpts o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has = i + 1 < argc;
        if (a == "--runs" && has) o.runs = (uint32_t)std::strtoul(argv[++i], nullptr, 10);
        else if (a == "--frames" && has) o.frames = (uint32_t)std::strtoul(argv[++i], nullptr, 10);
        else if (a == "--seed" && has) o.seed = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--noise" && has) o.noise_px = std::strtod(argv[++i], nullptr);
        else if (a == "--out" && has) o.out = argv[++i];
        else if (a == "--only" && has) o.only = argv[++i];
        else if (a == "--opengv-thr-px" && has) o.opengv_thr_px = std::strtod(argv[++i], nullptr);
        else if (a == "--quick") o.runs = 3;
        else if (a == "-h" || a == "--help") { usage(argv[0]); return 0; }
        else { usage(argv[0]); return 2; }
    }
    if (o.runs == 0 || o.frames < 2 || !(o.noise_px > 0.0)) {
        std::fprintf(stderr, "bench: need runs >= 1, frames >= 2, noise > 0\n");
        return 2;
    }
    cv::setNumThreads(1);

    Figures fig;
    int rc = 0, ran = 0;
    for (const Section &s : kSections) {
        if (!o.only.empty() && o.only != s.name) continue;
        ++ran;
        if (s.run(o, fig) != 0) {
            std::fprintf(stderr, "bench: section %s failed\n", s.name);
            rc = 1;
        }
    }
    if (ran == 0) {
        std::fprintf(stderr, "bench: no section named '%s'\n", o.only.c_str());
        return 2;
    }
    if (!fig.write_json(o.out)) {
        std::fprintf(stderr, "bench: cannot write %s\n", o.out.c_str());
        return 1;
    }
    std::printf("\n%zu figures written to %s\n", fig.size(), o.out.c_str());
    return rc;
}
