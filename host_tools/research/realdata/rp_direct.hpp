/*
 * rp_direct.hpp - a second, feature-free yardstick of the ground truth for rectified stereo
 * sequences (host only, C++ with OpenCV; never linked into the core or the daemon).
 *
 * Dense direct stereo odometry, frame to frame: the left image j gets a dense depth map from
 * OpenCV's semi-global matching (StereoSGBM, left-right checked to 1 px); every pixel of it
 * with a strong enough gradient and a depth up to `max_depth_m` is warped into the left image
 * j+1 by a rigid motion, and the motion (6 parameters) plus an affine brightness change
 * (gain, offset) is found by Gauss-Newton on the photometric difference, coarse to fine over
 * an image pyramid, with a Huber weight. No corners, no tracks, no matching, no PnP: it shares
 * nothing with rigpose's pipeline nor with the OpenCV PnP yardstick except the images and the
 * calibration, so where both yardsticks and rigpose agree against the ground truth, the
 * disagreement is in the ground truth (or in the calibration they all use).
 */
#ifndef RP_DIRECT_HPP
#define RP_DIRECT_HPP

#include <string>
#include <vector>

#include "rp_realdata.hpp"

namespace rprd {

struct DirectOpts {
    double max_depth_m = 40.0;  /* pixels farther than this are left out (disparity noise) */
    double min_grad = 4.0;      /* grey levels per pixel: flatter pixels carry no information */
    double huber = 8.0;         /* grey levels: larger residuals are down-weighted */
    int levels = 5;             /* pyramid levels (the largest flows near the car are ~60 px) */
    int iterations = 30;        /* Gauss-Newton iterations per level at most */
    double start_step_m = 0.0;  /* initial forward step, m (0: no motion; KITTI's results are
                                 * the same from 0, 0.3 and 0.75 m; a hand-held clip's steps
                                 * are centimetres, which a car's 0.75 m start misses) */
    int row_min = 0;            /* only pixels of rows row_min..row_max - 1 (full size) are */
    int row_max = 1 << 30;      /* used: e.g. the road alone, or everything above it */
};

/* Chains the frame-to-frame motions of seq (rectified pair: camera 1 at (b, 0, 0), same
 * intrinsics, no rotation) into traj (cam1 in the first frame, as seq.truth), and each step
 * (points of frame j into frame j+1) into steps if not NULL. Returns false with a message in
 * *err if the sequence is not a rectified pair or an image cannot be read. */
bool direct_reference(const Sequence &seq, const DirectOpts &o, std::vector<Pose> *traj,
                      std::vector<Pose> *steps, std::string *err);

}  // namespace rprd

#endif /* RP_DIRECT_HPP */
