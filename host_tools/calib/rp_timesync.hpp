/*
 * rp_timesync.hpp - a camera's clock offset from the rig's rotation, before any filter runs.
 *
 * The cameras of a rigid rig turn together: each sees the rig's angular velocity w(t), in its
 * own frame. Camera k's rotation between two consecutive images (OpenCV KLT tracks, their
 * undistorted bearings rotated onto each other: RANSAC over pairs, Kabsch's fit on the inliers)
 * divided by their stamp interval is w over that interval, expressed in cam1's frame through
 * the extrinsics (w_1 = R_k w_k). A pure rotation takes the translation's parallax for
 * rotation: in a scene near against the motion between two images (the rendered room, 0.7-1 m
 * at 0.5 m/s) the cameras that face across the motion see different rates, and the fit refuses
 * them (below) rather than report a lag. With capture = stamp +
 * offset (rp_ekf.h's convention), camera k's sample at stamp time s is the reference camera's
 * w at s + offset_k. The offset is the lag that best aligns the two series: the least-squares
 * fit of w_ref(s + offset) to w_k(s) (both interpolated linearly) over a grid of lags, refined
 * by a parabola through the best three; its standard deviation from the cost's curvature there
 * (var = s_r^2 / (S''/2), S the summed squares, s_r^2 the residual variance). Translation does
 * not enter (the rotation is the same for every camera of a rigid rig, wherever it sits), so a
 * drive at a constant rate of turn gives no answer: the fit then reports an infinite sigma (the
 * rate's variation under 3 times the residual) rather than a number.
 *
 * The offset is a start value for the filter's offset states (estimator.estimate_time_offsets
 * with cameras[i].time_offset_s), which refine it online; it needs rotation in the clip (the
 * hand-held EuRoC clip has plenty) and sees offsets up to max_lag_s.
 */
#ifndef RP_TIMESYNC_HPP
#define RP_TIMESYNC_HPP

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "rigpose/rp_rig.h"

namespace rpts {

struct RateSample {
    double t_s = 0.0;  /* mid-point of the two images' stamps, s */
    double w[3] = {0, 0, 0}; /* angular velocity over the interval, rad/s, in cam1's frame */
    int inliers = 0;   /* essential-matrix inliers */
};

/* One camera's rate series, image by image (a live source or a recording): each image after
 * the first gives a sample for the interval from the previous one (its stamp later, the same
 * size), unless fewer than 30 tracks fit the rotation. */
class RateTracker {
public:
    explicit RateTracker(const rp_rig_cam_t &c);
    /* grey: 8-bit, one channel (copied); utime: its stamp, us. False for an empty or other
     * image (nothing kept). */
    bool add(const cv::Mat &grey, int64_t utime);
    void restart(); /* the next image starts a new interval (a gap: a missing frame) */
    const std::vector<RateSample> &samples() const { return samples_; }

private:
    void step(const cv::Mat &next, int64_t utime);
    cv::Mat K_, dist_, Rk_, prev_;
    int64_t prev_t_ = 0;
    double thr_ = 0.0;
    std::vector<RateSample> samples_;
};

/* Camera c's angular velocity between consecutive images img[j], img[j + 1] (stamps utime,
 * us), through RateTracker. False (err) if an image cannot be read or no interval gives a
 * rotation. */
bool camera_rates(const std::vector<std::string> &img, const std::vector<int64_t> &utime,
                  const rp_rig_cam_t &c, std::vector<RateSample> *out, std::string *err);

struct OffsetFit {
    double offset_s = 0.0;   /* capture = stamp + offset_s for the camera, relative to ref */
    double sigma_s = 0.0;    /* its standard deviation */
    double rms_zero = 0.0;   /* rms difference of the series at lag 0, rad/s */
    double rms_fit = 0.0;    /* at the fitted lag */
    size_t n = 0;            /* samples compared at the fitted lag */
    double snr = 0.0;        /* rms variation of the reference's rate over rms_fit: under 3
                              * the rate hardly varies, the lag is noise's and sigma_s is
                              * infinite */
};

/* The lag within +-max_lag_s (grid of step_s) that aligns cam to ref. False if the series
 * overlap in fewer than 10 samples at every lag. */
bool fit_offset(const std::vector<RateSample> &ref, const std::vector<RateSample> &cam,
                double max_lag_s, double step_s, OffsetFit *out);

}  // namespace rpts

#endif /* RP_TIMESYNC_HPP */
