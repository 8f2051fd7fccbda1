/*
 * rigpose-calib - calibrates a rigpose rig from chessboard images and writes the daemon's YAML
 * configuration (config/README.md). Three modes:
 *
 *   rigpose-calib mono   [opts] IMAGE...
 *       intrinsics of one camera.
 *   rigpose-calib stereo [opts] --left IMAGE... --right IMAGE...
 *       intrinsics of both cameras, then the pair's R, T, E, F. Images are paired by the digits
 *       of their file names (left07.jpg with right07.jpg); an image without a partner is reported
 *       and used for its own camera's intrinsics only.
 *   rigpose-calib rig    [opts] --frames FRAMES.CSV [--pair COLA,COLB]...
 *       a whole rig from a replay folder's frames.csv (utime_us,cam0,cam1,... rows of
 *       simultaneous images, e.g. recorded by rigpose-log): intrinsics per column; each --pair
 *       (overlapping cameras seeing the same board) by stereo calibration; every other camera
 *       by hand-eye calibration against cam0 from its own static board seen over a common
 *       rig motion (rotate the rig about at least two axes). --intrinsics FILE.yaml takes the
 *       cameras' intrinsics from an earlier calibration (e.g. each camera's `mono` run merged, or
 *       any rigpose configuration with the same camera order) instead of estimating them from
 *       these views: a static board seen from a rig that turns a little gives weak intrinsics.
 *
 * Options: --board WxH (inner corners, default 9x6), --square M (metres, default 0.025),
 * --fix-aspect (fx / fy fixed to 1), --out FILE.yaml, --source v4l2|replay (default v4l2; rig
 * mode with replay points replay_index at FRAMES.CSV), --names a,b,... (camera names).
 * Every rejected image is reported on its own line ("FILE: rejected: why") and the others go on.
 * Exit: 0 calibrated (some images may have been rejected), 1 calibration impossible, 2 usage.
 */
#include <climits>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "rp_calib.hpp"

namespace {

void usage(FILE *out)
{
    std::fprintf(out,
                 "usage: rigpose-calib mono   [opts] IMAGE...\n"
                 "       rigpose-calib stereo [opts] --left IMAGE... --right IMAGE...\n"
                 "       rigpose-calib rig    [opts] --frames FRAMES.CSV [--pair COLA,COLB]...\n"
                 "                            [--intrinsics FILE.yaml]\n"
                 "opts:  --board WxH (inner corners, 9x6)  --square M (0.025)  --fix-aspect\n"
                 "       --out FILE.yaml  --source v4l2|replay  --names NAME,NAME,...\n");
}

std::vector<std::string> split(const std::string &s, char sep)
{
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, sep)) {
        out.push_back(item);
    }
    return out;
}

std::string basename_of(const std::string &p)
{
    const size_t k = p.find_last_of('/');
    return k == std::string::npos ? p : p.substr(k + 1);
}

std::string dirname_of(const std::string &p)
{
    const size_t k = p.find_last_of('/');
    return k == std::string::npos ? std::string(".") : p.substr(0, k);
}

/* The pairing key of a stereo image: the digits of its file name. */
std::string digits_of(const std::string &p)
{
    std::string d;
    for (char c : basename_of(p)) {
        if (std::isdigit(static_cast<unsigned char>(c))) {
            d += c;
        }
    }
    return d;
}

struct Args {
    std::string mode;
    rpc::Board board;
    rpc::IntrinsicsOpts iopts;
    std::string out, source = "v4l2", frames, intrinsics;
    std::vector<std::string> names, images, left, right, pairs;
};

bool parse(int argc, char **argv, Args *a)
{
    if (argc < 2) {
        return false;
    }
    a->mode = argv[1];
    std::vector<std::string> *list = &a->images;
    for (int i = 2; i < argc; ++i) {
        const std::string s = argv[i];
        const bool has_val = i + 1 < argc;
        if (s == "--board" && has_val) {
            int w = 0, h = 0;
            if (std::sscanf(argv[++i], "%dx%d", &w, &h) != 2 || w < 2 || h < 2) {
                std::fprintf(stderr, "rigpose-calib: --board wants WxH inner corners, e.g. 9x6\n");
                return false;
            }
            a->board.inner = cv::Size(w, h);
        } else if (s == "--square" && has_val) {
            a->board.square_m = std::atof(argv[++i]);
            if (!(a->board.square_m > 0.0)) {
                std::fprintf(stderr, "rigpose-calib: --square wants a positive length in metres\n");
                return false;
            }
        } else if (s == "--fix-aspect") {
            a->iopts.fix_aspect = true;
        } else if (s == "--out" && has_val) {
            a->out = argv[++i];
        } else if (s == "--source" && has_val) {
            a->source = argv[++i];
            if (a->source != "v4l2" && a->source != "replay") {
                std::fprintf(stderr, "rigpose-calib: --source is v4l2 or replay\n");
                return false;
            }
        } else if (s == "--names" && has_val) {
            a->names = split(argv[++i], ',');
        } else if (s == "--intrinsics" && has_val) {
            a->intrinsics = argv[++i];
        } else if (s == "--frames" && has_val) {
            a->frames = argv[++i];
        } else if (s == "--pair" && has_val) {
            a->pairs.push_back(argv[++i]);
        } else if (s == "--left") {
            list = &a->left;
        } else if (s == "--right") {
            list = &a->right;
        } else if (s.size() > 1 && s[0] == '-') {
            std::fprintf(stderr, "rigpose-calib: unknown or incomplete option %s\n", s.c_str());
            return false;
        } else {
            list->push_back(s);
        }
    }
    return true;
}

/* Detects the board in every file of one camera, printing one line per file. */
std::vector<rpc::View> detect_all(const std::string &cam, const std::vector<std::string> &files,
                                  const rpc::Board &board, cv::Size *size)
{
    std::vector<rpc::View> v;
    for (const std::string &f : files) {
        v.push_back(rpc::detect_board(f, board, size));
        if (!v.back().found) {
            std::printf("%s: %s: rejected: %s\n", cam.c_str(), f.c_str(), v.back().why.c_str());
        }
    }
    return v;
}

bool calib_camera(const std::string &cam, const std::vector<rpc::View> &views, cv::Size size,
                  const Args &a, rpc::Intrinsics *out)
{
    std::string why;
    if (!rpc::calibrate_intrinsics(views, a.board, size, a.iopts, out, &why)) {
        std::printf("%s: calibration failed: %s\n", cam.c_str(), why.c_str());
        return false;
    }
    for (size_t i = 0; i < out->used.size(); ++i) {
        std::printf("%s: %s: view RMS %.3f px\n", cam.c_str(),
                    views[static_cast<size_t>(out->used[i])].file.c_str(), out->view_rms_px[i]);
    }
    const rpc::Intrinsics &k = *out;
    size_t n_files = 0; /* empty views stand for a missing partner / row: not files */
    for (const rpc::View &v : views) {
        n_files += v.file.empty() ? 0u : 1u;
    }
    std::printf("%s: %zu of %zu images, %dx%d: fx %.3f fy %.3f cx %.3f cy %.3f  "
                "k1 %.5f k2 %.5f p1 %.6f p2 %.6f k3 %.5f  RMS %.4f px\n",
                cam.c_str(), k.used.size(), n_files, k.size.width, k.size.height, k.K(0, 0),
                k.K(1, 1), k.K(0, 2), k.K(1, 2), k.dist[0], k.dist[1], k.dist[2], k.dist[3],
                k.dist[4], k.rms_px);
    return true;
}

std::string name_of(const Args &a, size_t i, const std::string &dflt)
{
    return i < a.names.size() ? a.names[i] : dflt;
}

std::string device_of(const Args &a, size_t i, const std::string &column)
{
    return a.source == "replay" ? column : "/dev/video" + std::to_string(i);
}

int finish(const Args &a, const std::vector<rpc::CamOut> &cams,
           const std::vector<std::pair<int, int>> &pairs, const std::string &replay_index)
{
    if (a.out.empty()) {
        return 0;
    }
    std::string why;
    if (!rpc::write_config(a.out, cams, pairs, a.source, replay_index, "", &why)) {
        std::fprintf(stderr, "rigpose-calib: %s\n", why.c_str());
        return 1;
    }
    std::printf("wrote %s\n", a.out.c_str());
    return 0;
}

void print_stereo(const std::string &tag, const rpc::Stereo &s)
{
    const rpc::Pose &p = s.left_in_right;
    double lo = 1e9, hi = 0.0;
    for (double b : s.pair_baseline_m) {
        lo = std::min(lo, b);
        hi = std::max(hi, b);
    }
    std::printf("%s: %d pairs, RMS %.4f px, baseline %.5f m (per pair %.5f..%.5f m)\n"
                "%s: T = [%.6f %.6f %.6f] m, R =\n", tag.c_str(), s.n_pairs, s.rms_px,
                s.baseline_m, lo, hi, tag.c_str(), p.t[0], p.t[1], p.t[2]);
    for (int r = 0; r < 3; ++r) {
        std::printf("    [%10.7f %10.7f %10.7f]\n", p.R(r, 0), p.R(r, 1), p.R(r, 2));
    }
    std::printf("%s: F =\n", tag.c_str());
    for (int r = 0; r < 3; ++r) {
        std::printf("    [% .6e % .6e % .6e]\n", s.F(r, 0), s.F(r, 1), s.F(r, 2));
    }
}

int run_mono(const Args &a)
{
    if (a.images.empty()) {
        usage(stderr);
        return 2;
    }
    const std::string name = name_of(a, 0, "cam1");
    cv::Size size;
    const std::vector<rpc::View> v = detect_all(name, a.images, a.board, &size);
    rpc::CamOut c;
    c.name = name;
    c.device = device_of(a, 0, "cam0");
    if (!calib_camera(name, v, size, a, &c.intr)) {
        return 1;
    }
    return finish(a, {c}, {}, "");
}

int run_stereo(const Args &a)
{
    if (a.left.empty() || a.right.empty()) {
        usage(stderr);
        return 2;
    }
    /* pair by the digits of the file names */
    std::map<std::string, std::string> rmap;
    for (const std::string &r : a.right) {
        rmap[digits_of(r)] = r;
    }
    std::map<std::string, bool> lkeys;
    std::vector<std::string> lfiles = a.left, rfiles;
    for (const std::string &l : a.left) {
        lkeys[digits_of(l)] = true;
        auto it = rmap.find(digits_of(l));
        rfiles.push_back(it == rmap.end() ? std::string() : it->second);
        if (it == rmap.end()) {
            std::printf("stereo: %s: no right partner (key \"%s\"): left intrinsics only\n",
                        l.c_str(), digits_of(l).c_str());
        }
    }
    for (const std::string &r : a.right) {
        if (!lkeys.count(digits_of(r))) {
            std::printf("stereo: %s: no left partner (key \"%s\"): right intrinsics only\n",
                        r.c_str(), digits_of(r).c_str());
            lfiles.push_back(std::string());
            rfiles.push_back(r);
        }
    }
    const std::string nl = name_of(a, 0, "cam1"), nr = name_of(a, 1, "cam1b");
    cv::Size sl, sr;
    std::vector<rpc::View> vl, vr;
    for (size_t i = 0; i < lfiles.size(); ++i) {
        /* a missing partner is an empty view (not found, not reported again) */
        vl.push_back(lfiles[i].empty() ? rpc::View() : detect_all(nl, {lfiles[i]}, a.board, &sl)[0]);
        vr.push_back(rfiles[i].empty() ? rpc::View() : detect_all(nr, {rfiles[i]}, a.board, &sr)[0]);
    }
    std::vector<rpc::CamOut> cams(2);
    cams[0].name = nl;
    cams[0].device = device_of(a, 0, "cam0");
    cams[1].name = nr;
    cams[1].device = device_of(a, 1, "cam1");
    if (!calib_camera(nl, vl, sl, a, &cams[0].intr) || !calib_camera(nr, vr, sr, a, &cams[1].intr)) {
        return 1;
    }
    rpc::Stereo s;
    std::string why;
    if (!rpc::calibrate_stereo(vl, vr, a.board, cams[0].intr, cams[1].intr, &s, &why)) {
        std::printf("stereo: %s\n", why.c_str());
        return 1;
    }
    print_stereo("stereo " + nl + "-" + nr, s);
    cams[1].in_cam1 = s.left_in_right.inv();
    return finish(a, cams, {{0, 1}}, "");
}

/* Intrinsics of every camera, in order, from a rigpose configuration file as rigpose-calib and
 * rigpose-render write it (one `width:`, `height:`, `intrinsics: [...]`, optional
 * `distortion: [...]` line per camera). */
bool read_intrinsics(const std::string &path, std::vector<rpc::Intrinsics> *out)
{
    std::ifstream in(path);
    if (!in) {
        std::fprintf(stderr, "rigpose-calib: cannot read %s\n", path.c_str());
        return false;
    }
    std::string line;
    int w = 0, h = 0;
    while (std::getline(in, line)) {
        const size_t b = line.find('[');
        double v[5] = {0, 0, 0, 0, 0};
        if (line.find("width:") != std::string::npos) {
            w = std::atoi(line.c_str() + line.find(':') + 1);
        } else if (line.find("height:") != std::string::npos) {
            h = std::atoi(line.c_str() + line.find(':') + 1);
        } else if (line.find("intrinsics:") != std::string::npos && b != std::string::npos &&
                   std::sscanf(line.c_str() + b, "[%lf, %lf, %lf, %lf]", v, v + 1, v + 2, v + 3) == 4) {
            rpc::Intrinsics k;
            k.K = cv::Matx33d(v[0], 0, v[2], 0, v[1], v[3], 0, 0, 1);
            k.size = cv::Size(w, h);
            out->push_back(k);
        } else if (line.find("distortion:") != std::string::npos && b != std::string::npos &&
                   !out->empty() &&
                   std::sscanf(line.c_str() + b, "[%lf, %lf, %lf, %lf, %lf]", v, v + 1, v + 2, v + 3,
                               v + 4) == 5) {
            out->back().dist.assign(v, v + 5);
        }
    }
    if (out->empty()) {
        std::fprintf(stderr, "rigpose-calib: %s: no `intrinsics: [fx, fy, cx, cy]` line\n", path.c_str());
        return false;
    }
    return true;
}

/* frames.csv of a replay folder: header utime_us,cam0,... then rows; paths relative to it. */
bool read_frames(const std::string &path, std::vector<std::string> *cols,
                 std::vector<std::vector<std::string>> *files)
{
    std::ifstream in(path);
    std::string line;
    if (!in || !std::getline(in, line)) {
        std::fprintf(stderr, "rigpose-calib: cannot read %s\n", path.c_str());
        return false;
    }
    std::vector<std::string> h = split(line, ',');
    if (h.size() < 2 || h[0] != "utime_us") {
        std::fprintf(stderr, "rigpose-calib: %s: header must be utime_us,cam0,...\n", path.c_str());
        return false;
    }
    cols->assign(h.begin() + 1, h.end());
    files->assign(cols->size(), {});
    const std::string dir = dirname_of(path);
    int row = 1;
    while (std::getline(in, line)) {
        ++row;
        if (line.empty()) {
            continue;
        }
        std::vector<std::string> f = split(line, ',');
        if (f.size() != h.size()) {
            std::printf("%s:%d: %zu fields, header has %zu: row skipped\n", path.c_str(), row,
                        f.size(), h.size());
            continue;
        }
        for (size_t k = 0; k < cols->size(); ++k) {
            const std::string &p = f[k + 1];
            (*files)[k].push_back(p.empty() ? p : (p[0] == '/' ? p : dir + "/" + p));
        }
    }
    return true;
}

int run_rig(const Args &a)
{
    std::vector<std::string> cols;
    std::vector<std::vector<std::string>> files;
    if (a.frames.empty() || !read_frames(a.frames, &cols, &files)) {
        usage(stderr);
        return 2;
    }
    const size_t n = cols.size();
    if (n > 6) {
        std::fprintf(stderr, "rigpose-calib: at most 6 cameras (%zu columns)\n", n);
        return 2;
    }
    std::vector<std::pair<int, int>> pairs;
    for (const std::string &p : a.pairs) {
        std::vector<std::string> ab = split(p, ',');
        int ia = -1, ib = -1;
        for (size_t k = 0; k < n && ab.size() == 2; ++k) {
            ia = cols[k] == ab[0] ? static_cast<int>(k) : ia;
            ib = cols[k] == ab[1] ? static_cast<int>(k) : ib;
        }
        if (ia < 0 || ib < 0 || ia == ib || ib == 0) {
            std::fprintf(stderr, "rigpose-calib: --pair %s: two distinct columns of %s (the "
                                 "right one not cam0)\n", p.c_str(), a.frames.c_str());
            return 2;
        }
        pairs.emplace_back(ia, ib);
    }
    std::vector<rpc::Intrinsics> known;
    if (!a.intrinsics.empty() && (!read_intrinsics(a.intrinsics, &known) || known.size() != n)) {
        std::fprintf(stderr, "rigpose-calib: --intrinsics %s: want the intrinsics of %zu cameras\n",
                     a.intrinsics.c_str(), n);
        return 2;
    }
    std::vector<rpc::CamOut> cams(n);
    std::vector<std::vector<rpc::View>> views(n);
    for (size_t k = 0; k < n; ++k) {
        cams[k].name = name_of(a, k, "cam" + std::to_string(k + 1));
        cams[k].device = device_of(a, k, cols[k]);
        cv::Size size;
        for (const std::string &f : files[k]) {
            views[k].push_back(f.empty() ? rpc::View() : rpc::detect_board(f, a.board, &size));
            if (f.empty()) {
                std::printf("%s: row %zu: no image\n", cams[k].name.c_str(), views[k].size());
            } else if (!views[k].back().found) {
                std::printf("%s: %s: rejected: %s\n", cams[k].name.c_str(), f.c_str(),
                            views[k].back().why.c_str());
            }
        }
        Args ak = a;
        if (!known.empty()) {
            ak.iopts.fixed = &known[k];
        }
        if (!calib_camera(cams[k].name, views[k], size, ak, &cams[k].intr)) {
            return 1;
        }
    }
    /* board pose of camera k in row r (only rows where it found the board) */
    auto board_pose = [&](size_t k, size_t r, rpc::Pose *p) {
        const std::vector<int> &u = cams[k].intr.used;
        for (size_t i = 0; i < u.size(); ++i) {
            if (static_cast<size_t>(u[i]) == r) {
                *p = cams[k].intr.board_in_cam[i];
                return true;
            }
        }
        return false;
    };
    std::vector<bool> done(n, false), is_right(n, false);
    done[0] = true;
    for (const auto &p : pairs) {
        is_right[static_cast<size_t>(p.second)] = true;
    }
    for (size_t k = 1; k < n; ++k) {
        if (is_right[k]) {
            continue;
        }
        std::vector<rpc::Pose> pr, pk;
        std::vector<std::vector<cv::Point2f>> cr, ck;
        for (size_t r = 0; r < views[0].size(); ++r) {
            rpc::Pose a0, ak;
            if (board_pose(0, r, &a0) && board_pose(k, r, &ak)) {
                pr.push_back(a0);
                pk.push_back(ak);
                cr.push_back(views[0][r].corners);
                ck.push_back(views[k][r].corners);
            }
        }
        double er = 0.0, et = 0.0, rms = 0.0;
        std::string why;
        if (!rpc::hand_eye(pr, pk, &cams[k].in_cam1, &er, &et, &why) ||
            !rpc::refine_extrinsics(cr, ck, cams[0].intr, cams[k].intr, a.board, &cams[k].in_cam1,
                                    &rms, &why)) {
            std::printf("%s: extrinsics failed: %s\n", cams[k].name.c_str(), why.c_str());
            return 1;
        }
        done[k] = true;
        const rpc::Pose &x = cams[k].in_cam1;
        std::printf("%s: hand-eye over %zu sets (residual %.4f deg, %.2f mm), bundle-adjusted: "
                    "D = [%.5f %.5f %.5f] m, reprojection RMS %.3f px\n", cams[k].name.c_str(),
                    pr.size(), er * 180.0 / CV_PI, et * 1e3, x.t[0], x.t[1], x.t[2], rms);
    }
    for (const auto &p : pairs) {
        const size_t l = static_cast<size_t>(p.first), r = static_cast<size_t>(p.second);
        if (!done[l]) {
            std::fprintf(stderr, "rigpose-calib: pair %s,%s: its left camera is itself a right "
                                 "camera\n", cols[l].c_str(), cols[r].c_str());
            return 2;
        }
        rpc::Stereo s;
        std::string why;
        if (!rpc::calibrate_stereo(views[l], views[r], a.board, cams[l].intr, cams[r].intr, &s,
                                   &why)) {
            std::printf("stereo %s-%s: %s\n", cams[l].name.c_str(), cams[r].name.c_str(),
                        why.c_str());
            return 1;
        }
        print_stereo("stereo " + cams[l].name + "-" + cams[r].name, s);
        cams[r].in_cam1 = cams[l].in_cam1 * s.left_in_right.inv();
        done[r] = true;
    }
    /* replay_index is relative to the configuration file's folder */
    std::string index = a.frames;
    if (!a.out.empty() && dirname_of(a.out) == dirname_of(a.frames)) {
        index = basename_of(a.frames);
    } else if (char *abs = realpath(a.frames.c_str(), nullptr)) {
        index = abs;
        std::free(abs);
    }
    return finish(a, cams, pairs, index);
}

} // namespace

int main(int argc, char **argv)
{
    Args a;
    if (!parse(argc, argv, &a)) {
        usage(stderr);
        return 2;
    }
    if (a.mode == "mono") {
        return run_mono(a);
    }
    if (a.mode == "stereo") {
        return run_stereo(a);
    }
    if (a.mode == "rig") {
        return run_rig(a);
    }
    usage(a.mode == "--help" || a.mode == "-h" ? stdout : stderr);
    return a.mode == "--help" || a.mode == "-h" ? 0 : 2;
}
