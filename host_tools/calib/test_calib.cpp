/*
 * test_calib.cpp - rigpose-calib's library (rp_calib.hpp), run by `make test`:
 *  - OpenCV's own stereo chessboard set from Debian's opencv-doc (left01..14, right01..14, 9x6
 *    inner corners, 25 mm squares): the left camera's intrinsics with a fixed aspect ratio
 *    reproduce OpenCV's published calibration (left_intrinsics.yml: fx 535.9, cx 342.3,
 *    cy 235.6) within 1 px and its RMS within 0.05 px;
 *  - the stereo pair: the baseline agrees with each pair's own board poses, and corners lie on
 *    their epipolar lines (F) after undistortion;
 *  - bad files: unreadable, corrupt, not an image, without a board, of another size: each
 *    rejected with a reason;
 *  - hand-eye extrinsics on synthetic board trajectories with a known answer (the paper's cam2
 *    and cam3 relative to cam1), noise-free and with 0.2 px corner noise.
 * The data may be installed gzip-compressed: it is then unpacked into $RP_CALIB_WORK.
 * Prints the measured figures; ends with "[  PASSED  ] N test(s)." and exit 0 when all pass.
 */
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "rp_calib.hpp"

static int n_pass = 0, n_fail = 0;

static void check(bool ok, const char *what)
{
    std::printf("%s %s\n", ok ? "[       OK ]" : "[  FAILED  ]", what);
    (ok ? n_pass : n_fail)++;
}

static const char *k_data = "/usr/share/doc/opencv-doc/examples/data";

static std::string work_dir()
{
    const char *w = std::getenv("RP_CALIB_WORK");
    std::string d = w ? w : "build/calib/work";
    std::string cmd = "mkdir -p '" + d + "'";
    if (std::system(cmd.c_str()) != 0) {
        std::printf("cannot create %s\n", d.c_str());
    }
    return d;
}

static bool exists(const std::string &p)
{
    struct stat st;
    return stat(p.c_str(), &st) == 0;
}

/* The path of an opencv-doc data file, unpacked into the work folder if only a .gz exists;
 * empty if absent. */
static std::string data_file(const std::string &name)
{
    const std::string plain = std::string(k_data) + "/" + name;
    if (exists(plain)) {
        return plain;
    }
    const std::string out = work_dir() + "/" + name;
    if (exists(plain + ".gz")) {
        const std::string cmd = "gzip -dc '" + plain + ".gz' > '" + out + "'";
        if (std::system(cmd.c_str()) == 0) {
            return out;
        }
    }
    return std::string();
}

static std::vector<std::string> set_files(const char *side)
{
    std::vector<std::string> f;
    for (int i = 1; i <= 14; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "%s%02d.jpg", side, i);
        const std::string p = data_file(name);
        if (!p.empty()) {
            f.push_back(p);
        }
    }
    return f;
}

static std::vector<rpc::View> detect(const std::vector<std::string> &files, cv::Size *size)
{
    std::vector<rpc::View> v;
    for (const std::string &f : files) {
        v.push_back(rpc::detect_board(f, rpc::Board(), size));
    }
    return v;
}

static rpc::Intrinsics g_left, g_right;
static std::vector<rpc::View> g_vl, g_vr;

static void test_published_intrinsics()
{
    cv::Size size;
    g_vl = detect(set_files("left"), &size);
    size_t found = 0;
    for (const rpc::View &v : g_vl) {
        found += v.found ? 1u : 0u;
    }
    std::printf("  left images: %zu, board found in %zu\n", g_vl.size(), found);
    check(g_vl.size() == 13 && found == 13, "opencv-doc: 13 left images (left10 is not shipped), all with the board");
    rpc::IntrinsicsOpts o;
    o.fix_aspect = true;
    std::string why;
    const bool ok = rpc::calibrate_intrinsics(g_vl, rpc::Board(), size, o, &g_left, &why);
    check(ok, "left camera calibrated");
    if (!ok) {
        std::printf("  %s\n", why.c_str());
        return;
    }
    double fx = 535.9, cx = 342.3, cy = 235.6, rms = 0.3926;
    const std::string yml = data_file("left_intrinsics.yml");
    if (!yml.empty()) {
        cv::FileStorage fs(yml, cv::FileStorage::READ);
        cv::Mat K;
        fs["camera_matrix"] >> K;
        fs["avg_reprojection_error"] >> rms;
        if (K.rows == 3) {
            fx = K.at<double>(0, 0);
            cx = K.at<double>(0, 2);
            cy = K.at<double>(1, 2);
        }
    }
    const rpc::Intrinsics &k = g_left;
    std::printf("  rigpose-calib: fx %.3f fy %.3f cx %.3f cy %.3f RMS %.4f px\n", k.K(0, 0),
                k.K(1, 1), k.K(0, 2), k.K(1, 2), k.rms_px);
    std::printf("  published:     fx %.3f cx %.3f cy %.3f RMS %.4f px (%s)\n", fx, cx, cy, rms,
                yml.empty() ? "issue's figures" : "left_intrinsics.yml");
    check(std::fabs(k.K(0, 0) - 535.9) < 1.0 && std::fabs(k.K(0, 2) - 342.3) < 1.0 &&
              std::fabs(k.K(1, 2) - 235.6) < 1.0,
          "fx, cx, cy within 1 px of 535.9 / 342.3 / 235.6");
    check(std::fabs(k.K(0, 0) - fx) < 1.0 && std::fabs(k.K(0, 2) - cx) < 1.0 &&
              std::fabs(k.K(1, 2) - cy) < 1.0,
          "fx, cx, cy within 1 px of left_intrinsics.yml");
    check(std::fabs(k.K(0, 0) - k.K(1, 1)) < 1e-9, "aspect ratio fixed (fx = fy)");
    check(std::fabs(k.rms_px - rms) < 0.05, "RMS within 0.05 px of the published value");
    double worst = 0.0;
    for (double r : k.view_rms_px) {
        worst = std::max(worst, r);
    }
    std::printf("  worst view RMS %.3f px over %zu views\n", worst, k.view_rms_px.size());
    check(k.view_rms_px.size() == 13 && worst < 2.0, "per-view RMS reported for every view");
}

static void test_stereo()
{
    cv::Size size;
    g_vr = detect(set_files("right"), &size);
    rpc::IntrinsicsOpts o;
    o.fix_aspect = true;
    std::string why;
    bool ok = g_vr.size() == g_vl.size() &&
              rpc::calibrate_intrinsics(g_vr, rpc::Board(), size, o, &g_right, &why);
    check(ok, "right camera calibrated");
    rpc::Stereo s;
    ok = ok && rpc::calibrate_stereo(g_vl, g_vr, rpc::Board(), g_left, g_right, &s, &why);
    check(ok, "stereo pair calibrated");
    if (!ok) {
        std::printf("  %s\n", why.c_str());
        return;
    }
    double lo = 1e9, hi = 0.0;
    for (double b : s.pair_baseline_m) {
        lo = std::min(lo, b);
        hi = std::max(hi, b);
    }
    std::printf("  %d pairs, stereo RMS %.4f px, baseline %.5f m, per-pair %.5f..%.5f m\n",
                s.n_pairs, s.rms_px, s.baseline_m, lo, hi);
    check(s.n_pairs == 13, "13 pairs used");
    check(lo > 0.95 * s.baseline_m && hi < 1.05 * s.baseline_m,
          "baseline consistent: every pair's own estimate within 5 %");
    check(std::fabs(s.left_in_right.t[0]) > 0.95 * s.baseline_m,
          "the pair is side by side (T mostly along x)");
    /* epipolar distance of the undistorted corners under F */
    double sum = 0.0, worst = 0.0;
    int n = 0;
    for (size_t i = 0; i < g_vl.size(); ++i) {
        if (!g_vl[i].found || !g_vr[i].found) {
            continue;
        }
        std::vector<cv::Point2f> ul, ur;
        cv::undistortPoints(g_vl[i].corners, ul, cv::Mat(g_left.K), g_left.dist, cv::noArray(),
                            cv::Mat(g_left.K));
        cv::undistortPoints(g_vr[i].corners, ur, cv::Mat(g_right.K), g_right.dist, cv::noArray(),
                            cv::Mat(g_right.K));
        for (size_t j = 0; j < ul.size(); ++j) {
            const cv::Vec3d xl(ul[j].x, ul[j].y, 1.0), xr(ur[j].x, ur[j].y, 1.0);
            const cv::Vec3d line = s.F * xl;
            const double d = std::fabs(xr.dot(line)) / std::hypot(line[0], line[1]);
            sum += d;
            worst = std::max(worst, d);
            ++n;
        }
    }
    std::printf("  epipolar distance of %d undistorted corners: mean %.3f px, worst %.3f px\n", n,
                sum / n, worst);
    check(sum / n < 0.5 && worst < 5.0, "corners on their epipolar lines (mean < 0.5 px)");
}

static void test_bad_files()
{
    const std::string w = work_dir();
    const std::string left01 = data_file("left01.jpg");
    std::string data;
    {
        std::ifstream in(left01, std::ios::binary);
        data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const std::string trunc = w + "/truncated.jpg", text = w + "/text.jpg",
                      blank = w + "/blank.png", small = w + "/small.png";
    std::ofstream(trunc, std::ios::binary).write(data.data(), static_cast<std::streamsize>(data.size() / 50));
    std::ofstream(text) << "not an image\n";
    cv::imwrite(blank, cv::Mat(480, 640, CV_8U, cv::Scalar(128)));
    cv::imwrite(small, cv::Mat(240, 320, CV_8U, cv::Scalar(128)));
    const char *files[] = {"/nonexistent/x.jpg", trunc.c_str(), text.c_str(), blank.c_str(),
                           small.c_str()};
    bool all_rejected = true;
    for (const char *f : files) {
        cv::Size size(640, 480);
        const rpc::View v = rpc::detect_board(f, rpc::Board(), &size);
        std::printf("  %s: %s\n", f, v.found ? "found?!" : v.why.c_str());
        all_rejected = all_rejected && !v.found && !v.why.empty();
    }
    check(all_rejected, "missing, truncated, non-image, board-less, wrong-size files each rejected with a reason");
    cv::Size size(640, 480);
    check(rpc::detect_board(left01, rpc::Board(), &size).found, "a good file after them still found");
}

/* Synthetic hand-eye: cameras k at a known pose X in cam1, each looking at its own static board;
 * the rig makes n random moves; board poses from solvePnP on noisy projected corners. */
static void hand_eye_case(const char *name, const rpc::Pose &X, double noise_px, double tol_deg,
                          double tol_m)
{
    std::mt19937 rng(42);
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    const cv::Matx33d K(600, 0, 320, 0, 600, 240, 0, 0, 1);
    const rpc::Board board;
    const std::vector<cv::Point3f> obj = board.object_points();
    /* boards 0.6 m in front of each camera at the start, centred on its axis (world = cam1 at
     * the start) */
    auto board_in_world = [&](const rpc::Pose &cam_in_world) {
        rpc::Pose b;
        b.R = cam_in_world.R;
        b.t = cam_in_world.R * cv::Vec3d(-0.1, -0.0625, 0.6) + cam_in_world.t;
        return b;
    };
    const rpc::Pose B1 = board_in_world(rpc::Pose()), Bk = board_in_world(X);
    std::vector<rpc::Pose> p1, pk;
    std::vector<std::vector<cv::Point2f>> c1, ck;
    auto observe = [&](const rpc::Pose &board_in_cam, rpc::Pose *est,
                       std::vector<std::vector<cv::Point2f>> *corners) {
        std::vector<cv::Point2f> px;
        for (const cv::Point3f &o : obj) {
            const cv::Vec3d c = board_in_cam.R * cv::Vec3d(o.x, o.y, o.z) + board_in_cam.t;
            px.emplace_back(static_cast<float>(K(0, 0) * c[0] / c[2] + K(0, 2) + noise_px * gauss(rng)),
                            static_cast<float>(K(1, 1) * c[1] / c[2] + K(1, 2) + noise_px * gauss(rng)));
        }
        corners->push_back(px);
        cv::Mat rv, tv, R;
        cv::solvePnP(obj, px, cv::Mat(K), cv::noArray(), rv, tv, false, cv::SOLVEPNP_ITERATIVE);
        cv::Rodrigues(rv, R);
        est->R = cv::Matx33d(R);
        est->t = cv::Vec3d(tv.at<double>(0), tv.at<double>(1), tv.at<double>(2));
    };
    for (int i = 0; i < 15; ++i) {
        /* rig (cam1) in the world: rotations up to 0.35 rad about every axis, 0.1 m moves */
        cv::Mat R;
        cv::Rodrigues(cv::Vec3d(0.35 * uni(rng), 0.35 * uni(rng), 0.35 * uni(rng)), R);
        rpc::Pose rig;
        rig.R = cv::Matx33d(R);
        rig.t = cv::Vec3d(0.1 * uni(rng), 0.1 * uni(rng), 0.1 * uni(rng));
        rpc::Pose e1, ek;
        observe(rig.inv() * B1, &e1, &c1);
        observe((rig * X).inv() * Bk, &ek, &ck);
        p1.push_back(e1);
        pk.push_back(ek);
    }
    rpc::Pose est;
    double er = 0.0, et = 0.0;
    std::string why;
    bool ok = rpc::hand_eye(p1, pk, &est, &er, &et, &why);
    auto errors = [&](double *rot_deg, double *dt) {
        cv::Mat dr;
        cv::Rodrigues(cv::Mat(est.R * X.R.t()), dr);
        *rot_deg = cv::norm(dr) * 180.0 / CV_PI;
        *dt = cv::norm(est.t - X.t);
    };
    double rot_deg, dt, rms = 0.0;
    errors(&rot_deg, &dt);
    std::printf("  %s, %.1f px noise, 15 sets: hand-eye (Park) rotation error %.4f deg, position "
                "error %.3f mm (residuals %.4f deg, %.3f mm)\n", name, noise_px, rot_deg, dt * 1e3,
                er * 180.0 / CV_PI, et * 1e3);
    rpc::Intrinsics kin;
    kin.K = K;
    ok = ok && rpc::refine_extrinsics(c1, ck, kin, kin, board, &est, &rms, &why);
    errors(&rot_deg, &dt);
    std::printf("  %s, %.1f px noise, 15 sets: after bundle adjustment rotation error %.4f deg, "
                "position error %.3f mm (reprojection RMS %.3f px)\n", name, noise_px, rot_deg,
                dt * 1e3, rms);
    char what[160];
    std::snprintf(what, sizeof what, "hand-eye %s at %.1f px: within %.3g deg and %.3g mm", name,
                  noise_px, tol_deg, tol_m * 1e3);
    check(ok && rot_deg < tol_deg && dt < tol_m, what);
}

static void test_hand_eye()
{
    rpc::Pose cam2, cam3;
    cam2.R = cv::Matx33d(0, 0, 1, 0, 1, 0, -1, 0, 0); /* looking +x (docs/design.md) */
    cam2.t = cv::Vec3d(0.0866025403784439, 0, -0.05);
    cam3.R = cv::Matx33d(-1, 0, 0, 0, 1, 0, 0, 0, -1); /* looking -z */
    cam3.t = cv::Vec3d(0, 0, -0.1);
    hand_eye_case("cam2", cam2, 0.0, 1e-5, 1e-6);
    hand_eye_case("cam3", cam3, 0.0, 1e-5, 1e-6);
    hand_eye_case("cam2", cam2, 0.2, 0.25, 0.005);
    hand_eye_case("cam3", cam3, 0.2, 0.25, 0.005);
    /* degenerate motion: rotations about one axis only cannot fix the offset along it */
    std::vector<rpc::Pose> a(2), b(2);
    rpc::Pose x;
    double er, et;
    std::string why;
    check(!rpc::hand_eye(a, b, &x, &er, &et, &why) && !why.empty(),
          "hand-eye refuses fewer than 3 sets, with a reason");
}

/* The whole rig through the program: synthetic chessboard images of five cameras (the paper's
 * cam1..cam4, each with its own board, and cam1's stereo partner sharing cam1's board) over 20
 * rig poses, rendered by warping a board texture (fx = fy = 600, 640x480, no distortion);
 * `rigpose-calib rig --pair cam0,cam4 --intrinsics` (the intrinsics known from earlier
 * calibrations) must return every camera's position and rotation in cam1's frame. */
static void test_rig_program()
{
    const char *bin = std::getenv("RP_CALIB_BIN");
    if (!bin) {
        bin = "build/release/rigpose-calib";
    }
    const std::string dir = work_dir() + "/rig";
    if (std::system(("rm -rf '" + dir + "' && mkdir -p '" + dir + "'").c_str()) != 0) {
        check(false, "rig folder created");
        return;
    }
    const double sq = 0.03, ppsq = 40.0; /* square side, m; texture px per square */
    const cv::Size inner(9, 6);
    cv::Mat tex((inner.height + 3) * 40, (inner.width + 3) * 40, CV_8U, cv::Scalar(255));
    for (int r = 0; r < inner.height + 1; ++r) {
        for (int c = 0; c < inner.width + 1; ++c) {
            if ((r + c) % 2 == 0) {
                tex(cv::Rect((c + 1) * 40, (r + 1) * 40, 40, 40)).setTo(cv::Scalar(0));
            }
        }
    }
    /* texture px (pixel centres) -> board plane (m): the first inner corner at the origin */
    const cv::Matx33d A(sq / ppsq, 0, -(2 * ppsq - 0.5) * sq / ppsq, 0, sq / ppsq,
                        -(2 * ppsq - 0.5) * sq / ppsq, 0, 0, 1);
    const cv::Matx33d K(600, 0, 319.5, 0, 600, 239.5, 0, 0, 1);
    std::vector<rpc::Pose> cams(5);
    cams[1].R = cv::Matx33d(0, 0, 1, 0, 1, 0, -1, 0, 0);
    cams[1].t = cv::Vec3d(0.0866025403784439, 0, -0.05);
    cams[2].R = cv::Matx33d(-1, 0, 0, 0, 1, 0, 0, 0, -1);
    cams[2].t = cv::Vec3d(0, 0, -0.1);
    cams[3].R = cv::Matx33d(0, 0, -1, 0, 1, 0, 1, 0, 0);
    cams[3].t = cv::Vec3d(-0.0866025403784439, 0, -0.05);
    cams[4].t = cv::Vec3d(0.1, 0, 0);
    /* each board 0.8 m in front of its camera at the start (cam1b shares cam1's) */
    std::vector<rpc::Pose> boards(4);
    for (int k = 0; k < 4; ++k) {
        boards[static_cast<size_t>(k)].R = cams[static_cast<size_t>(k)].R;
        boards[static_cast<size_t>(k)].t =
            cams[static_cast<size_t>(k)].R * cv::Vec3d(-4 * sq, -2.5 * sq, 0.8) + cams[static_cast<size_t>(k)].t;
    }
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::ofstream csv(dir + "/frames.csv");
    csv << "utime_us,cam0,cam1,cam2,cam3,cam4\n";
    for (int i = 0; i < 20; ++i) {
        cv::Mat Rm;
        cv::Rodrigues(cv::Vec3d(0.25 * u(rng), 0.25 * u(rng), 0.25 * u(rng)), Rm);
        rpc::Pose rig;
        rig.R = cv::Matx33d(Rm);
        rig.t = cv::Vec3d(0.04 * u(rng), 0.04 * u(rng), 0.04 * u(rng));
        csv << i * 33333;
        for (int k = 0; k < 5; ++k) {
            const rpc::Pose b = (rig * cams[static_cast<size_t>(k)]).inv() * boards[static_cast<size_t>(k == 4 ? 0 : k)];
            const cv::Matx33d P(b.R(0, 0), b.R(0, 1), b.t[0], b.R(1, 0), b.R(1, 1), b.t[1], b.R(2, 0),
                                b.R(2, 1), b.t[2]);
            cv::Mat img;
            cv::warpPerspective(tex, img, cv::Mat(K * P * A), cv::Size(640, 480), cv::INTER_AREA,
                                cv::BORDER_CONSTANT, cv::Scalar(160));
            char name[32];
            std::snprintf(name, sizeof name, "c%d_%02d.png", k, i);
            cv::imwrite(dir + "/" + name, img);
            csv << "," << name;
        }
        csv << "\n";
    }
    csv.close();
    /* the cameras' intrinsics as an earlier per-camera calibration would give them */
    std::ofstream known(dir + "/intrinsics.yaml");
    for (int k = 0; k < 5; ++k) {
        known << "  - name: c" << k << "\n    width: 640\n    height: 480\n"
              << "    intrinsics: [600, 600, 319.5, 239.5]\n    distortion: [0, 0, 0, 0, 0]\n";
    }
    known.close();
    const std::string out = dir + "/rig.yaml", log = dir + "/calib.out";
    const std::string cmd = std::string(bin) + " rig --square 0.03 --frames '" + dir +
                            "/frames.csv' --pair cam0,cam4 --intrinsics '" + dir +
                            "/intrinsics.yaml' --out '" + out + "' > '" + log + "' 2>&1";
    const int rc = std::system(cmd.c_str());
    check(rc == 0, "rigpose-calib rig on the synthetic rig: exit 0");
    /* positions and rotations, in camera order, from the YAML */
    std::ifstream y(out), l(log);
    std::string line;
    while (std::getline(l, line)) {
        if (line.find("view RMS") == std::string::npos) {
            std::printf("  | %s\n", line.c_str());
        }
    }
    std::vector<cv::Vec3d> pos;
    std::vector<cv::Matx33d> rot;
    while (std::getline(y, line)) {
        const size_t b = line.find('[');
        if (line.find("position:") != std::string::npos && b != std::string::npos) {
            cv::Vec3d p;
            std::sscanf(line.c_str() + b, "[%lf, %lf, %lf]", &p[0], &p[1], &p[2]);
            pos.push_back(p);
        } else if (line.find("rotation:") != std::string::npos && b != std::string::npos) {
            cv::Matx33d R;
            double *r = R.val;
            std::sscanf(line.c_str() + b, "[%lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf, %lf]", r, r + 1,
                        r + 2, r + 3, r + 4, r + 5, r + 6, r + 7, r + 8);
            rot.push_back(R);
        }
    }
    bool ok = pos.size() == 5 && rot.size() == 5;
    double worst_mm = 0.0, worst_deg = 0.0;
    for (size_t k = 0; ok && k < 5; ++k) {
        cv::Mat dr;
        cv::Rodrigues(cv::Mat(rot[k] * cams[k].R.t()), dr);
        const double e_mm = cv::norm(pos[k] - cams[k].t) * 1e3, e_deg = cv::norm(dr) * 180.0 / CV_PI;
        std::printf("  cam%zu: position error %.2f mm, rotation error %.3f deg\n", k + 1, e_mm, e_deg);
        worst_mm = std::max(worst_mm, e_mm);
        worst_deg = std::max(worst_deg, e_deg);
    }
    check(ok && worst_mm < 8.0 && worst_deg < 0.5,
          "rig extrinsics (hand-eye + bundle adjustment, stereo partner) within 8 mm and 0.5 deg");
}

int main()
{
    if (data_file("left01.jpg").empty()) {
        std::printf("[  FAILED  ] opencv-doc's chessboard images not found under %s\n", k_data);
        return 1;
    }
    test_published_intrinsics();
    test_stereo();
    test_bad_files();
    test_hand_eye();
    test_rig_program();
    std::printf("%s %d test(s).\n", n_fail ? "[  FAILED  ]" : "[  PASSED  ]", n_fail ? n_fail : n_pass);
    return n_fail ? 1 : 0;
}
