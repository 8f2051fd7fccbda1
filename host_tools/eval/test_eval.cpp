/*
 * test_eval.cpp - rigpose-eval's library (rp_eval.hpp), run by `make test`:
 *  - Umeyama recovers a known Sim(3) / SE(3) from noise-free points;
 *  - ATE of a trajectory shifted by a constant: the shift without alignment, ~0 with SE(3);
 *    of a scaled one: ~0 only with Sim(3); RPE is blind to a rigid transformation of the whole;
 *  - association by timestamp with a tolerance;
 *  - formats: TUM and KITTI written and read back, rigpose CSV (angles), an LCM log of
 *    rigpose.pose_t (with truth and method) written here and read back; malformed files give
 *    "file:line: why";
 *  - the six-panel plot is written.
 * Prints the measured figures; ends with "[  PASSED  ] N test(s)." and exit 0 when all pass.
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>

#include <lcm/eventlog.h>

#include "rigpose_pose_t.h"
#include "rp_eval.hpp"

static int n_pass = 0, n_fail = 0;

static void check(bool ok, const char *what)
{
    std::printf("%s %s\n", ok ? "[       OK ]" : "[  FAILED  ]", what);
    (ok ? n_pass : n_fail)++;
}

static std::string work()
{
    const char *w = std::getenv("RP_EVAL_WORK");
    const std::string d = w ? w : "build/eval/work";
    if (std::system(("mkdir -p '" + d + "'").c_str()) != 0) {
        std::printf("cannot create %s\n", d.c_str());
    }
    return d;
}

/* A random walk like the paper's motion: 100 poses at 30 Hz. */
static rpe::Traj walk(unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    rpe::Traj t;
    rpe::Pose p;
    for (int i = 0; i < 100; ++i) {
        p.utime = 1000000 + 33333 * i;
        t.push_back(p);
        p.t += cv::Vec3d(0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng));
        p.R = p.R * rpe::rot_from_angles(cv::Vec3d(0.02 * u(rng), 0.02 * u(rng), 0.02 * u(rng)));
    }
    return t;
}

/* g * t: every pose moved by the similarity (s, R, d). */
static rpe::Traj transform(const rpe::Traj &t, double s, const cv::Matx33d &R, const cv::Vec3d &d)
{
    rpe::Traj o = t;
    for (rpe::Pose &p : o) {
        p.t = s * (R * p.t) + d;
        p.R = R * p.R;
    }
    return o;
}

static double max_pose_diff(const rpe::Traj &a, const rpe::Traj &b)
{
    if (a.size() != b.size()) {
        return 1e9;
    }
    double m = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        m = std::max(m, cv::norm(a[i].t - b[i].t));
        m = std::max(m, cv::norm(cv::Mat(a[i].R - b[i].R), cv::NORM_INF));
        m = std::max(m, std::fabs(static_cast<double>(a[i].utime - b[i].utime)));
    }
    return m;
}

static void test_umeyama_and_ate()
{
    const rpe::Traj ref = walk(1);
    const cv::Matx33d R = rpe::rot_from_angles(cv::Vec3d(0.3, -0.2, 1.1));
    const cv::Vec3d d(0.5, -1.0, 2.0);
    const rpe::Traj sim = transform(ref, 1.7, R, d);
    std::vector<cv::Vec3d> src, dst;
    for (size_t i = 0; i < ref.size(); ++i) {
        src.push_back(sim[i].t);
        dst.push_back(ref[i].t);
    }
    cv::Matx33d Ra;
    cv::Vec3d ta;
    double s = 0.0;
    const bool ok = rpe::umeyama(src, dst, true, &Ra, &ta, &s);
    std::printf("  Umeyama on a Sim(3) with scale 1.7: recovered scale %.12f (1/1.7 = %.12f)\n", s,
                1.0 / 1.7);
    check(ok && std::fabs(s - 1.0 / 1.7) < 1e-9 && cv::norm(cv::Mat(Ra * R - cv::Matx33d::eye())) < 1e-9,
          "Umeyama recovers a known Sim(3)");

    rpe::Stats st;
    std::string why;
    const rpe::Traj shifted = transform(ref, 1.0, cv::Matx33d::eye(), cv::Vec3d(0.01, -0.02, 0.0));
    rpe::ate(shifted, ref, rpe::Align::none, 1000, &st, nullptr, nullptr, &why);
    std::printf("  ATE of a (0.01, -0.02, 0) m shift, no alignment: %.9f m\n", st.rmse);
    check(std::fabs(st.rmse - std::sqrt(0.0005)) < 1e-12 && std::fabs(st.std) < 1e-12,
          "ATE without alignment = the shift");
    rpe::ate(shifted, ref, rpe::Align::se3, 1000, &st, nullptr, nullptr, &why);
    std::printf("  ATE after SE(3) alignment %.3g m\n", st.rmse);
    check(st.rmse < 1e-12, "ATE with SE(3) alignment ~ 0");
    const rpe::Traj rigid = transform(ref, 1.0, R, d);
    double scale = 0.0;
    rpe::ate(sim, ref, rpe::Align::se3, 1000, &st, nullptr, &scale, &why);
    const double se3_rmse = st.rmse;
    rpe::ate(sim, ref, rpe::Align::sim3, 1000, &st, nullptr, &scale, &why);
    std::printf("  scaled x1.7: ATE SE(3) %.6f m, Sim(3) %.3g m (scale %.6f)\n", se3_rmse, st.rmse, scale);
    check(se3_rmse > 1e-3 && st.rmse < 1e-12, "a scale error is removed by Sim(3) only");

    rpe::Stats rt, rr;
    const bool rok = rpe::rpe(rigid, ref, 1, 1000, &rt, &rr, &why);
    std::printf("  RPE of a rigidly moved copy: %.3g m, %.3g rad\n", rt.rmse, rr.rmse);
    check(rok && rt.rmse < 1e-12 && rr.rmse < 1e-12 && rt.n == 99, "RPE is blind to a rigid transformation");
    rpe::Traj jump = ref;
    for (size_t i = 50; i < jump.size(); ++i) {
        jump[i].t += cv::Vec3d(0.0, 0.0, 0.05);
    }
    rpe::rpe(jump, ref, 1, 1000, &rt, &rr, &why);
    std::printf("  RPE of one 0.05 m jump: max %.9f m over %zu pairs\n", rt.max, rt.n);
    check(std::fabs(rt.max - 0.05) < 1e-9 && rt.median < 1e-12, "RPE sees one jump once");
    check(!rpe::ate(rpe::Traj(ref.begin(), ref.begin() + 2), ref, rpe::Align::none, 1000, &st,
                    nullptr, nullptr, &why) && !why.empty(),
          "ATE refuses fewer than 3 matched poses, with a reason");
}

static void test_associate()
{
    rpe::Traj ref = walk(2), est = ref;
    for (size_t i = 0; i < est.size(); ++i) {
        est[i].utime += (i % 2) ? 400 : -400; /* within 1 ms */
    }
    est.erase(est.begin() + 10); /* a missing estimate */
    const auto m = rpe::associate(est, ref, 1000);
    bool right = m.size() == 99;
    for (const auto &p : m) {
        right = right && p.second == (p.first < 10 ? p.first : p.first + 1);
    }
    check(right, "association: 99 of 99 matched to their own frame despite +-0.4 ms jitter");
    check(rpe::associate(est, ref, 300).empty(), "association: nothing within 0.3 ms");
}

static void test_formats()
{
    const std::string w = work();
    const rpe::Traj ref = walk(3);
    std::string why;
    rpe::Traj back;
    check(rpe::write_tum(w + "/t.tum", ref, &why) && rpe::load(w + "/t.tum", "", &back, nullptr, nullptr, &why) &&
              max_pose_diff(back, ref) < 1e-8,
          "TUM written and read back (1e-8)");
    check(rpe::write_kitti(w + "/t.kitti", ref, &why) &&
              rpe::load(w + "/t.kitti", "", &back, nullptr, nullptr, &why) && back.size() == ref.size() &&
              cv::norm(back[57].t - ref[57].t) < 1e-10 && cv::norm(cv::Mat(back[57].R - ref[57].R)) < 1e-10,
          "KITTI written and read back");
    {
        std::ofstream f(w + "/t.csv");
        f << "utime_us,tx,ty,tz,alpha,beta,gamma\n0,0,0,0,0,0,0\n33333,0.1,0.2,0.3,0.01,-0.02,0.03\n";
    }
    const bool csv = rpe::load(w + "/t.csv", "", &back, nullptr, nullptr, &why) && back.size() == 2;
    const cv::Vec3d abg = csv ? rpe::rot_to_angles(back[1].R) : cv::Vec3d();
    check(csv && back[1].utime == 33333 && std::fabs(abg[0] - 0.01) < 1e-12 &&
              std::fabs(abg[1] + 0.02) < 1e-12 && std::fabs(abg[2] - 0.03) < 1e-12,
          "truth.csv read (the paper's angles)");
    {
        std::ofstream f(w + "/bad.tum");
        f << "# ok\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 x 1\n";
    }
    const bool bad = !rpe::load(w + "/bad.tum", "", &back, nullptr, nullptr, &why);
    std::printf("  malformed TUM: %s\n", why.c_str());
    check(bad && why.find("bad.tum:3:") != std::string::npos, "malformed file: file:line: why");
    {
        std::ofstream f(w + "/back.tum");
        f << "2.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n";
    }
    check(!rpe::load(w + "/back.tum", "", &back, nullptr, nullptr, &why), "time going back refused");
    check(!rpe::load(w + "/none.tum", "", &back, nullptr, nullptr, &why), "missing file refused");
}

static void test_lcm_log()
{
    const std::string path = work() + "/poses.log";
    std::remove(path.c_str());
    lcm_eventlog_t *log = lcm_eventlog_create(path.c_str(), "w");
    check(log != nullptr, "LCM log created");
    if (!log) {
        return;
    }
    const rpe::Traj ref = walk(4);
    for (size_t i = 0; i < ref.size(); ++i) {
        rigpose_pose_t m = rigpose_pose_t();
        m.utime = ref[i].utime;
        m.seq = static_cast<int32_t>(i);
        m.method = RIGPOSE_POSE_T_METHOD_GC;
        const cv::Vec4d q = rpe::rot_to_quat(ref[i].R);
        const cv::Vec3d a = rpe::rot_to_angles(ref[i].R);
        for (int k = 0; k < 3; ++k) {
            m.position[k] = ref[i].t[k] + 0.001; /* estimate = truth + 1 mm per axis */
            m.truth[k] = ref[i].t[k];
            m.truth[3 + k] = a[k];
            m.angles[k] = a[k];
        }
        for (int k = 0; k < 4; ++k) {
            m.quaternion[k] = q[k];
        }
        m.has_truth = 1;
        std::vector<uint8_t> buf(static_cast<size_t>(rigpose_pose_t_encoded_size(&m)));
        rigpose_pose_t_encode(buf.data(), 0, static_cast<int>(buf.size()), &m);
        lcm_eventlog_event_t ev = lcm_eventlog_event_t();
        ev.timestamp = m.utime;
        char ch[] = "RIGPOSE_POSE";
        ev.channel = ch;
        ev.channellen = static_cast<int32_t>(sizeof ch - 1);
        ev.data = buf.data();
        ev.datalen = static_cast<int32_t>(buf.size());
        lcm_eventlog_write_event(log, &ev);
        char other[] = "RIGPOSE_STATUS"; /* another channel: skipped */
        ev.channel = other;
        ev.channellen = static_cast<int32_t>(sizeof other - 1);
        lcm_eventlog_write_event(log, &ev);
    }
    lcm_eventlog_destroy(log);
    rpe::Traj est, truth;
    std::string method, why;
    const bool ok = rpe::load(path, "RIGPOSE_POSE", &est, &truth, &method, &why);
    check(ok && est.size() == 100 && truth.size() == 100 && method == "gc",
          "LCM log: 100 poses, their truth and the method read back");
    rpe::Stats st;
    rpe::ate(est, truth, rpe::Align::none, 1000, &st, nullptr, nullptr, &why);
    std::printf("  LCM log: ATE %.9f m (sqrt(3) mm = %.9f)\n", st.rmse, std::sqrt(3.0) * 1e-3);
    check(std::fabs(st.rmse - std::sqrt(3.0) * 1e-3) < 1e-9 && max_pose_diff(truth, ref) < 1e-9,
          "LCM log: ATE of the 1 mm offset, truth exact");
    check(!rpe::load(path, "NO_SUCH", &est, &truth, &method, &why) && !why.empty(),
          "LCM log without the channel: refused with a reason");
    const std::string png = work() + "/plot.png";
    std::remove(png.c_str());
    check(rpe::plot(png, truth, {{"gc", est}}, 1000, "test", &why) && std::ifstream(png).good(),
          "six-panel plot written");
}

int main()
{
    test_umeyama_and_ate();
    test_associate();
    test_formats();
    test_lcm_log();
    std::printf("%s %d test(s).\n", n_fail ? "[  FAILED  ]" : "[  PASSED  ]", n_fail ? n_fail : n_pass);
    return n_fail ? 1 : 0;
}
