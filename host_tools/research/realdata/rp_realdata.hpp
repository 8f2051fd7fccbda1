/*
 * rp_realdata.hpp - real stereo sequences for rigpose (host only, C++ with OpenCV): loaders of a
 * KITTI odometry folder and of an EuRoC MAV folder into one Sequence (the rig of one stereo
 * pair, the frames' image paths and times, the ground truth in rigpose's conventions), the
 * conversions between rigpose's pose vector and the datasets' poses, and the trajectory error.
 *
 * rigpose's conventions (docs/design.md): the world is cam1's frame at the first frame; a pose is
 * p = [tx ty tz alpha beta gamma]: cam1's position in the world (m) and its rotation
 * R = Rz(gamma) Ry(beta) Rx(alpha) (camera-to-world). Here cam1 (rig camera 0) is the left
 * camera of the pair (KITTI image_0 / "left", EuRoC cam0), rig camera 1 the right one.
 *
 *   KITTI:  poses.txt line j is [R|t] taking points of the left camera at frame j into the left
 *           camera at frame 0: exactly (R_j, d_j). Rectified pinhole pair: P0, P1 of calib.txt
 *           (lines "P0: ..." and "P1: ...", or "P_rect_00:" / "P_rect_01:", or without labels
 *           the first two lines of 12 numbers), the right camera at
 *           D = (-P1[0][3] / P1[0][0], 0, 0), no rotation, no distortion. Times: times.txt (s,
 *           one line per frame) or a frame rate given.
 *   EuRoC:  camera pose in the world T_WC = T_WB T_BS (body pose at the nearest timestamp, T_BS
 *           of the camera's sensor.yaml); expressed in the first frame's cam0:
 *           T_j = T_WC0(0)^-1 T_WC0(j). The pair: R_1, D_1 of T_BS0^-1 T_BS1; intrinsics and
 *           radial-tangential distortion (k1 k2 p1 p2, k3 = 0) per camera. Body poses from
 *           groundtruth.txt (TUM: t[s] tx ty tz qx qy qz qw, qw last) or EuRoC's own
 *           state_groundtruth_estimate0/data.csv (t[ns], px, py, pz, qw, qx, qy, qz, ..., qw
 *           first); the format is told by the time column (nanoseconds: over 1e12).
 */
#ifndef RP_REALDATA_HPP
#define RP_REALDATA_HPP

#include <cstdint>
#include <string>
#include <vector>

#include "rigpose/rp_rig.h"

namespace rprd {

/* A rigid transform: x' = R x + t (R row-major). */
struct Pose {
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double t[3] = {0, 0, 0};
};

Pose pose_mul(const Pose &a, const Pose &b);  /* a * b */
Pose pose_inv(const Pose &a);                 /* a^-1 */

/* rigpose's pose vector [tx ty tz alpha beta gamma] of a camera-to-world pose, and back
 * (through the core's rp_rot_to_angles / rp_rot_from_angles). */
void pose_to_vec(const Pose &T, double p[6]);
Pose pose_from_vec(const double p[6]);

enum class Format { KITTI, EUROC };

struct Sequence {
    Format format = Format::KITTI;
    std::string name;                      /* "kitti00", "euroc_mh01": figure prefix */
    std::string dir;                       /* the dataset folder */
    rp_rig_t rig;                          /* camera 0 left (cam1), camera 1 right */
    std::vector<int64_t> utime;            /* per frame, us */
    std::vector<std::string> img[2];       /* per frame: left and right image paths */
    std::vector<Pose> truth;               /* per frame: cam1 in the world (first cam1 frame) */
    std::vector<std::string> notes;        /* what the loader read, one line each (folders,
                                            * times, the truth's columns and first pose) */
};

/* What a loader takes besides the folder. */
struct LoadOpts {
    size_t first = 0;      /* frames skipped: stereo frames (a KITTI line, an EuRoC timestamp
                            * both cameras list), never file rows; that frame's cam1 is the world */
    size_t max_frames = 0; /* frames loaded, 0: all */
    std::string left, right; /* KITTI: the image folders under the folder; empty: the first of
                              * image_0/image_1, image_l/image_r, left/right that holds the
                              * first frame's left image */
    double fps = 0.0;      /* KITTI: > 0: frame j (of the file) at j / fps s, times.txt not read */
    std::string truth;     /* ground-truth file; empty: KITTI poses.txt; EuRoC groundtruth.txt
                            * (TUM), else state_groundtruth_estimate0/data.csv (EuRoC's own) */
};

/* Load a KITTI odometry / EuRoC MAV folder. The file formats (column orders) are those of
 * rigpose-realdata --help; seq->notes says which files and folders were read, and the first
 * ground-truth pose as read, in words (a file whose columns are in another order shows there).
 * On failure returns false with a message in *err (missing file or image, naming the first;
 * malformed line with its number; folders tried; no ground truth near a frame; no frame...). */
bool load_kitti(const std::string &dir, const LoadOpts &o, Sequence *seq, std::string *err);
bool load_euroc(const std::string &dir, const LoadOpts &o, Sequence *seq, std::string *err);

/* The same with only first and max_frames. */
inline bool load_kitti(const std::string &dir, size_t first, size_t max_frames, Sequence *seq,
                       std::string *err)
{
    LoadOpts o;
    o.first = first;
    o.max_frames = max_frames;
    return load_kitti(dir, o, seq, err);
}
inline bool load_euroc(const std::string &dir, size_t first, size_t max_frames, Sequence *seq,
                       std::string *err)
{
    LoadOpts o;
    o.first = first;
    o.max_frames = max_frames;
    return load_euroc(dir, o, seq, err);
}

/* Trajectory error against the truth, frame by frame, no alignment beyond the shared start
 * (both start at the identity). */
struct FrameErr {
    double trans_m;  /* |d_est - d_true| */
    double rot_rad;  /* angle of R_est^T R_true */
};
FrameErr frame_error(const double p_est[6], const Pose &truth);

struct Summary {
    size_t frames = 0;
    double rpe_percent = 0.0; /* relative pose error: sum over frames j >= 1 of
                               * |t(T_est(j-1)^-1 T_est(j)) - t(T_true(j-1)^-1 T_true(j))|, in
                               * percent of the path (frame-to-frame drift, whatever the start) */
    double path_m = 0.0;     /* length of the true path over the frames */
    double ate_m = 0.0;      /* RMSE of trans_m over the frames */
    double ate_percent = 0.0; /* 100 ate_m / path_m */
    double max_m = 0.0;      /* largest trans_m */
    double final_m = 0.0;    /* trans_m at the last frame */
    double rot_rmse_deg = 0.0;
    double scale = 0.0;      /* least-squares scale of the estimated positions on the true
                              * ones, sum e.t / sum t.t over the frames (both start at the
                              * origin): 1 is metric; 1.03 is a path 3 % too long */
};
Summary summarise(const std::vector<Pose> &est, const std::vector<Pose> &truth);

}  // namespace rprd

#endif /* RP_REALDATA_HPP */
