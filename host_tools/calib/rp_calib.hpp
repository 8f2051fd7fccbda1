/*
 * rp_calib.hpp - calibration of a rigpose rig from chessboard images (host only, OpenCV):
 *  - intrinsics of one camera (corner refinement, RMS per view and overall, per-file rejection);
 *  - a stereo pair's R, T, E, F (the fixed fundamental matrix of the stereo layout);
 *  - the extrinsics (R_k, D_k) of cameras that share no view with cam1, by hand-eye calibration
 *    from each camera's own board trajectory over a common rig motion (AX = XB);
 *  - the daemon's YAML configuration (config/README.md) from the result.
 *
 * Conventions (docs/design.md): camera axes x right, y down, z forward; a pose "A in B" maps A's
 * coordinates to B's: p_B = R p_A + t. The rig's R_k is camera k to cam1 and D_k camera k's
 * centre in cam1's frame, metres.
 */
#ifndef RP_CALIB_HPP
#define RP_CALIB_HPP

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace rpc {

/* A planar chessboard: inner corners (columns x rows) and the side of a square, metres. */
struct Board {
    cv::Size inner{9, 6};
    double square_m = 0.025;
    std::vector<cv::Point3f> object_points() const;
};

/* One image of one camera: the board's corners (refined), or why it was rejected. */
struct View {
    std::string file;
    bool found = false;
    std::vector<cv::Point2f> corners;
    std::string why; /* empty when found */
};

/* Reads `file` as 8-bit grey, finds and refines the board. `size` is the camera's image size:
 * if empty it is set from this image, otherwise an image of another size is rejected. Never
 * throws; an unreadable / corrupt file, a size mismatch or a missing board give found = false
 * and a one-line reason. */
View detect_board(const std::string &file, const Board &board, cv::Size *size);

/* A pose: p_to = R p_from + t (metres). */
struct Pose {
    cv::Matx33d R = cv::Matx33d::eye();
    cv::Vec3d t{0, 0, 0};
    Pose inv() const;
    Pose operator*(const Pose &b) const;
};

struct Intrinsics;

struct IntrinsicsOpts {
    bool fix_aspect = false;   /* fx / fy fixed to the initial guess's (1) */
    bool zero_tangential = false;
    const Intrinsics *fixed = nullptr; /* known K and distortion: only the board poses (solvePnP) */
};

struct Intrinsics {
    cv::Size size;
    cv::Matx33d K = cv::Matx33d::eye();
    std::vector<double> dist = std::vector<double>(5, 0.0); /* k1 k2 p1 p2 k3 */
    double rms_px = 0.0;                  /* over all corners of the used views */
    std::vector<int> used;                /* indices into the views given */
    std::vector<double> view_rms_px;      /* per used view */
    std::vector<Pose> board_in_cam;       /* per used view */
};

/* Calibrates from the views with a board (at least 3), or with opts.fixed only finds the board
 * poses and reprojection errors. False with a reason otherwise. */
bool calibrate_intrinsics(const std::vector<View> &views, const Board &board, cv::Size size,
                          const IntrinsicsOpts &opts, Intrinsics *out, std::string *why);

struct Stereo {
    Pose left_in_right;          /* x_right = R x_left + T (OpenCV's stereoCalibrate R, T) */
    cv::Matx33d E, F;            /* x_right^T F x_left = 0, undistorted pixels of both images */
    double rms_px = 0.0;
    double baseline_m = 0.0;     /* |T| */
    int n_pairs = 0;
    std::vector<double> pair_baseline_m; /* |t_R - R t_L| style per pair, from the board poses */
};

/* Calibrates a stereo pair from views paired by index (both must have found the board; pairs
 * where either did not are skipped). Intrinsics are held fixed (calibrate each camera first). */
bool calibrate_stereo(const std::vector<View> &left, const std::vector<View> &right,
                      const Board &board, const Intrinsics &kl, const Intrinsics &kr,
                      Stereo *out, std::string *why);

/* Hand-eye: camera k's pose in the reference camera's frame from simultaneous board poses of
 * both cameras over a common rigid motion (each camera sees its own, static board). Needs at
 * least 3 sets with rotations about different axes. Method: OpenCV's calibrateHandEye (Park and
 * Martin). Residuals: RMS of A_i X - X B_i over consecutive sets (rotation angle, translation). */
bool hand_eye(const std::vector<Pose> &ref_board_in_cam, const std::vector<Pose> &k_board_in_cam,
              Pose *cam_k_in_ref, double *residual_rot_rad, double *residual_t_m, std::string *why);

/* Refines X = camera k in the reference camera by bundle adjustment over the corners themselves:
 * unknowns are the reference board's pose in each set, X, and camera k's board in the reference
 * board's frame; residuals are both cameras' reprojection errors (Levenberg-Marquardt, numeric
 * Jacobian). c_ref[i] / c_k[i] are set i's corners; start from hand_eye's X. rms_px: after. */
bool refine_extrinsics(const std::vector<std::vector<cv::Point2f>> &c_ref,
                       const std::vector<std::vector<cv::Point2f>> &c_k, const Intrinsics &k_ref,
                       const Intrinsics &k_k, const Board &board, Pose *cam_k_in_ref,
                       double *rms_px, std::string *why);

/* One camera of the configuration file. */
struct CamOut {
    std::string name, device;
    Intrinsics intr;
    Pose in_cam1; /* R_k (camera to cam1), D_k */
};

/* Writes the daemon's configuration (config/README.md, version 1). pairs: indices into cams.
 * The method is stereo4 for two pairs, stereo2 for one, gc over all cameras otherwise.
 * `source_kind` is v4l2 or replay (replay_index given). Returns false with a reason. */
bool write_config(const std::string &path, const std::vector<CamOut> &cams,
                  const std::vector<std::pair<int, int>> &pairs, const std::string &source_kind,
                  const std::string &replay_index, const std::string &meta_note,
                  std::string *why);

} // namespace rpc

#endif
