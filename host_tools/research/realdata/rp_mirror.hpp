/*
 * rp_mirror.hpp - the left-right mirror image of a stereo sequence (issue 14 item 8): a
 * symmetric problem should give a symmetric answer, so rigpose's error on a clip's mirror image
 * should match its error on the clip.
 *
 * With M = diag(-1, 1, 1) (x flipped, in every camera frame), the mirror image of a rig seen
 * through images flipped left-right is:
 *   - the cameras swapped: the mirrored left camera (rig camera 0) is the original right
 *     camera's mirror image, the mirrored right camera the original left's;
 *   - each camera: a point X of its frame is seen as M X; with u' = w - 1 - u (the pixel
 *     centres' convention, docs/design.md) the intrinsics keep fx, fy, cy and take cx' = w - 1 - cx;
 *     OpenCV's radial-tangential distortion keeps k1, k2, k3 and p1 and takes p2' = -p2
 *     (x_d = x (1 + k1 r^2 + ...) + 2 p1 x y + p2 (r^2 + 2 x^2): odd in x only if p2 flips;
 *     y_d = y (...) + p1 (r^2 + 2 y^2) + 2 p2 x y: even in x only if p2 flips);
 *   - the pair: the original right camera's pose in the left camera E = (R, D) becomes
 *     E' = M E^-1 M (a KITTI baseline b along +x stays +b, the right camera to the right);
 *   - the truth: the world is the mirrored left camera at the first frame, and frame j's pose
 *     T'_j = M (E^-1 T_j E) M (the original right camera's trajectory, conjugated by M).
 * Mirroring twice gives the sequence back (M M = I), exactly up to rounding.
 */
#ifndef RP_MIRROR_HPP
#define RP_MIRROR_HPP

#include <string>

#include "rp_realdata.hpp"

namespace rprd {

rp_camera_t mirror_camera(const rp_camera_t &c); /* cx -> w - 1 - cx, p2 -> -p2 */
Pose mirror_pose(const Pose &T);                 /* M T M */

/* The mirror image of seq: rig and truth as above, the image paths swapped (img[0] the
 * original right images: they must be flipped when read, which write_sequence does). */
Sequence mirror_sequence(const Sequence &seq);

/* Write seq as a folder of its own format in dir (created), readable by load_kitti /
 * load_euroc: KITTI calib.txt (P0, P1), poses.txt, times.txt, left/ and right/ NNNNNN.png
 * (frames renumbered from 0); EuRoC cam0/ and cam1/ (sensor.yaml with T_BS: body = cam0,
 * data.csv, data/<t_ns>.png) and groundtruth.txt (TUM, cam0's poses). flip: images flipped
 * left-right on the way. KITTI needs a rectified pair (camera 1 at (b > 0, 0, 0), no rotation,
 * no distortion). False with a message in *err. */
bool write_sequence(const Sequence &seq, const std::string &dir, bool flip, std::string *err);

}  // namespace rprd

#endif /* RP_MIRROR_HPP */
