/*
 * rp_eval.hpp - trajectories of rigpose runs: reading (TUM, rigpose CSV, KITTI, LCM logs of the
 * daemon's rigpose.pose_t), writing (TUM, KITTI, EuRoC), association by timestamp, absolute
 * trajectory error with optional SE(3) / Sim(3) Umeyama alignment, relative pose error, and the paper's
 * Fig. 3/4-style six-panel plot. Host only (OpenCV for the drawing).
 *
 * Conventions (docs/design.md): a pose is cam1 in the world, p_world = R p_cam1 + t; angles
 * (alpha, beta, gamma) with R = Rz(gamma) Ry(beta) Rx(alpha); quaternions (w, x, y, z) here,
 * written in TUM's order (x, y, z, w); metres, radians; utime in microseconds.
 */
#ifndef RP_EVAL_HPP
#define RP_EVAL_HPP

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace rpe {

struct Pose {
    int64_t utime = 0;
    cv::Matx33d R = cv::Matx33d::eye(); /* cam1 to world */
    cv::Vec3d t{0, 0, 0};               /* cam1's position in the world, m */
};
typedef std::vector<Pose> Traj;

/* Rotation from / to the paper's angles [alpha, beta, gamma] (rad), and unit quaternions
 * (w, x, y, z). */
cv::Matx33d rot_from_angles(const cv::Vec3d &abg);
cv::Vec3d rot_to_angles(const cv::Matx33d &R);
cv::Matx33d rot_from_quat(const cv::Vec4d &wxyz);
cv::Vec4d rot_to_quat(const cv::Matx33d &R);

/* A trajectory file, its format found from its content:
 *  - LCM log (rigpose.pose_t on `channel`): the estimates; `truth` (may be NULL) receives the
 *    messages' ground truth when they carry it; `method` (may be NULL) the method's name;
 *  - CSV with header utime_us,tx,ty,tz,alpha,beta,gamma (truth.csv of a replay folder);
 *  - TUM: "timestamp tx ty tz qx qy qz qw" per line (seconds), '#' comments;
 *  - KITTI: 12 numbers per line (row-major [R | t]); utime = line index * 1e5 (10 Hz).
 * False with a reason (file:line) on a malformed file; never throws. LCM logs are read by
 * host_tools/common/rp_lcmlog.h: a truncated or corrupt log is refused with the byte offset
 * ("FILE: offset N: what"), or with `tolerant` read on past bad stretches, one warning line per
 * skip on stderr. */
bool load(const std::string &path, const std::string &channel, Traj *out, Traj *truth,
          std::string *method, std::string *why, bool tolerant = false);

bool write_tum(const std::string &path, const Traj &t, std::string *why);
bool write_kitti(const std::string &path, const Traj &t, std::string *why);
/* EuRoC's ground-truth CSV (state_groundtruth_estimate0/data.csv, the first 8 columns):
 * "timestamp [ns], p_RS_R_x [m], p_RS_R_y, p_RS_R_z, q_RS_w [], q_RS_x, q_RS_y, q_RS_z". */
bool write_euroc(const std::string &path, const Traj &t, std::string *why);

/* Pairs (index in est, index in ref) with |utime difference| <= max_dt_us, each ref pose used
 * at most once, in time order (nearest neighbour). */
std::vector<std::pair<size_t, size_t>> associate(const Traj &est, const Traj &ref,
                                                 int64_t max_dt_us);

/* Umeyama (1991): s, R, t minimising sum |dst_i - (s R src_i + t)|^2; with_scale false: s = 1.
 * False if fewer than 3 points or degenerate. */
bool umeyama(const std::vector<cv::Vec3d> &src, const std::vector<cv::Vec3d> &dst, bool with_scale,
             cv::Matx33d *R, cv::Vec3d *t, double *s);

struct Stats {
    size_t n = 0;
    double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0, sse = 0;
};
Stats stats(std::vector<double> e);

enum class Align { none, se3, sim3 };

/* Absolute trajectory error: position error of the associated pairs after aligning the estimate
 * to the reference (as evo_ape's default translation metric). `aligned` (may be NULL) receives
 * the estimate after alignment, `scale` the Sim(3) scale (1 otherwise). */
bool ate(const Traj &est, const Traj &ref, Align align, int64_t max_dt_us, Stats *out,
         Traj *aligned, double *scale, std::string *why);

/* Relative pose error over `delta` associated frames, E_i = (Q_i^-1 Q_i+d)^-1 (P_i^-1 P_i+d)
 * (as evo_rpe): translation norm (m) and rotation angle (rad) of E_i. */
bool rpe(const Traj &est, const Traj &ref, int delta, int64_t max_dt_us, Stats *trans,
         Stats *rot, std::string *why);

/* The six-panel plot (tx, ty, tz in m; alpha, beta, gamma in rad against frame index of the
 * reference): the reference in black, one coloured line per method. */
struct Series {
    std::string name;
    Traj traj;
};
bool plot(const std::string &png, const Traj &ref, const std::vector<Series> &methods,
          int64_t max_dt_us, const std::string &title, std::string *why);

} // namespace rpe

#endif
