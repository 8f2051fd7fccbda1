/*
 * rp_eval.cpp - see rp_eval.hpp.
 */
#include "rp_eval.hpp"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "rigpose/rp_pipe.h"
#include "rigpose/rp_rot.h"
#include "rigpose_pose_t.h"
#include "rp_lcmlog.h"

namespace rpe {

static_assert(sizeof(rp_real) == sizeof(double), "rigpose-eval links the double core");

cv::Matx33d rot_from_angles(const cv::Vec3d &abg)
{
    const rp_real a[3] = {abg[0], abg[1], abg[2]};
    rp_real R[9];
    rp_rot_from_angles(a, R);
    return cv::Matx33d(R);
}

cv::Vec3d rot_to_angles(const cv::Matx33d &R)
{
    rp_real a[3] = {0, 0, 0};
    (void)rp_rot_to_angles(R.val, a); /* only non-finite input fails: then NaN stays visible */
    return cv::Vec3d(a[0], a[1], a[2]);
}

cv::Matx33d rot_from_quat(const cv::Vec4d &q)
{
    rp_real R[9];
    if (rp_rot_from_quat(q.val, R) != RP_OK) {
        return cv::Matx33d::all(NAN);
    }
    return cv::Matx33d(R);
}

cv::Vec4d rot_to_quat(const cv::Matx33d &R)
{
    rp_real q[4];
    rp_rot_to_quat(R.val, q);
    return cv::Vec4d(q[0], q[1], q[2], q[3]);
}

/* ---- reading ----------------------------------------------------------------------------- */

static std::string at(const std::string &path, int line)
{
    return path + ":" + std::to_string(line) + ": ";
}

static bool load_lcm(const std::string &path, const std::string &channel, Traj *out, Traj *truth,
                     std::string *method, bool tolerant, std::string *why)
{
    rp_lcmlog_t log;
    if (rp_lcmlog_open(&log, path.c_str(), tolerant) != 0) {
        *why = log.err;
        rp_lcmlog_close(&log);
        return false;
    }
    log.warn = stderr;
    log.prog = "rigpose-eval";
    int64_t n_bad = 0, n_other = 0;
    rp_lcmlog_event_t ev;
    int r;
    while ((r = rp_lcmlog_next(&log, &ev)) > 0) {
        if (channel != ev.channel) {
            ++n_other;
            continue;
        }
        rigpose_pose_t m;
        if (rigpose_pose_t_decode(ev.data, 0, static_cast<int>(ev.datalen), &m) < 0) {
            ++n_bad;
            continue;
        }
        Pose p;
        p.utime = m.utime;
        p.t = cv::Vec3d(m.position[0], m.position[1], m.position[2]);
        p.R = rot_from_quat(cv::Vec4d(m.quaternion[0], m.quaternion[1], m.quaternion[2],
                                      m.quaternion[3]));
        out->push_back(p);
        if (truth && m.has_truth) {
            Pose g;
            g.utime = m.utime;
            g.t = cv::Vec3d(m.truth[0], m.truth[1], m.truth[2]);
            g.R = rot_from_angles(cv::Vec3d(m.truth[3], m.truth[4], m.truth[5]));
            truth->push_back(g);
        }
        if (method && m.method >= 0 && m.method < RP_PIPE_LAYOUT_COUNT_) {
            *method = rp_pipe_layout_name(static_cast<rp_pipe_layout_t>(m.method));
        }
        rigpose_pose_t_decode_cleanup(&m);
    }
    if (r < 0) { /* truncated or corrupt: the whole file is refused (--tolerant reads on) */
        *why = log.err;
        rp_lcmlog_close(&log);
        return false;
    }
    rp_lcmlog_close(&log);
    if (n_bad > 0) {
        std::fprintf(stderr, "%s: %" PRId64 " messages on %s did not decode as rigpose.pose_t\n",
                     path.c_str(), n_bad, channel.c_str());
    }
    if (out->empty()) {
        *why = path + ": no rigpose.pose_t on channel " + channel + " (" +
               std::to_string(n_other) + " events on other channels)";
        return false;
    }
    return true;
}

static bool parse_numbers(const std::string &line, char sep, std::vector<double> *v)
{
    v->clear();
    std::string s = line;
    if (sep != ' ') {
        std::replace(s.begin(), s.end(), sep, ' ');
    }
    std::istringstream in(s);
    std::string tok;
    while (in >> tok) {
        char *end = nullptr;
        const double x = std::strtod(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0' || !std::isfinite(x)) {
            return false;
        }
        v->push_back(x);
    }
    return true;
}

bool load(const std::string &path, const std::string &channel, Traj *out, Traj *truth,
          std::string *method, std::string *why, bool tolerant)
{
    out->clear();
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        *why = path + ": cannot open";
        return false;
    }
    unsigned char magic[4] = {0, 0, 0, 0};
    in.read(reinterpret_cast<char *>(magic), 4);
    if (magic[0] == 0xED && magic[1] == 0xA1 && magic[2] == 0xDA && magic[3] == 0x01) {
        return load_lcm(path, channel, out, truth, method, tolerant, why);
    }
    in.clear();
    in.seekg(0);
    std::string line;
    int no = 0;
    enum { unknown, csv, tum, kitti } fmt = unknown;
    std::vector<double> v;
    while (std::getline(in, line)) {
        ++no;
        if (!line.empty() && line.back() == '\r') {
            line.pop_back();
        }
        if (line.empty() || line[0] == '#') {
            continue;
        }
        if (fmt == unknown && line.compare(0, 9, "utime_us,") == 0) {
            if (line != "utime_us,tx,ty,tz,alpha,beta,gamma") {
                *why = at(path, no) + "CSV header must be utime_us,tx,ty,tz,alpha,beta,gamma";
                return false;
            }
            fmt = csv;
            continue;
        }
        if (!parse_numbers(line, fmt == csv ? ',' : ' ', &v)) {
            *why = at(path, no) + "not a number";
            return false;
        }
        if (fmt == unknown) {
            fmt = v.size() == 8 ? tum : v.size() == 12 ? kitti : unknown;
            if (fmt == unknown) {
                *why = at(path, no) + "neither TUM (8 numbers), KITTI (12) nor rigpose CSV "
                                      "(header utime_us,tx,...)";
                return false;
            }
        }
        const size_t want = fmt == csv ? 7u : fmt == tum ? 8u : 12u;
        if (v.size() != want) {
            *why = at(path, no) + "expected " + std::to_string(want) + " numbers, got " +
                   std::to_string(v.size());
            return false;
        }
        Pose p;
        if (fmt == csv) {
            p.utime = static_cast<int64_t>(std::llround(v[0]));
            p.t = cv::Vec3d(v[1], v[2], v[3]);
            p.R = rot_from_angles(cv::Vec3d(v[4], v[5], v[6]));
        } else if (fmt == tum) {
            p.utime = static_cast<int64_t>(std::llround(v[0] * 1e6));
            p.t = cv::Vec3d(v[1], v[2], v[3]);
            p.R = rot_from_quat(cv::Vec4d(v[7], v[4], v[5], v[6]));
            if (!std::isfinite(p.R(0, 0))) {
                *why = at(path, no) + "zero quaternion";
                return false;
            }
        } else {
            p.utime = static_cast<int64_t>(out->size()) * 100000;
            p.R = cv::Matx33d(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
            p.t = cv::Vec3d(v[3], v[7], v[11]);
        }
        if (!out->empty() && p.utime <= out->back().utime) {
            *why = at(path, no) + "timestamps must increase";
            return false;
        }
        out->push_back(p);
    }
    if (out->empty()) {
        *why = path + ": no poses";
        return false;
    }
    return true;
}

/* ---- writing ----------------------------------------------------------------------------- */

bool write_tum(const std::string &path, const Traj &t, std::string *why)
{
    FILE *f = std::fopen(path.c_str(), "w");
    if (!f) {
        *why = "cannot write " + path;
        return false;
    }
    std::fprintf(f, "# timestamp tx ty tz qx qy qz qw (rigpose-eval: cam1 in the world)\n");
    for (const Pose &p : t) {
        const cv::Vec4d q = rot_to_quat(p.R);
        const int64_t u = p.utime < 0 ? -p.utime : p.utime; /* exact decimal seconds */
        std::fprintf(f, "%s%" PRId64 ".%06" PRId64 " %.9f %.9f %.9f %.12f %.12f %.12f %.12f\n",
                     p.utime < 0 ? "-" : "", u / 1000000, u % 1000000, p.t[0], p.t[1], p.t[2],
                     q[1], q[2], q[3], q[0]);
    }
    if (std::fclose(f) != 0) {
        *why = "write error on " + path;
        return false;
    }
    return true;
}

bool write_euroc(const std::string &path, const Traj &t, std::string *why)
{
    FILE *f = std::fopen(path.c_str(), "w");
    if (!f) {
        *why = "cannot write " + path;
        return false;
    }
    std::fprintf(f, "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],"
                    "q_RS_y [],q_RS_z []\n");
    for (const Pose &p : t) {
        const cv::Vec4d q = rot_to_quat(p.R);
        std::fprintf(f, "%" PRId64 ",%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,%.12f\n", p.utime * 1000,
                     p.t[0], p.t[1], p.t[2], q[0], q[1], q[2], q[3]);
    }
    if (std::fclose(f) != 0) {
        *why = "write error on " + path;
        return false;
    }
    return true;
}

bool write_kitti(const std::string &path, const Traj &t, std::string *why)
{
    FILE *f = std::fopen(path.c_str(), "w");
    if (!f) {
        *why = "cannot write " + path;
        return false;
    }
    for (const Pose &p : t) {
        for (int r = 0; r < 3; ++r) {
            std::fprintf(f, "%.12e %.12e %.12e %.12e%s", p.R(r, 0), p.R(r, 1), p.R(r, 2), p.t[r],
                         r < 2 ? " " : "\n");
        }
    }
    if (std::fclose(f) != 0) {
        *why = "write error on " + path;
        return false;
    }
    return true;
}

/* ---- metrics ----------------------------------------------------------------------------- */

std::vector<std::pair<size_t, size_t>> associate(const Traj &est, const Traj &ref,
                                                 int64_t max_dt_us)
{
    std::vector<std::pair<size_t, size_t>> m;
    size_t j = 0;
    for (size_t i = 0; i < est.size(); ++i) {
        const int64_t u = est[i].utime;
        while (j + 1 < ref.size() && std::llabs(ref[j + 1].utime - u) <= std::llabs(ref[j].utime - u)) {
            ++j;
        }
        if (j < ref.size() && std::llabs(ref[j].utime - u) <= max_dt_us &&
            (m.empty() || m.back().second != j)) {
            m.emplace_back(i, j);
        }
    }
    return m;
}

bool umeyama(const std::vector<cv::Vec3d> &src, const std::vector<cv::Vec3d> &dst, bool with_scale,
             cv::Matx33d *R, cv::Vec3d *t, double *s)
{
    const size_t n = src.size();
    if (n < 3 || dst.size() != n) {
        return false;
    }
    cv::Vec3d ms(0, 0, 0), md(0, 0, 0);
    for (size_t i = 0; i < n; ++i) {
        ms += src[i];
        md += dst[i];
    }
    ms *= 1.0 / static_cast<double>(n);
    md *= 1.0 / static_cast<double>(n);
    cv::Matx33d C = cv::Matx33d::zeros();
    double var = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const cv::Vec3d a = src[i] - ms, b = dst[i] - md;
        C += b * a.t();
        var += a.dot(a);
    }
    C *= 1.0 / static_cast<double>(n);
    var /= static_cast<double>(n);
    cv::Mat w, u, vt;
    cv::SVD::compute(cv::Mat(C), w, u, vt);
    cv::Matx33d S = cv::Matx33d::eye();
    if (cv::determinant(u) * cv::determinant(vt) < 0.0) {
        S(2, 2) = -1.0;
    }
    const cv::Matx33d U(u), Vt(vt);
    *R = U * S * Vt;
    const double tr = w.at<double>(0) * S(0, 0) + w.at<double>(1) * S(1, 1) + w.at<double>(2) * S(2, 2);
    if (!(var > 0.0)) {
        return false;
    }
    *s = with_scale ? tr / var : 1.0;
    *t = md - (*s) * ((*R) * ms);
    return std::isfinite(*s) && cv::checkRange(cv::Mat(*R));
}

Stats stats(std::vector<double> e)
{
    Stats s;
    s.n = e.size();
    if (e.empty()) {
        return s;
    }
    for (double x : e) {
        s.sse += x * x;
        s.mean += x;
    }
    const double n = static_cast<double>(e.size());
    s.mean /= n;
    s.rmse = std::sqrt(s.sse / n);
    for (double x : e) {
        s.std += (x - s.mean) * (x - s.mean);
    }
    s.std = std::sqrt(s.std / n);
    std::sort(e.begin(), e.end());
    s.min = e.front();
    s.max = e.back();
    s.median = e.size() % 2 ? e[e.size() / 2] : 0.5 * (e[e.size() / 2 - 1] + e[e.size() / 2]);
    return s;
}

bool ate(const Traj &est, const Traj &ref, Align align, int64_t max_dt_us, Stats *out,
         Traj *aligned, double *scale, std::string *why)
{
    const auto m = associate(est, ref, max_dt_us);
    if (m.size() < 3) {
        *why = "fewer than 3 poses of the estimate match the reference in time (" +
               std::to_string(m.size()) + ")";
        return false;
    }
    std::vector<cv::Vec3d> src, dst;
    for (const auto &p : m) {
        src.push_back(est[p.first].t);
        dst.push_back(ref[p.second].t);
    }
    cv::Matx33d R = cv::Matx33d::eye();
    cv::Vec3d t(0, 0, 0);
    double s = 1.0;
    if (align != Align::none && !umeyama(src, dst, align == Align::sim3, &R, &t, &s)) {
        *why = "alignment failed (degenerate trajectory)";
        return false;
    }
    std::vector<double> e;
    Traj al;
    for (const auto &p : m) {
        Pose q = est[p.first];
        q.t = s * (R * q.t) + t;
        q.R = R * q.R;
        e.push_back(cv::norm(q.t - ref[p.second].t));
        al.push_back(q);
    }
    *out = stats(e);
    if (aligned) {
        *aligned = al;
    }
    if (scale) {
        *scale = s;
    }
    return true;
}

static Pose rel(const Pose &a, const Pose &b) /* a^-1 b */
{
    Pose r;
    r.R = a.R.t() * b.R;
    r.t = a.R.t() * (b.t - a.t);
    return r;
}

bool rpe(const Traj &est, const Traj &ref, int delta, int64_t max_dt_us, Stats *trans,
         Stats *rot, std::string *why)
{
    const auto m = associate(est, ref, max_dt_us);
    if (delta < 1 || m.size() <= static_cast<size_t>(delta)) {
        *why = "not enough associated poses for RPE over " + std::to_string(delta) + " frames";
        return false;
    }
    std::vector<double> et, er;
    for (size_t i = 0; i + static_cast<size_t>(delta) < m.size(); ++i) {
        const size_t k = i + static_cast<size_t>(delta);
        const Pose Q = rel(ref[m[i].second], ref[m[k].second]);
        const Pose P = rel(est[m[i].first], est[m[k].first]);
        const Pose E = rel(Q, P);
        et.push_back(cv::norm(E.t));
        /* rotation angle, accurate near 0 too: atan2(|sin| from the skew part, cos) */
        const double c = 0.5 * (E.R(0, 0) + E.R(1, 1) + E.R(2, 2) - 1.0);
        const cv::Vec3d w(E.R(2, 1) - E.R(1, 2), E.R(0, 2) - E.R(2, 0), E.R(1, 0) - E.R(0, 1));
        er.push_back(std::atan2(0.5 * cv::norm(w), c));
    }
    *trans = stats(et);
    *rot = stats(er);
    return true;
}

/* ---- the plot ------------------------------------------------------------------------------ */

/* A "nice" tick step for a range (1, 2 or 5 times a power of ten). */
static double tick_step(double range, int want)
{
    const double raw = range / want, p = std::pow(10.0, std::floor(std::log10(raw)));
    const double f = raw / p;
    return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * p;
}

bool plot(const std::string &png, const Traj &ref, const std::vector<Series> &methods,
          int64_t max_dt_us, const std::string &title, std::string *why)
{
    static const cv::Scalar colours[] = {{200, 80, 0},  {0, 140, 255}, {40, 160, 40},
                                         {60, 60, 220}, {180, 60, 180}, {140, 140, 0},
                                         {0, 200, 200}, {120, 80, 40}};
    const char *labels[6] = {"tx (m)", "ty (m)", "tz (m)", "alpha (rad)", "beta (rad)", "gamma (rad)"};
    const int pw = 470, ph = 260, ml = 70, mt = 40, cols = 3, rows = 2, top = 40, legend = 30;
    cv::Mat img(top + rows * ph + legend, cols * pw, CV_8UC3, cv::Scalar(255, 255, 255));
    auto value = [](const Pose &p, int k) {
        return k < 3 ? p.t[k] : rot_to_angles(p.R)[k - 3];
    };
    /* series: per method, (frame index of the reference, pose) */
    std::vector<std::vector<std::pair<size_t, Pose>>> ser;
    for (const Series &s : methods) {
        std::vector<std::pair<size_t, Pose>> v;
        for (const auto &p : associate(s.traj, ref, max_dt_us)) {
            v.emplace_back(p.second, s.traj[p.first]);
        }
        ser.push_back(v);
    }
    if (ref.size() < 2) {
        *why = "the reference has fewer than 2 poses";
        return false;
    }
    const double font = 0.45;
    cv::putText(img, title, cv::Point(10, 26), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
    for (int k = 0; k < 6; ++k) {
        const int ox = (k % 3) * pw, oy = top + (k / 3) * ph;
        const cv::Rect box(ox + ml, oy + 10, pw - ml - 20, ph - mt - 20);
        double lo = 1e300, hi = -1e300;
        for (const Pose &p : ref) {
            lo = std::min(lo, value(p, k));
            hi = std::max(hi, value(p, k));
        }
        for (const auto &v : ser) {
            for (const auto &p : v) {
                const double y = value(p.second, k);
                if (std::isfinite(y)) {
                    lo = std::min(lo, y);
                    hi = std::max(hi, y);
                }
            }
        }
        if (hi - lo < 1e-9) {
            lo -= 1e-3;
            hi += 1e-3;
        }
        const double pad = 0.05 * (hi - lo);
        lo -= pad;
        hi += pad;
        const double xmax = static_cast<double>(ref.size() - 1);
        auto X = [&](double f) { return box.x + static_cast<int>(std::lround(f / xmax * box.width)); };
        auto Y = [&](double y) {
            return box.y + box.height - static_cast<int>(std::lround((y - lo) / (hi - lo) * box.height));
        };
        cv::rectangle(img, box, cv::Scalar(0, 0, 0), 1);
        const double ys = tick_step(hi - lo, 5);
        for (double y = std::ceil(lo / ys) * ys; y <= hi; y += ys) {
            cv::line(img, cv::Point(box.x, Y(y)), cv::Point(box.x + box.width, Y(y)),
                     cv::Scalar(225, 225, 225), 1);
            char b[32];
            std::snprintf(b, sizeof b, "%.3g", std::fabs(y) < 1e-12 ? 0.0 : y);
            cv::putText(img, b, cv::Point(ox + 8, Y(y) + 5), cv::FONT_HERSHEY_SIMPLEX, font,
                        cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
        }
        const double xs = tick_step(xmax, 5);
        for (double f = 0; f <= xmax; f += xs) {
            char b[32];
            std::snprintf(b, sizeof b, "%.0f", f);
            cv::putText(img, b, cv::Point(X(f) - 8, box.y + box.height + 18),
                        cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
        }
        cv::putText(img, labels[k], cv::Point(box.x + 8, box.y + 18), cv::FONT_HERSHEY_SIMPLEX, 0.55,
                    cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
        cv::putText(img, "frame", cv::Point(box.x + box.width - 50, box.y + box.height + 34),
                    cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
        for (size_t i = 1; i < ref.size(); ++i) {
            cv::line(img, cv::Point(X(static_cast<double>(i - 1)), Y(value(ref[i - 1], k))),
                     cv::Point(X(static_cast<double>(i)), Y(value(ref[i], k))), cv::Scalar(0, 0, 0),
                     2, cv::LINE_AA);
        }
        for (size_t s = 0; s < ser.size(); ++s) {
            const cv::Scalar c = colours[s % 8];
            for (size_t i = 1; i < ser[s].size(); ++i) {
                const double y0 = value(ser[s][i - 1].second, k), y1 = value(ser[s][i].second, k);
                if (std::isfinite(y0) && std::isfinite(y1)) {
                    cv::line(img, cv::Point(X(static_cast<double>(ser[s][i - 1].first)), Y(y0)),
                             cv::Point(X(static_cast<double>(ser[s][i].first)), Y(y1)), c, 1,
                             cv::LINE_AA);
                }
            }
        }
    }
    /* legend */
    int lx = 10;
    const int ly = top + rows * ph + 18;
    auto entry = [&](const std::string &name, const cv::Scalar &c, int thick) {
        cv::line(img, cv::Point(lx, ly - 4), cv::Point(lx + 30, ly - 4), c, thick, cv::LINE_AA);
        cv::putText(img, name, cv::Point(lx + 36, ly), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                    cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
        lx += 36 + 10 * static_cast<int>(name.size()) + 30;
    };
    entry("ground truth", cv::Scalar(0, 0, 0), 2);
    for (size_t s = 0; s < methods.size(); ++s) {
        entry(methods[s].name, colours[s % 8], 2);
    }
    try {
        if (!cv::imwrite(png, img, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
            *why = "cannot write " + png;
            return false;
        }
    } catch (const cv::Exception &e) {
        *why = "cannot write " + png + ": " + e.what();
        return false;
    }
    return true;
}

} // namespace rpe
