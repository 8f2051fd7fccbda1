/*
 * rp_rectify.hpp - a stereo sequence made rectified for the yardsticks (OpenCV stereo PnP and
 * dense direct odometry need a rectified pair: camera 1 at (b, 0, 0), the same intrinsics, no
 * rotation, no distortion), so that they measure every clip, EuRoC's distorted, verged pair too.
 *
 * cv::stereoRectify (CALIB_ZERO_DISPARITY, alpha 0: only valid pixels) on the rig's two cameras
 * gives R1, the rotation of the left camera's frame into the rectified left frame, X_r = R1 X,
 * and the rectified projections; every image pair is remapped (bilinear) into a folder. The
 * rectified sequence's truth is the original's in the rectified frame, T_r = R1 T R1^T: a pose
 * error is the same in both frames (positions rotated by R1, rotation angles unchanged), so a
 * trajectory scored against it scores as it would in the original frame.
 */
#ifndef RP_RECTIFY_HPP
#define RP_RECTIFY_HPP

#include <string>

#include "rp_realdata.hpp"

namespace rprd {

/* 1 if seq's pair is already rectified (the yardsticks' condition above). */
bool is_rectified(const Sequence &seq);

/* The rectified copy of seq in *out, its images written to dir (which must exist) as
 * left/NNNNNN.png and right/NNNNNN.png. False with a message in *err (an image that cannot be
 * read or written, a rig that is not a pair). */
bool rectify_sequence(const Sequence &seq, const std::string &dir, Sequence *out,
                      std::string *err);

}  // namespace rprd

#endif /* RP_RECTIFY_HPP */
