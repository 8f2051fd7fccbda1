/*
 * test_realdata_conv.cpp - rp_realdata's conversions and scoring, and (when the data is there)
 * its loaders: pose vector round trip in the paper's angles, transform algebra, the ATE / RPE
 * of a known error, the KITTI and EuRoC rigs and first frames, and the dense direct yardstick
 * (rp_direct.hpp) on a few KITTI frames; the loaders' traps (issue 14) on small synthetic
 * folders the test writes in /tmp: calib.txt with and without labels, image_l/image_r and
 * other folder names, no times.txt (--fps), missing images, EuRoC's own ground-truth csv
 * against TUM, --first counting stereo frames, the first pose of a wrong-order TUM file. Run by `make test`; prints one line per check and a
 * cmocka-style summary.
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <filesystem>
#include <sys/stat.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "rp_direct.hpp"
#include "rp_mirror.hpp"
#include "rp_rectify.hpp"
#include "rp_realdata.hpp"
#include "../../calib/rp_timesync.hpp"

namespace {

int n_pass = 0, n_fail = 0;

void check(bool ok, const char *what, double value)
{
    std::printf("[%s] %s (%.9g)\n", ok ? "       OK " : "  FAILED  ", what, value);
    (ok ? n_pass : n_fail)++;
}

double pose_diff(const rprd::Pose &a, const rprd::Pose &b)
{
    double d = 0.0;
    for (int i = 0; i < 9; ++i) {
        d = std::fmax(d, std::fabs(a.R[i] - b.R[i]));
    }
    for (int i = 0; i < 3; ++i) {
        d = std::fmax(d, std::fabs(a.t[i] - b.t[i]));
    }
    return d;
}

double length(const rprd::Pose &T)
{
    return std::sqrt(T.t[0] * T.t[0] + T.t[1] * T.t[1] + T.t[2] * T.t[2]);
}

/* Rotation angle of a pose, degrees. */
double angle_deg(const rprd::Pose &T)
{
    const double c = (T.R[0] + T.R[4] + T.R[8] - 1.0) / 2.0;
    return std::acos(std::fmin(1.0, std::fmax(-1.0, c))) * 180.0 / M_PI;
}

/* The dense direct yardstick on KITTI: 3 steps of frames 20-23 (where the truth is a real
 * measurement) agree with the truth, whatever the start; 3 steps of frames 0-3 do not (the
 * truth's extrapolated start, README.md); a distorted pair is refused. */
void check_direct(const std::string &kitti, const rprd::Sequence &euroc)
{
    rprd::Sequence k;
    std::string err;
    if (!rprd::load_kitti(kitti, 20, 4, &k, &err)) {
        check(false, ("direct: KITTI frames 20-23: " + err).c_str(), 0.0);
        return;
    }
    rprd::DirectOpts o;
    std::vector<rprd::Pose> traj, steps, traj2, steps2;
    const bool ok = rprd::direct_reference(k, o, &traj, &steps, &err);
    o.start_step_m = 0.3;
    const bool ok2 = rprd::direct_reference(k, o, &traj2, &steps2, &err);
    check(ok && ok2 && steps.size() == 3 && traj.size() == 4, "direct: 3 steps, 4 poses", 0.0);
    if (!ok || !ok2 || steps.size() != 3) {
        return;
    }
    double worst_len = 0.0, worst_rot = 0.0, worst_start = 0.0;
    for (size_t j = 1; j < 4; ++j) {
        const rprd::Pose truth = rprd::pose_mul(rprd::pose_inv(k.truth[j - 1]), k.truth[j]);
        const rprd::Pose est = rprd::pose_inv(steps[j - 1]);
        worst_len = std::fmax(worst_len, std::fabs(length(est) / length(truth) - 1.0));
        worst_rot = std::fmax(worst_rot, angle_deg(rprd::pose_mul(rprd::pose_inv(est), truth)));
        worst_start = std::fmax(worst_start, pose_diff(steps[j - 1], steps2[j - 1]));
    }
    check(worst_len < 0.02, "direct: KITTI steps 20-23 within 2 % of the truth's length",
          worst_len);
    check(worst_rot < 0.05, "direct: ... and within 0.05 deg of its rotation", worst_rot);
    check(worst_start < 1e-4, "direct: same steps from a 0.3 m start as from none",
          worst_start);
    rprd::Sequence s0;
    if (rprd::load_kitti(kitti, 0, 4, &s0, &err) &&
        rprd::direct_reference(s0, rprd::DirectOpts(), &traj, &steps, &err)) {
        double longest = 0.0, truth_shortest = 1e9;
        for (size_t j = 1; j < 4; ++j) {
            longest = std::fmax(longest, length(steps[j - 1]));
            truth_shortest = std::fmin(
                truth_shortest, length(rprd::pose_mul(rprd::pose_inv(s0.truth[j - 1]), s0.truth[j])));
        }
        check(longest < 0.75 && truth_shortest > 0.85,
              "direct: KITTI frames 0-3: images under 0.75 m a step, truth over 0.85 m", longest);
    } else {
        check(false, ("direct: KITTI frames 0-3: " + err).c_str(), 0.0);
    }
    err.clear();
    const bool refused = !rprd::direct_reference(euroc, rprd::DirectOpts(), &traj, nullptr, &err);
    check(refused && !err.empty(), ("direct: a distorted pair is refused: " + err).c_str(), 0.0);

    /* ... and rectified (rp_rectify.hpp) it is taken: EuRoC's first frames rectified into a
     * temporary folder; the truth in the rectified frame keeps every distance and angle, and
     * the direct yardstick's steps on it follow the truth's to a centimetre */
    char tmpl[] = "/tmp/rp_rect_test_XXXXXX";
    if (!mkdtemp(tmpl)) {
        check(false, "rectify: mkdtemp", 0.0);
        return;
    }
    rprd::Sequence few = euroc, r;
    const size_t nf = std::min<size_t>(6, few.utime.size());
    few.utime.resize(nf);
    few.img[0].resize(nf);
    few.img[1].resize(nf);
    few.truth.resize(nf);
    err.clear();
    const bool okr = rprd::rectify_sequence(few, tmpl, &r, &err);
    check(okr && !rprd::is_rectified(few) && rprd::is_rectified(r),
          ("rectify: EuRoC's pair is not rectified, its copy is" + err).c_str(), 0.0);
    double worst_d = 0.0, worst_a = 0.0, worst_s = 0.0;
    std::vector<rprd::Pose> rt;
    if (okr) {
        for (size_t j = 0; j < nf; ++j) {
            worst_d = std::fmax(worst_d, std::fabs(length(r.truth[j]) - length(few.truth[j])));
            worst_a = std::fmax(worst_a, std::fabs(angle_deg(r.truth[j]) - angle_deg(few.truth[j])));
        }
        if (rprd::direct_reference(r, rprd::DirectOpts(), &rt, nullptr, &err) && rt.size() == nf) {
            for (size_t j = 0; j < nf; ++j) {
                double d = 0.0;
                for (int i = 0; i < 3; ++i) {
                    d += (rt[j].t[i] - r.truth[j].t[i]) * (rt[j].t[i] - r.truth[j].t[i]);
                }
                worst_s = std::fmax(worst_s, std::sqrt(d));
            }
        } else {
            worst_s = 1e9;
        }
    }
    check(worst_d < 1e-9 && worst_a < 1e-6, "rectify: the truth keeps its distances and angles",
          std::fmax(worst_d, worst_a));
    check(worst_s < 0.01, "rectify: the direct yardstick on it within 1 cm of the truth", worst_s);
    std::error_code ec;
    std::filesystem::remove_all(tmpl, ec);
}

bool is_dir(const std::string &p)
{
    struct stat st;
    return stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}


/* ---- synthetic folders written by the test (the loaders' traps, issue 14 item 5) ---------- */

std::string g_tmp; /* this run's temporary folder */

void put(const std::string &path, const std::string &text)
{
    FILE *f = std::fopen(path.c_str(), "w");
    if (f) {
        std::fputs(text.c_str(), f);
        std::fclose(f);
    }
}

void mkdirs(const std::string &path)
{
    std::string cur;
    for (size_t i = 0; i <= path.size(); ++i) {
        if (i == path.size() || path[i] == '/') {
            if (!cur.empty()) {
                mkdir(cur.c_str(), 0755);
            }
        }
        if (i < path.size()) {
            cur += path[i];
        }
    }
}

void put_png(const std::string &path)
{
    cv::Mat im(48, 64, CV_8UC1);
    cv::randu(im, 0, 255);
    cv::imwrite(path, im);
}

const char *const kP0 = "718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0";
const char *const kP1 = "718.856 0 607.1928 -386.1448 0 718.856 185.2157 0 0 0 1 0";

/* A KITTI folder of n frames: calib labelled or not, image folders l/r, times.txt or not;
 * frame j 1 m ahead of frame j-1 (z) and turned 0.01 rad about y. */
std::string make_kitti(const std::string &name, bool labels, const std::string &l,
                       const std::string &r, bool times, int n)
{
    const std::string d = g_tmp + "/" + name;
    mkdirs(d + "/" + l);
    mkdirs(d + "/" + r);
    put(d + "/calib.txt", labels ? std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\nP2: " + kP0 + "\n"
                                 : std::string(kP0) + "\n" + kP1 + "\n" + kP0 + "\n");
    std::string poses, ts;
    for (int j = 0; j < n; ++j) {
        const double a = 0.01 * j, c = std::cos(a), si = std::sin(a);
        char line[256];
        std::snprintf(line, sizeof line, "%.9f 0 %.9f 0 0 1 0 0 %.9f 0 %.9f %d\n", c, si, -si, c, j);
        poses += line;
        std::snprintf(line, sizeof line, "%.6f\n", 0.1 * j);
        ts += line;
        char img[32];
        std::snprintf(img, sizeof img, "/%06d.png", j);
        put_png(d + "/" + l + img);
        put_png(d + "/" + r + img);
    }
    put(d + "/poses.txt", poses);
    if (times) {
        put(d + "/times.txt", ts);
    }
    return d;
}

const char *const kSensor0 =
    "sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n"
    "rate_hz: 20\nresolution: [64, 48]\ncamera_model: pinhole\nintrinsics: [50, 50, 31.5, 23.5]\n"
    "distortion_model: radial-tangential\ndistortion_coefficients: [-0.28, 0.07, 0.0002, 0.00002]\n";
const char *const kSensor1 =
    "sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1, 0, 0, 0.11, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n"
    "rate_hz: 20\nresolution: [64, 48]\ncamera_model: pinhole\nintrinsics: [50, 50, 31.5, 23.5]\n"
    "distortion_model: radial-tangential\ndistortion_coefficients: [-0.28, 0.07, 0.0002, 0.00002]\n";

/* An EuRoC folder of n frames at 20 Hz from t0; cam1 lacks frame `skip1` (-1: none); the image
 * of cam0's frame `missing` is not written (-1: all are); the truth as TUM groundtruth.txt
 * (tum) or EuRoC's own csv. Body pose at frame j: x = 0.1 j, rotated 0.02 j rad about z. */
const long long kT0 = 1403636584763555584LL;
std::string make_euroc(const std::string &name, int n, int skip1, int missing, bool tum)
{
    const std::string d = g_tmp + "/" + name;
    std::string list[2] = {"#timestamp [ns],filename\n", "#timestamp [ns],filename\n"};
    for (int k = 0; k < 2; ++k) {
        mkdirs(d + "/cam" + std::to_string(k) + "/data");
        put(d + "/cam" + std::to_string(k) + "/sensor.yaml", k ? kSensor1 : kSensor0);
    }
    std::string gt = tum ? "# timestamp(s) tx ty tz qx qy qz qw\n"
                         : "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], "
                           "q_RS_x [], q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y, "
                           "v_RS_R_z, b_w_x, b_w_y, b_w_z, b_a_x, b_a_y, b_a_z\n";
    for (int j = 0; j < n; ++j) {
        const long long t = kT0 + 50000000LL * j;
        for (int k = 0; k < 2; ++k) {
            if (k == 1 && j == skip1) {
                continue;
            }
            const std::string f = std::to_string(t) + ".png";
            list[k] += std::to_string(t) + "," + f + "\n";
            if (!(k == 0 && j == missing)) {
                put_png(d + "/cam" + std::to_string(k) + "/data/" + f);
            }
        }
        const double h = 0.01 * j; /* half angle */
        char line[320];
        if (tum) {
            std::snprintf(line, sizeof line, "%.6f %.6f 0.5 0.25 0 0 %.9f %.9f\n", (double)t * 1e-9,
                          0.1 * j, std::sin(h), std::cos(h));
        } else {
            std::snprintf(line, sizeof line, "%lld,%.6f,0.5,0.25,%.9f,0,0,%.9f,0,0,0,0,0,0,0,0,0\n",
                          t, 0.1 * j, std::cos(h), std::sin(h));
        }
        gt += line;
    }
    put(d + "/cam0/data.csv", list[0]);
    put(d + "/cam1/data.csv", list[1]);
    if (tum) {
        put(d + "/groundtruth.txt", gt);
    } else {
        mkdirs(d + "/state_groundtruth_estimate0");
        put(d + "/state_groundtruth_estimate0/data.csv", gt);
    }
    return d;
}

bool has(const std::string &text, const std::string &part)
{
    return text.find(part) != std::string::npos;
}

void check_mirror(const char *what, const rprd::Sequence &s);

void check_loaders_synthetic()
{
    char tmpl[] = "/tmp/rp_realdata_test_XXXXXX";
    const char *t = mkdtemp(tmpl);
    if (!t) {
        check(false, "synthetic folders: mkdtemp", 0.0);
        return;
    }
    g_tmp = t;
    std::string err;
    rprd::Sequence a, b;
    /* KITTI calib with and without labels: the same rig */
    const std::string kl = make_kitti("k_labels", true, "image_0", "image_1", true, 5);
    const std::string ku = make_kitti("k_bare", false, "image_0", "image_1", true, 5);
    const bool ok_l = rprd::load_kitti(kl, 0, 0, &a, &err);
    check(ok_l && a.utime.size() == 5, ("KITTI: labelled calib.txt loads " + err).c_str(), 0.0);
    const bool ok_u = rprd::load_kitti(ku, 0, 0, &b, &err);
    check(ok_u && b.utime.size() == 5, ("KITTI: calib.txt without P0:/P1: labels loads " + err).c_str(), 0.0);
    if (ok_l && ok_u) {
        check(std::fabs((double)b.rig.cam[1].D[0] - 386.1448 / 718.856) < 1e-12 &&
                  b.rig.cam[0].cam.cx == a.rig.cam[0].cam.cx && b.rig.cam[0].cam.width == 64,
              "KITTI: ... the same rig (baseline, cx, image size)", (double)b.rig.cam[1].D[0]);
        check(has(b.notes[0], "no P0/P1 labels"), ("KITTI: ... and says so: " + b.notes[0]).c_str(), 0.0);
    }
    /* image_l / image_r found by itself, or given */
    const std::string klr = make_kitti("k_lr", true, "image_l", "image_r", true, 3);
    const bool ok_lr = rprd::load_kitti(klr, 0, 0, &a, &err);
    check(ok_lr && a.img[1][2] == klr + "/image_r/000002.png",
          ("KITTI: image_l/ + image_r/ found " + err).c_str(), 0.0);
    const std::string kc = make_kitti("k_custom", true, "cam_a", "cam_b", true, 3);
    err.clear();
    const bool ok_c = rprd::load_kitti(kc, 0, 0, &a, &err);
    check(!ok_c && has(err, "image_0/") && has(err, "image_l/") && has(err, "left/") &&
              has(err, "--images"),
          ("KITTI: unknown folders refused naming all tried: " + err).c_str(), 0.0);
    rprd::LoadOpts o;
    o.left = "cam_a";
    o.right = "cam_b";
    const bool ok_c2 = rprd::load_kitti(kc, o, &a, &err);
    check(ok_c2 && a.img[0][1] == kc + "/cam_a/000001.png", "KITTI: ... and loads with --images cam_a,cam_b", 0.0);
    /* times.txt optional with --fps */
    const std::string kn = make_kitti("k_notimes", true, "image_0", "image_1", false, 4);
    err.clear();
    const bool ok_n = rprd::load_kitti(kn, 0, 0, &a, &err);
    check(!ok_n && has(err, "times.txt") && has(err, "--fps"),
          ("KITTI: no times.txt and no --fps: refused naming --fps: " + err).c_str(), 0.0);
    rprd::LoadOpts of;
    of.fps = 10.0;
    of.first = 1;
    const bool ok_f = rprd::load_kitti(kn, of, &a, &err);
    check(ok_f && a.utime.size() == 3 && a.utime[0] == 100000 && a.utime[2] == 300000,
          "KITTI: --fps 10 --first 1: frames 1-3 at 0.1, 0.2, 0.3 s", ok_f ? (double)a.utime[0] : -1.0);
    /* a missing KITTI image: the first one named */
    std::remove((kl + "/image_1/000003.png").c_str());
    err.clear();
    const bool ok_m = rprd::load_kitti(kl, 0, 0, &a, &err);
    check(!ok_m && has(err, "image_1/000003.png"), ("KITTI: a missing image is named: " + err).c_str(), 0.0);

    /* EuRoC: the native csv (qw first) and TUM (qw last) of the same poses give the same truth */
    const std::string et = make_euroc("e_tum", 6, -1, -1, true);
    const std::string en = make_euroc("e_native", 6, -1, -1, false);
    err.clear();
    const bool ok_t = rprd::load_euroc(et, 0, 0, &a, &err);
    const bool ok_e = rprd::load_euroc(en, 0, 0, &b, &err);
    check(ok_t && ok_e && a.utime.size() == 6 && b.utime.size() == 6,
          ("EuRoC: TUM groundtruth.txt and state_groundtruth_estimate0/data.csv load " + err).c_str(), 0.0);
    if (ok_t && ok_e) {
        double d = 0.0;
        for (size_t j = 0; j < 6; ++j) {
            d = std::fmax(d, pose_diff(a.truth[j], b.truth[j]));
        }
        /* frame 5 in frame 0: 0.5 m along the body's x turned 0.1 rad about z */
        const double ang = std::atan2(b.truth[5].R[3], b.truth[5].R[0]);
        check(d < 1e-9, "EuRoC: ... the same truth from both formats", d);
        check(std::fabs(ang - 0.1) < 1e-9 && std::fabs(b.truth[5].t[0] - 0.5) < 1e-9,
              "EuRoC native csv: frame 5 at x 0.5 m, turned 0.1 rad about z", ang);
        check(has(b.notes[1], "qw first") && has(b.notes[1], "qw 1.000000") &&
                  has(a.notes[1], "qw last") && has(a.notes[1], "position 0.000000 0.500000 0.250000"),
              ("EuRoC: the truth's columns and first pose printed: " + b.notes[1]).c_str(), 0.0);
    }
    /* a listed image missing: an error naming it */
    const std::string em = make_euroc("e_missing", 6, -1, 2, true);
    err.clear();
    const bool ok_mi = rprd::load_euroc(em, 0, 0, &a, &err);
    check(!ok_mi && has(err, std::to_string(kT0 + 2 * 50000000LL) + ".png") && has(err, "data.csv:4"),
          ("EuRoC: a listed image that is missing is an error naming it: " + err).c_str(), 0.0);
    /* --first counts stereo frames: cam1 lacks frame 1, so frame 2 of the pairs is row 3 */
    const std::string es = make_euroc("e_skip", 6, 1, -1, true);
    const bool ok_s = rprd::load_euroc(es, 2, 0, &a, &err);
    check(ok_s && a.utime.size() == 3 && a.utime[0] == (kT0 + 3 * 50000000LL) / 1000,
          "EuRoC: --first 2 skips 2 stereo frames (cam1 lacks one): starts at row 3", ok_s ? (double)a.utime.size() : -1.0);
    /* a wrong-order TUM file (qw first) is not refused, but its first pose shows it */
    put(et + "/groundtruth.txt", "1403636584.763556 0 0.5 0.25 1 0 0 0\n1403636584.813556 0.1 0.5 0.25 1 0 0 0\n"
                                 "1403636584.863556 0.2 0.5 0.25 1 0 0 0\n1403636584.913556 0.3 0.5 0.25 1 0 0 0\n"
                                 "1403636584.963556 0.4 0.5 0.25 1 0 0 0\n1403636585.013556 0.5 0.5 0.25 1 0 0 0\n");
    const bool ok_w = rprd::load_euroc(et, 0, 0, &a, &err);
    check(ok_w && has(a.notes[1], "qw 0.000000 qx 1.000000"),
          ("EuRoC: a TUM file with qw first shows qx 1 in its first pose: " + a.notes[1]).c_str(), 0.0);
    /* the mirror image of a synthetic KITTI and EuRoC folder (EuRoC: distortion, a rotated pair) */
    make_kitti("k_mirror", true, "image_0", "image_1", true, 4);
    if (rprd::load_kitti(g_tmp + "/k_mirror", 0, 0, &a, &err)) {
        check_mirror("mirror: synthetic KITTI", a);
    }
    const std::string er = make_euroc("e_mirror", 4, -1, -1, true);
    put(er + "/cam1/sensor.yaml",
        "T_BS:\n  data: [0.999997256478, -0.00231713572328, -0.000343393120572, 0.1100741378,\n"
        "    0.00231206719243, 0.999898048507, -0.0140906684527, -0.000156612054393,\n"
        "    0.000376008102368, 0.0140898358467, 0.999900662638, 0.000889382785436, 0, 0, 0, 1]\n"
        "resolution: [64, 48]\nintrinsics: [48, 47, 33.2, 22.1]\n"
        "distortion_model: radial-tangential\ndistortion_coefficients: [-0.2837, 0.0745, -0.0001, -0.00003]\n");
    if (rprd::load_euroc(er, 0, 0, &a, &err)) {
        check_mirror("mirror: synthetic EuRoC", a);
    } else {
        check(false, ("mirror: synthetic EuRoC: " + err).c_str(), 0.0);
    }
    const std::string cmd = "rm -rf '" + g_tmp + "'";
    if (std::system(cmd.c_str()) != 0) {
        std::printf("note: could not remove %s\n", g_tmp.c_str());
    }
}

/* ---- the mirror image (rp_mirror.hpp, issue 14 item 8) ------------------------------------ */

double rig_diff(const rp_rig_t &a, const rp_rig_t &b)
{
    double d = 0.0;
    for (int k = 0; k < 2; ++k) {
        const rp_rig_cam_t &x = a.cam[k], &y = b.cam[k];
        for (int i = 0; i < 9; ++i) {
            d = std::fmax(d, std::fabs((double)(x.R[i] - y.R[i])));
        }
        for (int i = 0; i < 3; ++i) {
            d = std::fmax(d, std::fabs((double)(x.D[i] - y.D[i])));
        }
        const rp_real p[] = {x.cam.fx - y.cam.fx, x.cam.fy - y.cam.fy, x.cam.cx - y.cam.cx,
                             x.cam.cy - y.cam.cy, x.cam.k1 - y.cam.k1, x.cam.k2 - y.cam.k2,
                             x.cam.p1 - y.cam.p1, x.cam.p2 - y.cam.p2, x.cam.k3 - y.cam.k3};
        for (rp_real v : p) {
            d = std::fmax(d, std::fabs((double)v));
        }
        if (x.cam.width != y.cam.width || x.cam.height != y.cam.height) {
            d = 1e9;
        }
    }
    return d;
}

double truth_diff(const rprd::Sequence &a, const rprd::Sequence &b)
{
    if (a.truth.size() != b.truth.size()) {
        return 1e9;
    }
    double d = 0.0;
    for (size_t j = 0; j < a.truth.size(); ++j) {
        d = std::fmax(d, pose_diff(a.truth[j], b.truth[j]));
    }
    return d;
}

rprd::Pose cam_pose(const rp_rig_cam_t &c)
{
    rprd::Pose T;
    for (int i = 0; i < 9; ++i) {
        T.R[i] = (double)c.R[i];
    }
    for (int i = 0; i < 3; ++i) {
        T.t[i] = (double)c.D[i];
    }
    return T;
}

/* Scene points seen by both sequences: the original's camera k at frame j sees X (world) at
 * pixel u; the mirror image's camera 1-k at frame j sees the mirrored point (X in the
 * mirrored world: M E^-1 X) at (w - 1 - u_x, u_y). Largest pixel difference over the frames,
 * both cameras and 200 seeded points in front of the cameras. */
double mirror_pixel_error(const rprd::Sequence &s, const rprd::Sequence &m)
{
    const rprd::Pose E = cam_pose(s.rig.cam[1]);
    const rprd::Pose Ei = rprd::pose_inv(E);
    std::srand(11);
    double worst = 0.0;
    int seen = 0;
    for (size_t j = 0; j < s.truth.size(); ++j) {
        for (int n = 0; n < 200; ++n) {
            /* a point 2..20 m in front of the left camera at frame j, in the world */
            const double z = 2.0 + 18.0 * std::rand() / RAND_MAX;
            const double pc[3] = {z * (0.8 * std::rand() / RAND_MAX - 0.4),
                                  z * (0.6 * std::rand() / RAND_MAX - 0.3), z};
            rprd::Pose P; /* the point as a translation */
            for (int i = 0; i < 3; ++i) {
                P.t[i] = pc[i];
            }
            const rprd::Pose Xw = rprd::pose_mul(s.truth[j], P);
            const rprd::Pose Xm = rprd::mirror_pose(rprd::pose_mul(Ei, Xw)); /* mirrored world */
            for (int k = 0; k < 2; ++k) {
                const rprd::Pose in_s =
                    rprd::pose_mul(rprd::pose_inv(rprd::pose_mul(s.truth[j], cam_pose(s.rig.cam[k]))), Xw);
                const rprd::Pose in_m = rprd::pose_mul(
                    rprd::pose_inv(rprd::pose_mul(m.truth[j], cam_pose(m.rig.cam[1 - k]))), Xm);
                rp_real a[3], b[3], ua[2], ub[2];
                for (int i = 0; i < 3; ++i) {
                    a[i] = (rp_real)in_s.t[i];
                    b[i] = (rp_real)in_m.t[i];
                }
                if (rp_cam_project(&s.rig.cam[k].cam, a, ua, nullptr) != RP_OK ||
                    rp_cam_project(&m.rig.cam[1 - k].cam, b, ub, nullptr) != RP_OK) {
                    continue;
                }
                const double w1 = (double)s.rig.cam[k].cam.width - 1.0;
                worst = std::fmax(worst, std::fabs(w1 - (double)ua[0] - (double)ub[0]));
                worst = std::fmax(worst, std::fabs((double)ua[1] - (double)ub[1]));
                ++seen;
            }
        }
    }
    return seen > 0 ? worst : 1e9;
}

/* The first row of pixels of a written image is the source image's row reversed. */
bool flipped_copy(const std::string &src, const std::string &dst)
{
    const cv::Mat a = cv::imread(src, cv::IMREAD_GRAYSCALE), b = cv::imread(dst, cv::IMREAD_GRAYSCALE);
    if (a.empty() || b.empty() || a.size() != b.size()) {
        return false;
    }
    cv::Mat f;
    cv::flip(a, f, 1);
    return cv::norm(f, b, cv::NORM_INF) == 0.0;
}

/* Mirror twice = the sequence; pixels of the mirror image = the flipped pixels; written and
 * read back = the mirror image. */
void check_mirror(const char *what, const rprd::Sequence &s)
{
    const rprd::Sequence m = rprd::mirror_sequence(s);
    const rprd::Sequence mm = rprd::mirror_sequence(m);
    const double d2 = std::fmax(rig_diff(s.rig, mm.rig), truth_diff(s, mm));
    check(d2 < 1e-12 && mm.img[0] == s.img[0] && mm.img[1] == s.img[1],
          (std::string(what) + ": mirror twice = the sequence (rig, truth, images)").c_str(), d2);
    check(rp_rig_check(&m.rig) == RP_OK && pose_diff(m.truth[0], rprd::Pose()) < 1e-12,
          (std::string(what) + ": mirror image: a usable rig, frame 0 the world").c_str(), 0.0);
    const double px = mirror_pixel_error(s, m);
    check(px < 1e-6, (std::string(what) + ": a scene point's pixel in the mirror image is the "
                                          "original's flipped (w - 1 - u), both cameras").c_str(), px);
    /* the brief's guess, p1 flipped instead of p2, would not be: show it on a distorted rig */
    if (s.rig.cam[0].cam.p1 != 0 || s.rig.cam[0].cam.p2 != 0) {
        rprd::Sequence wrong = m;
        for (int k = 0; k < 2; ++k) {
            wrong.rig.cam[k].cam.p1 = -wrong.rig.cam[k].cam.p1;
            wrong.rig.cam[k].cam.p2 = -wrong.rig.cam[k].cam.p2;
        }
        const double pw = mirror_pixel_error(s, wrong);
        check(pw > 1e-3, (std::string(what) + ": ... and flipping p1 instead of p2 is not").c_str(), pw);
    }
    char tmpl[] = "/tmp/rp_mirror_test_XXXXXX";
    const char *t = mkdtemp(tmpl);
    std::string err;
    rprd::Sequence back;
    const bool w = t && rprd::write_sequence(m, t, true, &err);
    const bool r = w && (s.format == rprd::Format::KITTI ? rprd::load_kitti(t, 0, 0, &back, &err)
                                                        : rprd::load_euroc(t, 0, 0, &back, &err));
    const double db = r ? std::fmax(rig_diff(m.rig, back.rig), truth_diff(m, back)) : 1e9;
    check(r && db < 1e-9 && back.utime.size() == s.utime.size() &&
              back.utime.back() - back.utime[0] == s.utime.back() - s.utime[0],
          (std::string(what) + ": mirror image written and read back: same rig, truth, times " + err).c_str(), db);
    if (r) {
        check(flipped_copy(s.img[1][0], back.img[0][0]) && flipped_copy(s.img[0].back(), back.img[1].back()),
              (std::string(what) + ": ... its left images are the right ones flipped, and back").c_str(), 0.0);
    }
    if (t) {
        std::error_code ec;
        std::filesystem::remove_all(t, ec);
    }
}

/* rp_timesync's lag fit on synthetic rates: a smooth w(t) (sums of sinusoids, rad/s) sampled
 * at 20 Hz for the reference and at stamp + 37 ms for the camera, with noise: the fit finds
 * 37 ms within 3 of its sigmas; with the camera's own clock (no offset) about 0; on a constant
 * rate (a straight drive at a steady turn) it cannot say, and its sigma says so. */
void check_timesync_synthetic()
{
    auto w_true = [](double t, double w[3]) {
        w[0] = 0.4 * std::sin(2.1 * t) + 0.2 * std::sin(5.3 * t + 1.0);
        w[1] = 0.3 * std::sin(1.3 * t + 0.5) + 0.15 * std::sin(7.1 * t);
        w[2] = 0.25 * std::sin(3.7 * t + 2.0);
    };
    std::srand(11);
    auto noise = []() { return 0.01 * (2.0 * std::rand() / RAND_MAX - 1.0); };
    for (double off : {0.037, 0.0, -0.052}) {
        std::vector<rpts::RateSample> ref, cam, flat_ref, flat_cam;
        for (int j = 0; j < 150; ++j) {
            rpts::RateSample a, b;
            a.t_s = b.t_s = 0.05 * j;
            w_true(a.t_s, a.w);
            w_true(b.t_s + off, b.w);
            for (int i = 0; i < 3; ++i) {
                a.w[i] += noise();
                b.w[i] += noise();
            }
            ref.push_back(a);
            cam.push_back(b);
            rpts::RateSample f = a, g = b;
            for (int i = 0; i < 3; ++i) {
                f.w[i] = 0.1 + noise();
                g.w[i] = 0.1 + noise();
            }
            flat_ref.push_back(f);
            flat_cam.push_back(g);
        }
        rpts::OffsetFit fit;
        const bool ok = rpts::fit_offset(ref, cam, 0.2, 0.001, &fit);
        char what[160];
        std::snprintf(what, sizeof what,
                      "timesync: offset %.0f ms found within 3 sigma (%.2f +- %.2f ms)",
                      1e3 * off, 1e3 * fit.offset_s, 1e3 * fit.sigma_s);
        check(ok && std::fabs(fit.offset_s - off) <= 3.0 * fit.sigma_s && fit.sigma_s < 0.005,
              what, 1e3 * (fit.offset_s - off));
        if (off == 0.0) {
            const bool ok_flat = rpts::fit_offset(flat_ref, flat_cam, 0.2, 0.001, &fit);
            check(ok_flat && std::isinf(fit.sigma_s),
                  "timesync: a constant rate leaves the offset undetermined (sigma infinite)",
                  fit.snr);
        }
    }
}

/* rp_timesync on EuRoC MH01 frames 0-59: the right camera's images one frame late (a true
 * offset of 50 ms, stamped as simultaneous) and as recorded (0): found within 3 sigma. */
void check_timesync_euroc(const rprd::Sequence &e)
{
    rprd::Sequence s = e;
    s.img[0].resize(60);
    s.img[1].resize(60);
    s.utime.resize(60);
    std::string err;
    for (int shift : {0, 1}) {
        std::vector<std::string> right(s.img[1]);
        for (size_t j = 0; j < right.size(); ++j) {
            right[j] = e.img[1][j + (size_t)shift];
        }
        std::vector<rpts::RateSample> w0, w1;
        rpts::OffsetFit fit;
        const bool ok = rpts::camera_rates(s.img[0], s.utime, s.rig.cam[0], &w0, &err) &&
                        rpts::camera_rates(right, s.utime, s.rig.cam[1], &w1, &err) &&
                        rpts::fit_offset(w0, w1, 0.2, 0.001, &fit);
        const double truth = 1e-6 * (double)(e.utime[(size_t)shift] - e.utime[0]);
        char what[200];
        std::snprintf(what, sizeof what,
                      "timesync: EuRoC 0-59, right camera %d frame(s) late: %.2f +- %.2f ms for "
                      "%.0f ms %s", shift, 1e3 * fit.offset_s, 1e3 * fit.sigma_s, 1e3 * truth,
                      err.c_str());
        check(ok && std::fabs(fit.offset_s - truth) <= 3.0 * fit.sigma_s && fit.sigma_s < 0.005,
              what, 1e3 * (fit.offset_s - truth));
    }
}

}  // namespace

int main()
{
    /* pose vector round trip, seeded */
    std::srand(7);
    double worst = 0.0, worst_inv = 0.0;
    for (int k = 0; k < 1000; ++k) {
        double p[6], q[6];
        for (int i = 0; i < 6; ++i) {
            p[i] = (2.0 * std::rand() / RAND_MAX - 1.0) * (i == 4 ? 1.5 : 3.0);
        }
        const rprd::Pose T = rprd::pose_from_vec(p);
        rprd::pose_to_vec(T, q);
        worst = std::fmax(worst, pose_diff(T, rprd::pose_from_vec(q)));
        worst_inv = std::fmax(worst_inv, pose_diff(rprd::pose_mul(rprd::pose_inv(T), T),
                                                   rprd::Pose()));
    }
    check(worst < 1e-12, "pose vector -> pose -> vector -> pose round trip", worst);
    check(worst_inv < 1e-12, "pose_inv(T) * T is the identity", worst_inv);

    /* a known error: 10 frames 1 m apart along z, the estimate 0.1 m off in x from frame 1 on */
    std::vector<rprd::Pose> truth(10), est(10);
    for (int j = 0; j < 10; ++j) {
        truth[(size_t)j].t[2] = j;
        est[(size_t)j].t[2] = j;
        est[(size_t)j].t[0] = j ? 0.1 : 0.0;
    }
    const rprd::Summary s = rprd::summarise(est, truth);
    check(std::fabs(s.path_m - 9.0) < 1e-12, "path length 9 m", s.path_m);
    check(std::fabs(s.ate_m - 0.1 * std::sqrt(0.9)) < 1e-12, "ATE = 0.1 sqrt(9/10) m", s.ate_m);
    check(std::fabs(s.rpe_percent - 100.0 * 0.1 / 9.0) < 1e-9, "RPE: one 0.1 m step error",
          s.rpe_percent);
    check(std::fabs(s.scale - 1.0) < 1e-12, "scale 1 when only x is off", s.scale);
    std::vector<rprd::Pose> longer = truth;
    for (rprd::Pose &T : longer) {
        T.t[2] *= 1.03;
    }
    const double sl = rprd::summarise(longer, truth).scale;
    check(std::fabs(sl - 1.03) < 1e-12, "scale 1.03 of a path 3 % too long", sl);

    /* the loaders on synthetic folders: labels, folder names, times, missing images, formats */
    check_loaders_synthetic();
    check_timesync_synthetic();

    /* the loaders, on the real data if present */
    const char *env = std::getenv("RIGPOSE_DATA");
    const std::string data = env ? env : "../shared/data";
    if (is_dir(data + "/kitti00_000-099") && is_dir(data + "/euroc_mh01_000-149")) {
        rprd::Sequence k, e;
        std::string err;
        const bool ok_k = rprd::load_kitti(data + "/kitti00_000-099", 0, 0, &k, &err);
        check(ok_k && k.utime.size() == 100, "KITTI: 100 frames loaded", (double)k.utime.size());
        if (ok_k) {
            check(rp_rig_check(&k.rig) == RP_OK, "KITTI: rig usable", 0.0);
            check(std::fabs((double)k.rig.cam[1].D[0] - 386.1448 / 718.856) < 1e-9,
                  "KITTI: baseline 386.1448 / 718.856 m", (double)k.rig.cam[1].D[0]);
            check(pose_diff(k.truth[0], rprd::Pose()) < 1e-6, "KITTI: frame 0 is the world",
                  pose_diff(k.truth[0], rprd::Pose()));
            check(std::fabs(k.truth[99].t[2] - 83.8853) < 1e-3, "KITTI: frame 99 at z 83.885 m",
                  k.truth[99].t[2]);
        }
        const bool ok_e = rprd::load_euroc(data + "/euroc_mh01_000-149", 0, 0, &e, &err);
        check(ok_e && e.utime.size() == 150, "EuRoC: 150 frames loaded", (double)e.utime.size());
        if (ok_e) {
            const double b = std::sqrt((double)(e.rig.cam[1].D[0] * e.rig.cam[1].D[0] +
                                                e.rig.cam[1].D[1] * e.rig.cam[1].D[1] +
                                                e.rig.cam[1].D[2] * e.rig.cam[1].D[2]));
            check(rp_rig_check(&e.rig) == RP_OK, "EuRoC: rig usable", 0.0);
            check(std::fabs(b - 0.110) < 0.001, "EuRoC: baseline about 0.110 m", b);
            check(pose_diff(e.truth[0], rprd::Pose()) < 1e-9, "EuRoC: frame 0 is the world",
                  pose_diff(e.truth[0], rprd::Pose()));
            check(e.utime[1] - e.utime[0] == 50000, "EuRoC: 20 Hz",
                  (double)(e.utime[1] - e.utime[0]));
        }
        if (ok_e) {
            check_direct(data + "/kitti00_000-099", e);
            check_timesync_euroc(e);
        }
        /* the mirror image's geometry on the real clips (first 3 frames each) */
        rprd::Sequence k3, e3;
        if (rprd::load_kitti(data + "/kitti00_000-099", 0, 3, &k3, &err)) {
            check_mirror("mirror: kitti00", k3);
        }
        if (rprd::load_euroc(data + "/euroc_mh01_000-149", 0, 3, &e3, &err)) {
            check_mirror("mirror: euroc_mh01", e3);
        }
        rprd::Sequence bad;
        err.clear();
        const bool refused = !rprd::load_kitti(data + "/euroc_mh01_000-149", 0, 0, &bad, &err);
        check(refused && !err.empty(), ("a wrong folder is refused: " + err).c_str(), 0.0);
    } else {
        std::printf("[  SKIPPED ] 1 test(s): the loaders on real data: no kitti00_000-099/ and "
                    "euroc_mh01_000-149/ in %s (set RIGPOSE_DATA)\n",
                    data.c_str());
    }
    std::printf("[  PASSED  ] %d test(s).\n", n_pass);
    if (n_fail) {
        std::printf("[  FAILED  ] %d test(s).\n", n_fail);
        return 1;
    }
    return 0;
}
