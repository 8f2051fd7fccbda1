/*
 * rp_realdata.cpp - loaders of KITTI / EuRoC stereo folders, pose conversions, trajectory error
 * (rp_realdata.hpp says the conventions).
 */
#include "rp_realdata.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <cstdarg>
#include <cstdio>
#include <sys/stat.h>

#include <opencv2/imgcodecs.hpp>

#include "rigpose/rp_rot.h"

namespace rprd {

namespace {

bool fail(std::string *err, const std::string &msg)
{
    if (err) {
        *err = msg;
    }
    return false;
}

/* Numbers of a line; false if a token is not a number. Commas count as separators. */
bool parse_numbers(std::string line, std::vector<double> *out)
{
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream is(line);
    std::string tok;
    out->clear();
    while (is >> tok) {
        char *end = nullptr;
        const double v = std::strtod(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0' || !std::isfinite(v)) {
            return false;
        }
        out->push_back(v);
    }
    return true;
}

/* The numbers of the flow list after `key:` in a small YAML file (EuRoC's sensor.yaml), which
 * may span lines up to its closing bracket; `after` makes the search start past that text
 * (e.g. "T_BS:" then "data:"). */
bool yaml_list(const std::string &text, const std::string &after, const std::string &key,
               std::vector<double> *out)
{
    size_t from = 0;
    if (!after.empty()) {
        from = text.find(after);
        if (from == std::string::npos) {
            return false;
        }
    }
    const size_t k = text.find(key + ":", from);
    if (k == std::string::npos) {
        return false;
    }
    const size_t open = text.find('[', k);
    const size_t close = text.find(']', k);
    if (open == std::string::npos || close == std::string::npos || close < open) {
        return false;
    }
    return parse_numbers(text.substr(open + 1, close - open - 1), out);
}

bool read_text(const std::string &path, std::string *text)
{
    std::ifstream f(path);
    if (!f) {
        return false;
    }
    std::stringstream ss;
    ss << f.rdbuf();
    *text = ss.str();
    return true;
}

Pose pose_from_3x4(const std::vector<double> &v)
{
    Pose T;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            T.R[3 * r + c] = v[(size_t)(4 * r + c)];
        }
        T.t[r] = v[(size_t)(4 * r + 3)];
    }
    return T;
}

/* Nearest rotation (the datasets print 7 digits; the rig check wants orthonormal to 1e-6). */
void orthonormalise(double R[9])
{
    rp_real Rr[9];
    for (int i = 0; i < 9; ++i) {
        Rr[i] = (rp_real)R[i];
    }
    rp_rot_orthonormalize(Rr);
    for (int i = 0; i < 9; ++i) {
        R[i] = (double)Rr[i];
    }
}

/* The right camera (rig camera 1) of a pair: rotation R and position D in the left camera. */
void set_pair_cams(rp_rig_t *rig, const rp_camera_t &left, const rp_camera_t &right,
                   const Pose &right_in_left)
{
    *rig = rp_rig_t();
    rig->n_cams = 2;
    const Pose I;
    const Pose *T[2] = {&I, &right_in_left};
    const rp_camera_t *cam[2] = {&left, &right};
    for (int k = 0; k < 2; ++k) {
        Pose Tk = *T[k];
        orthonormalise(Tk.R);
        for (int i = 0; i < 9; ++i) {
            rig->cam[k].R[i] = (rp_real)Tk.R[i];
        }
        for (int i = 0; i < 3; ++i) {
            rig->cam[k].D[i] = (rp_real)Tk.t[i];
        }
        rig->cam[k].cam = *cam[k];
    }
}

/* Sorted ground-truth samples: time (us) and body pose in the world. */
struct Gt {
    int64_t utime;
    Pose T;
};

bool file_exists(const std::string &path)
{
    struct stat st;
    return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

bool dir_exists(const std::string &path)
{
    struct stat st;
    return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string fmt(const char *f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char *f, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, f);
    std::vsnprintf(buf, sizeof buf, f, ap);
    va_end(ap);
    return buf;
}

/* Body poses of a ground-truth file, either format: TUM (t[s] tx ty tz qx qy qz qw, spaces) or
 * EuRoC's state_groundtruth_estimate0/data.csv (t[ns], px, py, pz, qw, qx, qy, qz, then
 * velocities and biases, commas). The first line's time tells which: over 1e12 is nanoseconds
 * (EuRoC; 1e12 s would be 31700 years). *note: the file, its columns, its first pose as read. */
bool load_truth(const std::string &path, std::vector<Gt> *gt, std::string *note, std::string *err)
{
    std::ifstream f(path);
    if (!f) {
        return fail(err, path + ": cannot open");
    }
    std::string line;
    std::vector<double> v;
    int ln = 0;
    int euroc = -1; /* -1: not known yet */
    while (std::getline(f, line)) {
        ++ln;
        if (!line.empty() && line.back() == '\r') {
            line.pop_back();
        }
        if (line.empty() || line[0] == '#') {
            continue;
        }
        if (!parse_numbers(line, &v) || v.empty()) {
            return fail(err, path + ":" + std::to_string(ln) + ": not a line of numbers");
        }
        if (euroc < 0) {
            euroc = v[0] > 1e12 ? 1 : 0;
        }
        if (euroc ? v.size() < 8 : v.size() != 8) {
            return fail(err, path + ":" + std::to_string(ln) +
                                 (euroc ? ": expected t[ns], px, py, pz, qw, qx, qy, qz, ... "
                                          "(EuRoC's state_groundtruth_estimate0/data.csv)"
                                        : ": expected t[s] tx ty tz qx qy qz qw (TUM)"));
        }
        Gt g;
        /* q = (w, x, y, z) for rp_rot_from_quat */
        rp_real q[4];
        if (euroc) {
            g.utime = (int64_t)std::llround(v[0] * 1e-3);
            q[0] = (rp_real)v[4];
            q[1] = (rp_real)v[5];
            q[2] = (rp_real)v[6];
            q[3] = (rp_real)v[7];
        } else {
            g.utime = (int64_t)std::llround(v[0] * 1e6);
            q[0] = (rp_real)v[7];
            q[1] = (rp_real)v[4];
            q[2] = (rp_real)v[5];
            q[3] = (rp_real)v[6];
        }
        const double qn = std::sqrt((double)(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]));
        rp_real R[9];
        if (std::fabs(qn - 1.0) > 1e-3 || rp_rot_from_quat(q, R) != RP_OK) {
            return fail(err, path + ":" + std::to_string(ln) +
                                 fmt(": quaternion of norm %.6f, not a unit quaternion", qn));
        }
        for (int i = 0; i < 9; ++i) {
            g.T.R[i] = (double)R[i];
        }
        for (int i = 0; i < 3; ++i) {
            g.T.t[i] = v[(size_t)(1 + i)];
        }
        if (gt->empty()) {
            *note = path +
                    (euroc ? ": EuRoC csv t[ns], px, py, pz, qw, qx, qy, qz (qw first)"
                           : ": TUM t[s] tx ty tz qx qy qz qw (qw last)") +
                    fmt("; first pose read (line %d): t %.6f s, position %.6f %.6f %.6f m, "
                        "quaternion qw %.6f qx %.6f qy %.6f qz %.6f",
                        ln, (double)g.utime * 1e-6, v[1], v[2], v[3], (double)q[0],
                        (double)q[1], (double)q[2], (double)q[3]);
        }
        gt->push_back(g);
    }
    std::sort(gt->begin(), gt->end(), [](const Gt &x, const Gt &y) { return x.utime < y.utime; });
    if (gt->empty()) {
        return fail(err, path + ": no pose");
    }
    return true;
}

/* EuRoC sensor.yaml: the camera (intrinsics, distortion, resolution) and T_BS. */
bool load_euroc_cam(const std::string &path, rp_camera_t *cam, Pose *T_BS, std::string *err)
{
    std::string text;
    if (!read_text(path, &text)) {
        return fail(err, path + ": cannot open");
    }
    std::vector<double> intr, dist, res, tbs;
    if (!yaml_list(text, "", "intrinsics", &intr) || intr.size() != 4) {
        return fail(err, path + ": intrinsics: expected [fu, fv, cu, cv]");
    }
    if (!yaml_list(text, "", "distortion_coefficients", &dist) || dist.size() < 4 ||
        dist.size() > 5) {
        return fail(err, path + ": distortion_coefficients: expected [k1, k2, p1, p2]");
    }
    if (!yaml_list(text, "", "resolution", &res) || res.size() != 2 || res[0] < 1 ||
        res[1] < 1 || res[0] > 65535 || res[1] > 65535) {
        return fail(err, path + ": resolution: expected [width, height]");
    }
    if (!yaml_list(text, "T_BS:", "data", &tbs) || tbs.size() != 16) {
        return fail(err, path + ": T_BS.data: expected 16 numbers");
    }
    if (text.find("radial-tangential") == std::string::npos) {
        return fail(err, path + ": only distortion_model radial-tangential is supported");
    }
    *cam = rp_cam_pinhole((uint16_t)res[0], (uint16_t)res[1], (rp_real)intr[0], (rp_real)intr[1],
                          (rp_real)intr[2], (rp_real)intr[3]);
    cam->k1 = (rp_real)dist[0];
    cam->k2 = (rp_real)dist[1];
    cam->p1 = (rp_real)dist[2];
    cam->p2 = (rp_real)dist[3];
    cam->k3 = dist.size() == 5 ? (rp_real)dist[4] : (rp_real)0;
    *T_BS = pose_from_3x4(tbs);
    return true;
}

/* EuRoC camN/data.csv: timestamps (ns) and file names. */
bool load_euroc_list(const std::string &dir, std::vector<int64_t> *t_ns,
                     std::vector<std::string> *files, std::string *err)
{
    const std::string path = dir + "/data.csv";
    std::ifstream f(path);
    if (!f) {
        return fail(err, path + ": cannot open");
    }
    std::string line;
    int ln = 0;
    while (std::getline(f, line)) {
        ++ln;
        if (!line.empty() && line.back() == '\r') {
            line.pop_back();
        }
        if (line.empty() || line[0] == '#') {
            continue;
        }
        const size_t comma = line.find(',');
        char *end = nullptr;
        const long long t = std::strtoll(line.c_str(), &end, 10);
        if (comma == std::string::npos || end != line.c_str() + comma || comma + 1 >= line.size()) {
            return fail(err, path + ":" + std::to_string(ln) + ": expected timestamp,filename");
        }
        std::string file = line.substr(comma + 1);
        file.erase(0, file.find_first_not_of(' '));
        file = dir + "/data/" + file;
        if (!file_exists(file)) {
            return fail(err, path + ":" + std::to_string(ln) + ": lists " + file +
                                 ", which does not exist (the first missing image)");
        }
        if (!t_ns->empty() && (int64_t)t <= t_ns->back()) {
            return fail(err, path + ":" + std::to_string(ln) + ": timestamps not increasing");
        }
        t_ns->push_back((int64_t)t);
        files->push_back(file);
    }
    if (t_ns->empty()) {
        return fail(err, path + ": lists no image");
    }
    return true;
}

}  // namespace

Pose pose_mul(const Pose &a, const Pose &b)
{
    Pose c;
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) {
            c.R[3 * r + k] = a.R[3 * r] * b.R[k] + a.R[3 * r + 1] * b.R[3 + k] +
                             a.R[3 * r + 2] * b.R[6 + k];
        }
        c.t[r] = a.R[3 * r] * b.t[0] + a.R[3 * r + 1] * b.t[1] + a.R[3 * r + 2] * b.t[2] + a.t[r];
    }
    return c;
}

Pose pose_inv(const Pose &a)
{
    Pose c;
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) {
            c.R[3 * r + k] = a.R[3 * k + r];
        }
    }
    for (int r = 0; r < 3; ++r) {
        c.t[r] = -(c.R[3 * r] * a.t[0] + c.R[3 * r + 1] * a.t[1] + c.R[3 * r + 2] * a.t[2]);
    }
    return c;
}

void pose_to_vec(const Pose &T, double p[6])
{
    rp_real R[9], abg[3] = {0, 0, 0};
    for (int i = 0; i < 9; ++i) {
        R[i] = (rp_real)T.R[i];
    }
    (void)rp_rot_to_angles(R, abg); /* finite input: RP_OK */
    for (int i = 0; i < 3; ++i) {
        p[i] = T.t[i];
        p[3 + i] = (double)abg[i];
    }
}

Pose pose_from_vec(const double p[6])
{
    const rp_real abg[3] = {(rp_real)p[3], (rp_real)p[4], (rp_real)p[5]};
    rp_real R[9];
    rp_rot_from_angles(abg, R);
    Pose T;
    for (int i = 0; i < 9; ++i) {
        T.R[i] = (double)R[i];
    }
    for (int i = 0; i < 3; ++i) {
        T.t[i] = p[i];
    }
    return T;
}

namespace {

bool max_frames_reached(const LoadOpts &o, size_t n)
{
    return o.max_frames != 0 && n >= o.max_frames;
}

/* calib.txt's P0 and P1: labelled lines (P0: / P1:, or KITTI raw's P_rect_00: / P_rect_01:),
 * else the first two lines of exactly 12 numbers. */
bool load_kitti_calib(const std::string &path, std::vector<double> P[2], std::string *note,
                      std::string *err)
{
    std::ifstream fc(path);
    if (!fc) {
        return fail(err, path + ": cannot open");
    }
    std::string line;
    std::vector<double> v;
    std::vector<std::vector<double>> bare;
    int ln = 0;
    while (std::getline(fc, line)) {
        ++ln;
        if (!line.empty() && line.back() == '\r') {
            line.pop_back();
        }
        const size_t colon = line.find(':');
        if (colon == std::string::npos) {
            if (parse_numbers(line, &v) && v.size() == 12) {
                bare.push_back(v);
            }
            continue;
        }
        std::string key = line.substr(0, colon);
        key.erase(0, key.find_first_not_of(' '));
        const int k = key == "P0" || key == "P_rect_00" ? 0
                      : key == "P1" || key == "P_rect_01" ? 1
                                                           : -1;
        if (k < 0) {
            continue;
        }
        if (!parse_numbers(line.substr(colon + 1), &v) || v.size() != 12) {
            return fail(err, path + ":" + std::to_string(ln) + ": " + key + ": expected 12 numbers");
        }
        P[k] = v;
    }
    if (P[0].empty() && P[1].empty() && bare.size() >= 2) {
        P[0] = bare[0];
        P[1] = bare[1];
        *note = path + ": no P0/P1 labels: the first two lines of 12 numbers are P0 (left), P1 (right)";
    } else if (P[0].empty() || P[1].empty()) {
        return fail(err, path + ": P0 and P1 required (lines \"P0: <12 numbers>\", \"P1: ...\", "
                                "or P_rect_00 / P_rect_01, or two unlabelled lines of 12 numbers)");
    } else {
        *note = path + ": P0 (left), P1 (right)";
    }
    if (P[0][0] <= 0.0 || P[1][0] <= 0.0 || P[0][3] != 0.0 || P[1][3] >= 0.0) {
        return fail(err, path + ": P0 must be [K|0] and P1 [K|-fx b] with b > 0 (P1: the right camera)");
    }
    return true;
}

}  // namespace

bool load_kitti(const std::string &dir, const LoadOpts &o, Sequence *seq, std::string *err)
{
    *seq = Sequence();
    seq->format = Format::KITTI;
    seq->name = "kitti";
    seq->dir = dir;
    std::vector<double> P[2];
    std::string note;
    if (!load_kitti_calib(dir + "/calib.txt", P, &note, err)) {
        return false;
    }
    seq->notes.push_back(note);
    char name[32];
    /* the image folders: given, or the first known pair holding the first frame's left image */
    std::snprintf(name, sizeof name, "%06zu.png", o.first);
    std::vector<std::pair<std::string, std::string>> pairs;
    if (!o.left.empty() || !o.right.empty()) {
        pairs.emplace_back(o.left.empty() ? "image_0" : o.left, o.right.empty() ? "image_1" : o.right);
    } else {
        pairs = {{"image_0", "image_1"}, {"image_l", "image_r"}, {"left", "right"}};
    }
    std::string ldir, rdir, tried;
    for (const auto &pr : pairs) {
        tried += (tried.empty() ? "" : ", ") + pr.first + "/";
        if (file_exists(dir + "/" + pr.first + "/" + name)) {
            ldir = pr.first;
            rdir = pr.second;
            break;
        }
    }
    if (ldir.empty()) {
        return fail(err, dir + ": no left image " + name + " in " + tried +
                             " (give the folders with --images LEFT,RIGHT)");
    }
    seq->notes.push_back(dir + ": images " + ldir + "/ (left), " + rdir + "/ (right)");
    /* times.txt (unless a frame rate is given) and poses.txt: one line per frame */
    const std::string tpath = dir + "/times.txt";
    const std::string ppath = o.truth.empty() ? dir + "/poses.txt" : o.truth;
    std::ifstream ft, fp(ppath);
    if (o.fps > 0.0) {
        seq->notes.push_back(fmt("times: frame j at j / %g s (--fps)%s", o.fps,
                                 file_exists(tpath) ? "; times.txt not read" : ""));
    } else {
        ft.open(tpath);
        if (!ft) {
            return fail(err, tpath + ": cannot open (without it, give the frame rate: --fps HZ)");
        }
        seq->notes.push_back("times: " + tpath + " (s)");
    }
    if (!fp) {
        return fail(err, ppath + ": cannot open (the ground truth, KITTI poses format)");
    }
    std::string lt, lp;
    std::vector<double> v;
    int ln = 0;
    Pose T0_inv;
    while (std::getline(fp, lp)) {
        ++ln;
        if (max_frames_reached(o, seq->utime.size())) {
            break;
        }
        std::vector<double> tv;
        if (o.fps > 0.0) {
            tv.assign(1, (double)(ln - 1) / o.fps);
        } else if (!std::getline(ft, lt)) {
            break; /* times.txt ends: so do the frames */
        } else if (!parse_numbers(lt, &tv) || tv.size() != 1) {
            return fail(err, tpath + ":" + std::to_string(ln) + ": expected seconds");
        }
        if (!parse_numbers(lp, &v) || v.size() != 12) {
            return fail(err, ppath + ":" + std::to_string(ln) +
                                 ": expected 12 numbers (3x4 [R|t] row-major)");
        }
        if (ln == 1) {
            seq->notes.push_back(
                ppath + fmt(": KITTI 3x4 [R|t] row-major per line (left camera at frame j in frame "
                            "0's); first pose read (line 1): t %.6f %.6f %.6f m, R rows "
                            "[%.6f %.6f %.6f] [%.6f %.6f %.6f] [%.6f %.6f %.6f]",
                            v[3], v[7], v[11], v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9],
                            v[10]));
        }
        const size_t j = (size_t)(ln - 1); /* the file's frame index */
        if (j < o.first) {
            continue;
        }
        Pose T = pose_from_3x4(v);
        orthonormalise(T.R);
        if (seq->truth.empty()) {
            T0_inv = pose_inv(T); /* the first frame is the world */
        }
        std::snprintf(name, sizeof name, "%06zu.png", j);
        const std::string im[2] = {dir + "/" + ldir + "/" + name, dir + "/" + rdir + "/" + name};
        for (int k = 0; k < 2; ++k) {
            if (!file_exists(im[k])) {
                return fail(err, im[k] + ": no such image (frame " + std::to_string(j) + " of " +
                                     ppath + ", the first missing one; --frames N stops before it)");
            }
        }
        seq->utime.push_back((int64_t)std::llround(tv[0] * 1e6));
        seq->img[0].push_back(im[0]);
        seq->img[1].push_back(im[1]);
        seq->truth.push_back(pose_mul(T0_inv, T));
    }
    if (seq->utime.empty()) {
        return fail(err, dir + ": no frame" + (o.first ? " from frame " + std::to_string(o.first) : ""));
    }
    for (size_t j = 1; j < seq->utime.size(); ++j) {
        if (seq->utime[j] <= seq->utime[j - 1]) {
            return fail(err, tpath + ": times not increasing at frame " + std::to_string(o.first + j));
        }
    }
    /* the image size (calib.txt does not hold it): the first left image's */
    const cv::Mat im = cv::imread(seq->img[0][0], cv::IMREAD_GRAYSCALE);
    if (im.empty() || im.cols > 65535 || im.rows > 65535) {
        return fail(err, seq->img[0][0] + ": cannot read the image");
    }
    rp_camera_t cam[2];
    for (int k = 0; k < 2; ++k) {
        cam[k] = rp_cam_pinhole((uint16_t)im.cols, (uint16_t)im.rows, (rp_real)P[k][0],
                                (rp_real)P[k][5], (rp_real)P[k][2], (rp_real)P[k][6]);
    }
    Pose right; /* the right camera at baseline b along the left camera's x axis */
    right.t[0] = -P[1][3] / P[1][0];
    set_pair_cams(&seq->rig, cam[0], cam[1], right);
    return true;
}

bool load_euroc(const std::string &dir_in, const LoadOpts &o, Sequence *seq, std::string *err)
{
    *seq = Sequence();
    seq->format = Format::EUROC;
    seq->name = "euroc";
    /* EuRoC's own archives hold everything under mav0/ */
    const std::string dir = !dir_exists(dir_in + "/cam0") && dir_exists(dir_in + "/mav0/cam0")
                                ? dir_in + "/mav0"
                                : dir_in;
    seq->dir = dir;
    if (o.fps > 0.0 || !o.left.empty() || !o.right.empty()) {
        return fail(err, "EuRoC: the frames and times are cam0/ and cam1/'s data.csv (no --fps, "
                         "--images)");
    }
    rp_camera_t cam[2];
    Pose T_BS[2];
    std::vector<int64_t> t_ns[2];
    std::vector<std::string> files[2];
    for (int k = 0; k < 2; ++k) {
        const std::string cdir = dir + "/cam" + std::to_string(k);
        if (!load_euroc_cam(cdir + "/sensor.yaml", &cam[k], &T_BS[k], err) ||
            !load_euroc_list(cdir, &t_ns[k], &files[k], err)) {
            return false;
        }
    }
    seq->notes.push_back(dir + ": cam0/ (left), cam1/ (right): sensor.yaml, data.csv (t[ns],file)");
    set_pair_cams(&seq->rig, cam[0], cam[1], pose_mul(pose_inv(T_BS[0]), T_BS[1]));
    std::string gpath = o.truth;
    if (gpath.empty()) {
        gpath = dir + "/groundtruth.txt";
        if (!file_exists(gpath) && file_exists(dir + "/state_groundtruth_estimate0/data.csv")) {
            gpath = dir + "/state_groundtruth_estimate0/data.csv";
        }
    }
    std::vector<Gt> gt;
    std::string note;
    if (!load_truth(gpath, &gt, &note, err)) {
        return false;
    }
    seq->notes.push_back(note);
    /* frames: the timestamps both lists hold, counted from 0 (--first skips frames, not rows) */
    size_t i1 = 0, frame = 0;
    Pose C0_inv;
    for (size_t i = 0; i < t_ns[0].size(); ++i) {
        if (max_frames_reached(o, seq->utime.size())) {
            break;
        }
        while (i1 < t_ns[1].size() && t_ns[1][i1] < t_ns[0][i]) {
            ++i1;
        }
        if (i1 >= t_ns[1].size() || t_ns[1][i1] != t_ns[0][i]) {
            continue; /* no right image at this time: not a stereo frame */
        }
        if (frame++ < o.first) {
            continue;
        }
        const int64_t ut = t_ns[0][i] / 1000;
        auto it = std::lower_bound(gt.begin(), gt.end(), ut,
                                   [](const Gt &g, int64_t t) { return g.utime < t; });
        const Gt *best = nullptr;
        if (it != gt.end()) {
            best = &*it;
        }
        if (it != gt.begin() && (!best || ut - (it - 1)->utime < best->utime - ut)) {
            best = &*(it - 1);
        }
        if (!best || std::llabs((long long)(best->utime - ut)) > 2500) {
            return fail(err, gpath + ": no pose within 2.5 ms of frame " +
                                 std::to_string(frame - 1) + " (" + files[0][i] + ")");
        }
        const Pose T_WC = pose_mul(best->T, T_BS[0]);
        if (seq->truth.empty()) {
            C0_inv = pose_inv(T_WC);
        }
        seq->utime.push_back(ut);
        seq->img[0].push_back(files[0][i]);
        seq->img[1].push_back(files[1][i1]);
        seq->truth.push_back(pose_mul(C0_inv, T_WC));
    }
    if (seq->utime.empty()) {
        return fail(err, dir + ": no stereo frame" +
                             (o.first ? fmt(" from frame %zu (%zu in all)", o.first, frame)
                                      : std::string()));
    }
    return true;
}

FrameErr frame_error(const double p_est[6], const Pose &truth)
{
    const Pose E = pose_from_vec(p_est);
    FrameErr e;
    double s = 0.0;
    for (int i = 0; i < 3; ++i) {
        s += (E.t[i] - truth.t[i]) * (E.t[i] - truth.t[i]);
    }
    e.trans_m = std::sqrt(s);
    /* angle of E.R^T truth.R from its trace */
    double tr = 0.0;
    for (int i = 0; i < 9; ++i) {
        tr += E.R[i] * truth.R[i];
    }
    e.rot_rad = std::acos(std::max(-1.0, std::min(1.0, 0.5 * (tr - 1.0))));
    return e;
}

Summary summarise(const std::vector<Pose> &est, const std::vector<Pose> &truth)
{
    Summary s;
    s.frames = std::min(est.size(), truth.size());
    double se = 0.0, sr = 0.0, rpe = 0.0, et = 0.0, tt = 0.0;
    for (size_t j = 0; j < s.frames; ++j) {
        double p[6];
        pose_to_vec(est[j], p);
        for (int i = 0; i < 3; ++i) {
            et += est[j].t[i] * truth[j].t[i];
            tt += truth[j].t[i] * truth[j].t[i];
        }
        const FrameErr e = frame_error(p, truth[j]);
        se += e.trans_m * e.trans_m;
        sr += e.rot_rad * e.rot_rad;
        s.max_m = std::max(s.max_m, e.trans_m);
        s.final_m = e.trans_m;
        if (j > 0) {
            const Pose de = pose_mul(pose_inv(est[j - 1]), est[j]);
            const Pose dt = pose_mul(pose_inv(truth[j - 1]), truth[j]);
            double d = 0.0, r = 0.0;
            for (int i = 0; i < 3; ++i) {
                d += dt.t[i] * dt.t[i];
                r += (de.t[i] - dt.t[i]) * (de.t[i] - dt.t[i]);
            }
            s.path_m += std::sqrt(d);
            rpe += std::sqrt(r);
        }
    }
    if (s.frames) {
        s.ate_m = std::sqrt(se / (double)s.frames);
        s.rot_rmse_deg = std::sqrt(sr / (double)s.frames) * 180.0 / M_PI;
    }
    if (tt > 0.0) {
        s.scale = et / tt;
    }
    if (s.path_m > 0.0) {
        s.ate_percent = 100.0 * s.ate_m / s.path_m;
        s.rpe_percent = 100.0 * rpe / s.path_m;
    }
    return s;
}

}  // namespace rprd
