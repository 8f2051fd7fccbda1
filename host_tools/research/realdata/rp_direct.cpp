/*
 * rp_direct.cpp - dense direct stereo odometry, the feature-free yardstick (rp_direct.hpp).
 */
#include "rp_direct.hpp"
#include "rp_rectify.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rprd {

namespace {

/* Left-image disparity (px, 0 = none) by semi-global matching, kept where the right image's
 * own disparity agrees to 1 px (occlusions and mismatches fail that check). */
cv::Mat checked_disparity(const cv::Mat &L, const cv::Mat &R)
{
    const int bs = 5;
    cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
        0, 128, bs, 8 * bs * bs, 32 * bs * bs, 1, 63, 10, 100, 2, cv::StereoSGBM::MODE_SGBM_3WAY);
    cv::Mat d16, dl, Lf, Rf, r16, dr;
    sgbm->compute(L, R, d16);
    d16.convertTo(dl, CV_32F, 1.0 / 16);
    cv::flip(L, Lf, 1); /* the right image's disparity: match the mirrored pair */
    cv::flip(R, Rf, 1);
    sgbm->compute(Rf, Lf, r16);
    cv::flip(r16, r16, 1);
    r16.convertTo(dr, CV_32F, 1.0 / 16);
    for (int y = 0; y < dl.rows; ++y) {
        float *row = dl.ptr<float>(y);
        const float *rrow = dr.ptr<float>(y);
        for (int x = 0; x < dl.cols; ++x) {
            const int xr = (int)std::lround((double)x - (double)row[x]);
            if (row[x] <= 0.0f || xr < 0 || std::fabs(rrow[xr] - row[x]) > 1.0f) {
                row[x] = 0.0f;
            }
        }
    }
    return dl;
}

float bilinear(const cv::Mat &I, double x, double y)
{
    const int x0 = (int)std::floor(x), y0 = (int)std::floor(y);
    const double ax = x - x0, ay = y - y0;
    const float *r0 = I.ptr<float>(y0), *r1 = I.ptr<float>(y0 + 1);
    return (float)((1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) +
                   ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]));
}

/* A pixel of the reference image at some pyramid level with its 3-D point (m, frame j). */
struct Sample {
    cv::Vec3d X;
    float grey;
};

struct Intrinsics {
    double fx, fy, cx, cy;
};

/* Gauss-Newton on one pyramid level: refines (R, t), X' = R X + t, and the brightness model
 * I_next(project(X')) = (1 + gain) I_ref + offset. */
void align_level(const std::vector<Sample> &S, const cv::Mat &next, const Intrinsics &k,
                 const DirectOpts &o, cv::Matx33d *R, cv::Vec3d *t, double *gain, double *offset)
{
    cv::Mat gx, gy;
    cv::Sobel(next, gx, CV_32F, 1, 0, 3, 1.0 / 8);
    cv::Sobel(next, gy, CV_32F, 0, 1, 3, 1.0 / 8);
    for (int it = 0; it < o.iterations; ++it) {
        cv::Matx<double, 8, 8> H = cv::Matx<double, 8, 8>::zeros();
        cv::Matx<double, 8, 1> g = cv::Matx<double, 8, 1>::zeros();
        for (const Sample &s : S) {
            const cv::Vec3d Y = (*R) * s.X + *t;
            if (Y[2] < 0.5) {
                continue;
            }
            const double iz = 1.0 / Y[2];
            const double u = k.fx * Y[0] * iz + k.cx, v = k.fy * Y[1] * iz + k.cy;
            if (u < 1.0 || v < 1.0 || u > next.cols - 3.0 || v > next.rows - 3.0) {
                continue;
            }
            const double r = bilinear(next, u, v) - (1.0 + *gain) * s.grey - *offset;
            const double Gx = bilinear(gx, u, v), Gy = bilinear(gy, u, v);
            /* d r / d Y (through the projection); a left increment [I | -[Y]x] of the motion
             * gives d r / d omega = Y x (d r / d Y). */
            const cv::Vec3d dY(Gx * k.fx * iz, Gy * k.fy * iz,
                               -(Gx * k.fx * Y[0] + Gy * k.fy * Y[1]) * iz * iz);
            const cv::Vec3d dw = Y.cross(dY);
            const cv::Matx<double, 8, 1> J(dY[0], dY[1], dY[2], dw[0], dw[1], dw[2], -s.grey, -1);
            const double w = std::fabs(r) < o.huber ? 1.0 : o.huber / std::fabs(r);
            H += w * J * J.t();
            g += w * r * J;
        }
        H(6, 6) += 1e-3; /* the brightness terms are weak where the texture is flat */
        H(7, 7) += 1e-3;
        cv::Mat dx;
        if (!cv::solve(cv::Mat(H), cv::Mat(-g), dx, cv::DECOMP_CHOLESKY)) {
            return;
        }
        const double *d = dx.ptr<double>();
        cv::Mat dR;
        cv::Rodrigues(cv::Vec3d(d[3], d[4], d[5]), dR);
        const cv::Matx33d dRm(dR);
        *R = dRm * (*R);
        *t = dRm * (*t) + cv::Vec3d(d[0], d[1], d[2]);
        *gain += d[6];
        *offset += d[7];
        if (std::hypot(d[0], d[1], d[2]) < 1e-5 && std::hypot(d[3], d[4], d[5]) < 1e-7) {
            return;
        }
    }
}

/* The motion from the left image ref (with its disparity disp) to the left image next. */
Pose align(const cv::Mat &ref, const cv::Mat &disp, const cv::Mat &next, const Intrinsics &k0,
           double baseline_m, const DirectOpts &o)
{
    std::vector<cv::Mat> pa, pb;
    cv::Mat a, b;
    ref.convertTo(a, CV_32F);
    next.convertTo(b, CV_32F);
    cv::buildPyramid(a, pa, o.levels - 1);
    cv::buildPyramid(b, pb, o.levels - 1);
    cv::Matx33d R = cv::Matx33d::eye();
    cv::Vec3d t(0, 0, -o.start_step_m);
    double gain = 0.0, offset = 0.0;
    for (int l = o.levels - 1; l >= 0; --l) {
        const double s = 1.0 / (double)(1 << l);
        const Intrinsics k = {k0.fx * s, k0.fy * s, (k0.cx + 0.5) * s - 0.5,
                              (k0.cy + 0.5) * s - 0.5};
        const cv::Mat &A = pa[(size_t)l];
        cv::Mat ax, ay;
        cv::Sobel(A, ax, CV_32F, 1, 0, 3, 1.0 / 8);
        cv::Sobel(A, ay, CV_32F, 0, 1, 3, 1.0 / 8);
        std::vector<Sample> S;
        for (int y = 2; y < A.rows - 2; ++y) {
            for (int x = 2; x < A.cols - 2; ++x) {
                if ((l == 0 && ((x + y) & 1)) || /* every other pixel at full size */
                    std::hypot(ax.at<float>(y, x), ay.at<float>(y, x)) < o.min_grad) {
                    continue;
                }
                const int X0 = (int)std::lround((x + 0.5) / s - 0.5);
                const int Y0 = (int)std::lround((y + 0.5) / s - 0.5);
                if (X0 >= disp.cols || Y0 >= disp.rows || Y0 < o.row_min || Y0 >= o.row_max) {
                    continue;
                }
                const double dv = disp.at<float>(Y0, X0);
                const double z = dv > 0.0 ? k0.fx * baseline_m / dv : 0.0;
                if (z <= 0.0 || z > o.max_depth_m) {
                    continue;
                }
                S.push_back({cv::Vec3d((X0 - k0.cx) * z / k0.fx, (Y0 - k0.cy) * z / k0.fy, z),
                             A.at<float>(y, x)});
            }
        }
        align_level(S, pb[(size_t)l], k, o, &R, &t, &gain, &offset);
    }
    Pose T;
    for (int i = 0; i < 9; ++i) {
        T.R[i] = R(i / 3, i % 3);
    }
    for (int i = 0; i < 3; ++i) {
        T.t[i] = t[i];
    }
    return T;
}

}  // namespace

bool direct_reference(const Sequence &seq, const DirectOpts &o, std::vector<Pose> *traj,
                      std::vector<Pose> *steps, std::string *err)
{
    const rp_rig_cam_t &c0 = seq.rig.cam[0], &c1 = seq.rig.cam[1];
    const rp_camera_t &c = c0.cam;
    const bool rectified = is_rectified(seq);
    if (!rectified) {
        *err = "direct yardstick: needs a rectified pair (rectify_sequence)";
        return false;
    }
    const Intrinsics k = {(double)c.fx, (double)c.fy, (double)c.cx, (double)c.cy};
    traj->assign(1, Pose());
    if (steps) {
        steps->clear();
    }
    cv::Mat ref = cv::imread(seq.img[0][0], cv::IMREAD_GRAYSCALE);
    for (size_t j = 0; j + 1 < seq.utime.size(); ++j) {
        const cv::Mat right = cv::imread(seq.img[1][j], cv::IMREAD_GRAYSCALE);
        const cv::Mat next = cv::imread(seq.img[0][j + 1], cv::IMREAD_GRAYSCALE);
        if (ref.empty() || right.empty() || next.empty()) {
            *err = "direct yardstick: cannot read the images of frame " + std::to_string(j);
            return false;
        }
        if (right.size() != ref.size() || next.size() != ref.size()) {
            *err = "direct yardstick: image sizes differ at frame " + std::to_string(j);
            return false;
        }
        Pose T;
        try {
            T = align(ref, checked_disparity(ref, right), next, k, (double)c1.D[0], o);
        } catch (const cv::Exception &e) {
            *err = "direct yardstick: OpenCV failed at frame " + std::to_string(j) + ": " + e.what();
            return false;
        }
        if (steps) {
            steps->push_back(T);
        }
        traj->push_back(pose_mul(traj->back(), pose_inv(T)));
        ref = next;
    }
    return true;
}

}  // namespace rprd
