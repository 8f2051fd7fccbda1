/* rp_timesync.cpp - see rp_timesync.hpp. */
#include "rp_timesync.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/matx.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace rpts {

namespace {

constexpr int kMinInliers = 30;
constexpr double kTrim = 0.9; /* the fit keeps the best 90 % of the samples at each lag: an
                               * interval whose essential matrix went wrong (a moving object,
                               * a blurred image) does not pull the lag */

/* Rotation vector (axis * angle) of a rotation matrix. */
void rotvec(const cv::Mat &R, double v[3])
{
    cv::Mat r;
    cv::Rodrigues(R, r);
    for (int i = 0; i < 3; ++i) {
        v[i] = r.at<double>(i);
    }
}

/* w at time t by linear interpolation between the samples around it (sorted by t); false
 * outside the series or across a gap of more than 1.5 intervals. */
bool interp(const std::vector<RateSample> &s, double t, double w[3], double dw[3])
{
    if (s.size() < 2 || t < s.front().t_s || t > s.back().t_s) {
        return false;
    }
    auto hi = std::lower_bound(s.begin(), s.end(), t,
                               [](const RateSample &a, double x) { return a.t_s < x; });
    if (hi == s.begin()) {
        ++hi;
    }
    const RateSample &b = *hi, &a = *(hi - 1);
    const double h = b.t_s - a.t_s;
    const double typ = (s.back().t_s - s.front().t_s) / (double)(s.size() - 1);
    if (!(h > 0.0) || h > 1.5 * typ) {
        return false;
    }
    const double u = (t - a.t_s) / h;
    for (int i = 0; i < 3; ++i) {
        w[i] = a.w[i] + u * (b.w[i] - a.w[i]);
        dw[i] = (b.w[i] - a.w[i]) / h;
    }
    return true;
}

constexpr double kMinSnr = 3.0; /* see fit_offset */
constexpr int kOversample = 8; /* grid points per sample interval */

/* Trimmed mean of squared differences |w_ref(t + lag) - w_cam(t)|^2 over the overlap, both
 * series interpolated on a grid of kOversample points per interval (interpolating only one of
 * them would smooth its noise at lags between samples and pull the fit there); also the summed
 * squared slope of w_ref, per sample (the grid's sum over kOversample). */
double lag_cost(const std::vector<RateSample> &ref, const std::vector<RateSample> &cam, double lag,
                size_t *n_out, double *slope2)
{
    *n_out = 0;
    *slope2 = 0.0;
    if (cam.size() < 2) {
        return -1.0;
    }
    const double h = (cam.back().t_s - cam.front().t_s) / (double)(cam.size() - 1) / kOversample;
    std::vector<std::pair<double, double>> e; /* squared residual, squared slope */
    for (double t = cam.front().t_s; t <= cam.back().t_s; t += h) {
        double w[3], dw[3], wc[3], dwc[3];
        if (!interp(ref, t + lag, w, dw) || !interp(cam, t, wc, dwc)) {
            continue;
        }
        double r2 = 0.0, d2 = 0.0;
        for (int i = 0; i < 3; ++i) {
            r2 += (w[i] - wc[i]) * (w[i] - wc[i]);
            d2 += dw[i] * dw[i];
        }
        e.emplace_back(r2, d2);
    }
    if (e.size() < 10 * (size_t)kOversample) {
        return -1.0;
    }
    std::sort(e.begin(), e.end());
    const size_t keep = (size_t)std::ceil(kTrim * (double)e.size());
    double sum = 0.0;
    for (size_t i = 0; i < keep; ++i) {
        sum += e[i].first;
        *slope2 += e[i].second;
    }
    *slope2 /= kOversample;
    *n_out = keep / kOversample;
    return sum / (double)keep;
}

/* Unit bearing of a normalised image point. */
cv::Vec3d bearing(const cv::Point2f &p)
{
    const cv::Vec3d b((double)p.x, (double)p.y, 1.0);
    return b / cv::norm(b);
}

/* The rotation R with b = R a for bearing pairs (least squares, Kabsch: the SVD of
 * sum b a^T, its determinant made +1). */
cv::Matx33d kabsch(const std::vector<cv::Vec3d> &a, const std::vector<cv::Vec3d> &b,
                   const std::vector<int> &idx)
{
    cv::Matx33d H = cv::Matx33d::zeros();
    for (int i : idx) {
        H += b[(size_t)i] * a[(size_t)i].t();
    }
    cv::Mat w, u, vt;
    cv::SVD::compute(cv::Mat(H), w, u, vt);
    cv::Mat R = u * vt;
    if (cv::determinant(R) < 0.0) {
        cv::Mat d = cv::Mat::eye(3, 3, CV_64F);
        d.at<double>(2, 2) = -1.0;
        R = u * d * vt;
    }
    return cv::Matx33d(R);
}

/* The camera's rotation between two images as a pure rotation of the bearings (the scene's
 * depth large against the motion between two frames: the parallax a translation adds is the
 * same for every camera that looks the same way, and averages out over a clip): RANSAC over
 * pairs of bearings (200 hypotheses, a fixed seed), inliers within thr (rad), the rotation refit
 * on them. Returns the inlier count. */
int rotation_ransac(const std::vector<cv::Point2f> &na, const std::vector<cv::Point2f> &nb,
                    double thr, cv::Matx33d *R_out)
{
    std::vector<cv::Vec3d> a, b;
    for (size_t i = 0; i < na.size(); ++i) {
        a.push_back(bearing(na[i]));
        b.push_back(bearing(nb[i]));
    }
    const int n = (int)a.size();
    if (n < 2) {
        return 0;
    }
    cv::RNG rng(0x5eed);
    std::vector<int> best;
    const double c_thr = std::cos(thr);
    for (int it = 0; it < 200; ++it) {
        const int i = rng.uniform(0, n), j = rng.uniform(0, n);
        if (i == j) {
            continue;
        }
        const cv::Matx33d R = kabsch(a, b, {i, j});
        std::vector<int> in;
        for (int k = 0; k < n; ++k) {
            if ((R * a[(size_t)k]).dot(b[(size_t)k]) >= c_thr) {
                in.push_back(k);
            }
        }
        if (in.size() > best.size()) {
            best.swap(in);
        }
    }
    if (best.size() < 3) {
        return 0;
    }
    *R_out = kabsch(a, b, best);
    return (int)best.size();
}

}  // namespace

RateTracker::RateTracker(const rp_rig_cam_t &c)
{
    K_ = (cv::Mat_<double>(3, 3) << (double)c.cam.fx, 0, (double)c.cam.cx, 0, (double)c.cam.fy,
          (double)c.cam.cy, 0, 0, 1);
    dist_ = (cv::Mat_<double>(1, 5) << (double)c.cam.k1, (double)c.cam.k2, (double)c.cam.p1,
             (double)c.cam.p2, (double)c.cam.k3);
    Rk_ = cv::Mat(3, 3, CV_64F);
    for (int i = 0; i < 9; ++i) {
        Rk_.at<double>(i / 3, i % 3) = (double)c.R[i];
    }
    thr_ = 2.0 / (double)c.cam.fx; /* 2 px, as an angle (rad) */
}

bool RateTracker::add(const cv::Mat &grey, int64_t utime)
{
    if (grey.empty() || grey.type() != CV_8UC1) {
        return false;
    }
    const bool have_prev = !prev_.empty() && prev_.size() == grey.size() && utime > prev_t_;
    if (have_prev) {
        step(grey, utime);
    }
    grey.copyTo(prev_);
    prev_t_ = utime;
    return true;
}

void RateTracker::restart()
{
    prev_.release();
}

void RateTracker::step(const cv::Mat &next, int64_t utime)
{
    std::vector<cv::Point2f> a, b, back;
    std::vector<uchar> st, st2;
    std::vector<float> e;
    cv::goodFeaturesToTrack(prev_, a, 400, 0.01, 8);
    if (a.size() < (size_t)kMinInliers) {
        return;
    }
    cv::calcOpticalFlowPyrLK(prev_, next, a, b, st, e, cv::Size(21, 21), 3);
    cv::calcOpticalFlowPyrLK(next, prev_, b, back, st2, e, cv::Size(21, 21), 3);
    std::vector<cv::Point2f> pa, pb;
    for (size_t i = 0; i < a.size(); ++i) {
        const float dx = back[i].x - a[i].x, dy = back[i].y - a[i].y;
        if (st[i] && st2[i] && dx * dx + dy * dy < 1.0f) {
            pa.push_back(a[i]);
            pb.push_back(b[i]);
        }
    }
    if (pa.size() < (size_t)kMinInliers) {
        return;
    }
    std::vector<cv::Point2f> na, nb;
    cv::undistortPoints(pa, na, K_, dist_);
    cv::undistortPoints(pb, nb, K_, dist_);
    /* a pure rotation of the bearings: in a scene far against the motion between two images
     * the essential matrix's rotation is ill-conditioned and noisier (an essential matrix
     * chosen by Torr's GRIC where it fits better was tried: docs/time.md) */
    cv::Matx33d R;
    const int inl = rotation_ransac(na, nb, thr_, &R);
    const double dt = 1e-6 * (double)(utime - prev_t_);
    if (inl < kMinInliers || !(dt > 0.0)) {
        return;
    }
    /* b_{j+1} = R b_j: the camera turned by R^T; in cam1's frame R_k R^T R_k^T */
    double v[3];
    rotvec(cv::Mat(Rk_ * cv::Mat(R.t()) * Rk_.t()), v);
    RateSample smp;
    smp.t_s = 1e-6 * 0.5 * (double)(prev_t_ + utime);
    for (int i = 0; i < 3; ++i) {
        smp.w[i] = v[i] / dt;
    }
    smp.inliers = inl;
    samples_.push_back(smp);
}

bool camera_rates(const std::vector<std::string> &img, const std::vector<int64_t> &utime,
                  const rp_rig_cam_t &c, std::vector<RateSample> *out, std::string *err)
{
    out->clear();
    if (img.size() != utime.size() || img.size() < 2) {
        *err = "camera_rates: need at least two images with stamps";
        return false;
    }
    RateTracker rt(c);
    for (size_t j = 0; j < img.size(); ++j) {
        const cv::Mat m = cv::imread(img[j], cv::IMREAD_GRAYSCALE);
        if (m.empty()) {
            *err = img[j] + ": cannot read";
            return false;
        }
        rt.add(m, utime[j]);
    }
    *out = rt.samples();
    if (out->empty()) {
        *err = "camera_rates: no interval gave a rotation";
        return false;
    }
    return true;
}

bool fit_offset(const std::vector<RateSample> &ref, const std::vector<RateSample> &cam,
                double max_lag_s, double step_s, OffsetFit *out)
{
    *out = OffsetFit();
    if (!(step_s > 0.0) || !(max_lag_s >= 0.0)) {
        return false;
    }
    const int n_steps = (int)std::floor(max_lag_s / step_s);
    std::vector<double> cost(2 * (size_t)n_steps + 1, -1.0);
    int best = -1;
    for (int i = -n_steps; i <= n_steps; ++i) {
        size_t n = 0;
        double s2 = 0.0;
        const double c = lag_cost(ref, cam, i * step_s, &n, &s2);
        cost[(size_t)(i + n_steps)] = c;
        if (c >= 0.0 && (best < 0 || c < cost[(size_t)best])) {
            best = i + n_steps;
        }
    }
    if (best < 0) {
        return false;
    }
    /* parabola through the best and its neighbours */
    double lag = (best - n_steps) * step_s;
    if (best > 0 && best + 1 < (int)cost.size() && cost[(size_t)best - 1] >= 0.0 &&
        cost[(size_t)best + 1] >= 0.0) {
        const double c0 = cost[(size_t)best - 1], c1 = cost[(size_t)best],
                     c2 = cost[(size_t)best + 1];
        const double den = c0 - 2.0 * c1 + c2;
        if (den > 0.0) {
            lag += 0.5 * step_s * (c0 - c2) / den;
        }
    }
    size_t n = 0, n0 = 0;
    double s2 = 0.0, s20 = 0.0;
    const double c = lag_cost(ref, cam, lag, &n, &s2);
    const double c0 = lag_cost(ref, cam, 0.0, &n0, &s20);
    if (c < 0.0) {
        return false;
    }
    out->offset_s = lag;
    out->n = n;
    out->rms_fit = std::sqrt(c / 3.0);
    out->rms_zero = c0 >= 0.0 ? std::sqrt(c0 / 3.0) : -1.0;
    /* the lag's variance from the cost's curvature at the fit (a second difference over
     * +-10 grid steps): with S = n c the summed squares, var = sigma_r^2 / (S'' / 2), sigma_r^2 =
     * c / 3 per coordinate. A flat cost (a constant rate: nothing to align) gives no
     * curvature and an infinite sigma. */
    const double h = 10.0 * step_s;
    size_t na = 0, nb = 0;
    double sa = 0.0, sb = 0.0;
    const double ca = lag_cost(ref, cam, lag - h, &na, &sa);
    const double cb = lag_cost(ref, cam, lag + h, &nb, &sb);
    const double curv = (ca - 2.0 * c + cb) / (h * h);
    out->sigma_s = ca >= 0.0 && cb >= 0.0 && curv > 0.0
                       ? std::sqrt((c / 3.0) / (0.5 * (double)n * curv))
                       : INFINITY;
    (void)s2; /* the slope's sum: the curvature above measures the same without the noise */
    /* a rate that hardly varies has nothing to align: the curvature then measures the noise's
     * own wiggles. The fit counts only if the reference's variation about its mean is at least
     * kMinSnr times the residual at the fit (per coordinate, both rms) */
    double mean[3] = {0, 0, 0}, var = 0.0;
    for (const RateSample &r : ref) {
        for (int i = 0; i < 3; ++i) {
            mean[i] += r.w[i] / (double)ref.size();
        }
    }
    for (const RateSample &r : ref) {
        for (int i = 0; i < 3; ++i) {
            var += (r.w[i] - mean[i]) * (r.w[i] - mean[i]) / (3.0 * (double)ref.size());
        }
    }
    out->snr = out->rms_fit > 0.0 ? std::sqrt(var) / out->rms_fit : INFINITY;
    if (out->snr < kMinSnr) {
        out->sigma_s = INFINITY;
    }
    return true;
}

}  // namespace rpts
