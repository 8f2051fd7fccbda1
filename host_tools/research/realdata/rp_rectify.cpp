/*
 * rp_rectify.cpp - see rp_rectify.hpp.
 */
#include "rp_rectify.hpp"

#include <cstdio>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rprd {

bool is_rectified(const Sequence &seq)
{
    if (seq.rig.n_cams != 2) {
        return false;
    }
    const rp_rig_cam_t &c0 = seq.rig.cam[0], &c1 = seq.rig.cam[1];
    const rp_camera_t &c = c0.cam;
    return c.k1 == 0 && c.k2 == 0 && c.p1 == 0 && c.p2 == 0 && c.k3 == 0 && c1.cam.k1 == 0 &&
           c1.cam.k2 == 0 && c1.cam.p1 == 0 && c1.cam.p2 == 0 && c1.cam.k3 == 0 &&
           c1.cam.fx == c.fx && c1.cam.fy == c.fy && c1.cam.cx == c.cx && c1.cam.cy == c.cy &&
           c1.D[0] > 0 && c1.D[1] == 0 && c1.D[2] == 0 && c1.R[0] == 1 && c1.R[4] == 1 &&
           c1.R[8] == 1;
}

namespace {

cv::Mat K_of(const rp_camera_t &c)
{
    return (cv::Mat_<double>(3, 3) << (double)c.fx, 0, (double)c.cx, 0, (double)c.fy,
            (double)c.cy, 0, 0, 1);
}

cv::Mat dist_of(const rp_camera_t &c)
{
    return (cv::Mat_<double>(1, 5) << (double)c.k1, (double)c.k2, (double)c.p1, (double)c.p2,
            (double)c.k3);
}

}  // namespace

bool rectify_sequence(const Sequence &seq, const std::string &dir, Sequence *out,
                      std::string *err)
{
    if (seq.rig.n_cams != 2) {
        *err = "rectify: not a stereo pair";
        return false;
    }
    const rp_rig_cam_t &c0 = seq.rig.cam[0], &c1 = seq.rig.cam[1];
    const cv::Size size((int)c0.cam.width, (int)c0.cam.height);
    /* rig: X0 = R_1 X1 + D_1 (camera 1's frame into camera 0's); OpenCV wants X1 = R X0 + T */
    cv::Mat R(3, 3, CV_64F), T(3, 1, CV_64F);
    for (int i = 0; i < 3; ++i) {
        double acc = 0.0;
        for (int j = 0; j < 3; ++j) {
            R.at<double>(i, j) = (double)c1.R[3 * j + i];
            acc += (double)c1.R[3 * j + i] * (double)c1.D[j];
        }
        T.at<double>(i) = -acc;
    }
    cv::Mat R1, R2, P1, P2, Q, m[2][2];
    try {
        cv::stereoRectify(K_of(c0.cam), dist_of(c0.cam), K_of(c1.cam), dist_of(c1.cam), size, R,
                          T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY, 0.0, size);
        cv::initUndistortRectifyMap(K_of(c0.cam), dist_of(c0.cam), R1, P1, size, CV_32FC1,
                                    m[0][0], m[0][1]);
        cv::initUndistortRectifyMap(K_of(c1.cam), dist_of(c1.cam), R2, P2, size, CV_32FC1,
                                    m[1][0], m[1][1]);
    } catch (const cv::Exception &e) {
        *err = std::string("rectify: OpenCV: ") + e.what();
        return false;
    }
    const double f = P1.at<double>(0, 0), b = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
    if (!(f > 0.0) || !(b > 0.0)) {
        *err = "rectify: the rectified pair has no positive baseline along x";
        return false;
    }
    *out = seq;
    out->dir = dir;
    rp_rig_t &rig = out->rig;
    for (int k = 0; k < 2; ++k) {
        rp_camera_t &c = rig.cam[k].cam;
        c.fx = c.fy = (rp_real)f;
        c.cx = (rp_real)P1.at<double>(0, 2);
        c.cy = (rp_real)P1.at<double>(1, 2);
        c.k1 = c.k2 = c.p1 = c.p2 = c.k3 = 0;
        for (int i = 0; i < 9; ++i) {
            rig.cam[k].R[i] = (rp_real)(i % 4 == 0 ? 1.0 : 0.0);
        }
        rig.cam[k].D[0] = rig.cam[k].D[1] = rig.cam[k].D[2] = 0;
    }
    rig.cam[1].D[0] = (rp_real)b;
    Pose Rr; /* X_r = R1 X */
    for (int i = 0; i < 9; ++i) {
        Rr.R[i] = R1.at<double>(i / 3, i % 3);
    }
    for (Pose &Tj : out->truth) {
        Tj = pose_mul(pose_mul(Rr, Tj), pose_inv(Rr));
    }
    static const char *const side[2] = {"left", "right"};
    for (int k = 0; k < 2; ++k) {
        const std::string sub = dir + "/" + side[k];
        std::error_code ec;
        std::filesystem::create_directories(sub, ec);
        if (ec) {
            *err = "rectify: cannot create " + sub;
            return false;
        }
        for (size_t j = 0; j < seq.img[k].size(); ++j) {
            const cv::Mat im = cv::imread(seq.img[k][j], cv::IMREAD_GRAYSCALE);
            if (im.empty() || im.size() != size) {
                *err = "rectify: cannot read " + seq.img[k][j] + " at the calibration's size";
                return false;
            }
            cv::Mat r;
            cv::remap(im, r, m[k][0], m[k][1], cv::INTER_LINEAR, cv::BORDER_CONSTANT);
            char name[32];
            std::snprintf(name, sizeof name, "/%06zu.png", j);
            out->img[k][j] = sub + name;
            if (!cv::imwrite(out->img[k][j], r)) {
                *err = "rectify: cannot write " + out->img[k][j];
                return false;
            }
        }
    }
    return true;
}

}  // namespace rprd
