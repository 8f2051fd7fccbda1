/*
 * rigpose-eval - how well estimated trajectories follow the truth (rp_eval.hpp):
 *
 *   rigpose-eval [--truth FILE] [--est [NAME=]FILE]... [FILE...] [options]
 *
 * Estimates: LCM logs of the daemon's rigpose.pose_t (e.g. `rigpose --lcm-url
 * file://run.log?mode=w`, or lcm-logger's), TUM files, rigpose CSV (utime_us,tx,ty,tz,alpha,beta,
 * gamma) or KITTI files. Truth: truth.csv of a replay folder, TUM, or, without --truth, the truth
 * carried by the first LCM log's messages. Prints per method the ATE (after --align) and the RPE
 * over --delta frames; writes TUM / KITTI copies, a six-panel PNG and a flat JSON of figures.
 *
 * Options:
 *   --align none|se3|sim3   ATE alignment (Umeyama; default none, as evo_ape without -a)
 *   --delta N               RPE step in frames (default 1)
 *   --max-dt-us N           association tolerance (default 1000 us)
 *   --channel NAME          pose channel in LCM logs (default RIGPOSE_POSE)
 *   --tum-dir DIR           write NAME.tum and truth.tum (the associated poses)
 *   --kitti-dir DIR         write NAME.kitti and truth.kitti (the associated poses, same rows)
 *   --euroc-dir DIR         write NAME.csv and truth.csv in EuRoC's ground-truth CSV
 *                           (timestamp ns, p_RS_R xyz, q_RS_w wxyz; `evo_ape euroc` reads it)
 *   --format tum|kitti|euroc --out-dir DIR   the same as --tum-dir / --kitti-dir / --euroc-dir DIR
 *   --plot FILE.png         six panels: tx ty tz alpha beta gamma against frame
 *   --title TEXT            the plot's title
 *   --json FILE             {"eval_<name>_ate_rmse_m": ..., "eval_<name>_rpe_trans_rmse_m": ...}
 *   --tolerant              read LCM logs on past truncated / corrupt stretches (one warning line
 *                           per skip: offset and bytes skipped) instead of refusing them
 * Exit: 0 done, 1 a file could not be read / evaluated (a truncated or corrupt LCM log: one line
 * "FILE: offset N: what"), 2 usage.
 */
#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "rp_eval.hpp"

namespace {

void usage(FILE *out)
{
    std::fprintf(out,
                 "usage: rigpose-eval [--truth FILE] [--est [NAME=]FILE]... [FILE...]\n"
                 "         [--align none|se3|sim3] [--delta N] [--max-dt-us N] [--channel NAME]\n"
                 "         [--tum-dir DIR] [--kitti-dir DIR] [--euroc-dir DIR]\n"
                 "         [--format tum|kitti|euroc --out-dir DIR] [--plot FILE.png] [--title TEXT]\n"
                 "         [--json FILE] [--tolerant]\n"
                 "estimates: LCM log (rigpose.pose_t), TUM, rigpose CSV or KITTI; truth: truth.csv,\n"
                 "TUM, or the truth inside the first LCM log\n");
}

struct Est {
    std::string name, path;
    rpe::Traj traj;
};

std::string stem(const std::string &p)
{
    std::string b = p.substr(p.find_last_of('/') == std::string::npos ? 0 : p.find_last_of('/') + 1);
    const size_t dot = b.find('.');
    return dot == std::string::npos || dot == 0 ? b : b.substr(0, dot);
}

bool make_dir(const std::string &d)
{
    return mkdir(d.c_str(), 0777) == 0 || errno == EEXIST;
}

} // namespace

int main(int argc, char **argv)
{
    std::string truth_path, channel = "RIGPOSE_POSE", tum_dir, kitti_dir, png, title, json;
    std::string euroc_dir, format, out_dir;
    rpe::Align align = rpe::Align::none;
    int delta = 1;
    long long max_dt = 1000;
    bool tolerant = false;
    std::vector<Est> ests;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool v = i + 1 < argc;
        if (a == "--help" || a == "-h") {
            usage(stdout);
            return 0;
        } else if (a == "--truth" && v) {
            truth_path = argv[++i];
        } else if (a == "--est" && v) {
            const std::string s = argv[++i];
            const size_t eq = s.find('=');
            Est e;
            e.path = eq == std::string::npos ? s : s.substr(eq + 1);
            e.name = eq == std::string::npos ? std::string() : s.substr(0, eq);
            ests.push_back(e);
        } else if (a == "--align" && v) {
            const std::string m = argv[++i];
            if (m == "none") {
                align = rpe::Align::none;
            } else if (m == "se3") {
                align = rpe::Align::se3;
            } else if (m == "sim3") {
                align = rpe::Align::sim3;
            } else {
                std::fprintf(stderr, "rigpose-eval: --align is none, se3 or sim3\n");
                return 2;
            }
        } else if (a == "--delta" && v) {
            delta = std::atoi(argv[++i]);
        } else if (a == "--max-dt-us" && v) {
            max_dt = std::atoll(argv[++i]);
        } else if (a == "--channel" && v) {
            channel = argv[++i];
        } else if (a == "--tum-dir" && v) {
            tum_dir = argv[++i];
        } else if (a == "--kitti-dir" && v) {
            kitti_dir = argv[++i];
        } else if (a == "--euroc-dir" && v) {
            euroc_dir = argv[++i];
        } else if (a == "--format" && v) {
            format = argv[++i];
        } else if (a == "--out-dir" && v) {
            out_dir = argv[++i];
        } else if (a == "--plot" && v) {
            png = argv[++i];
        } else if (a == "--title" && v) {
            title = argv[++i];
        } else if (a == "--json" && v) {
            json = argv[++i];
        } else if (a == "--tolerant") {
            tolerant = true;
        } else if (!a.empty() && a[0] != '-') {
            Est e;
            e.path = a;
            ests.push_back(e);
        } else {
            std::fprintf(stderr, "rigpose-eval: unknown or incomplete option %s\n", a.c_str());
            usage(stderr);
            return 2;
        }
    }
    if (ests.empty() || delta < 1 || max_dt < 0) {
        usage(stderr);
        return 2;
    }
    rpe::Traj truth, log_truth;
    std::string why;
    for (Est &e : ests) {
        std::string method;
        rpe::Traj lt;
        if (!rpe::load(e.path, channel, &e.traj, &lt, &method, &why, tolerant)) {
            std::fprintf(stderr, "rigpose-eval: %s\n", why.c_str());
            return 1;
        }
        if (log_truth.empty()) {
            log_truth = lt;
        }
        if (e.name.empty()) {
            e.name = method.empty() ? stem(e.path) : method;
        }
    }
    if (!truth_path.empty()) {
        if (!rpe::load(truth_path, channel, &truth, nullptr, nullptr, &why, tolerant)) {
            std::fprintf(stderr, "rigpose-eval: %s\n", why.c_str());
            return 1;
        }
    } else if (!log_truth.empty()) {
        truth = log_truth;
        truth_path = "the LCM log's truth";
    } else {
        std::fprintf(stderr, "rigpose-eval: no --truth, and no LCM log carries the truth\n");
        return 2;
    }
    const char *align_name = align == rpe::Align::none ? "none" : align == rpe::Align::se3 ? "SE(3)" : "Sim(3)";
    std::printf("truth: %s (%zu poses); ATE alignment %s; RPE over %d frame(s)\n",
                truth_path.c_str(), truth.size(), align_name, delta);
    std::printf("%-10s %6s %12s %12s %12s %12s %8s %14s %14s\n", "method", "poses", "ATE rmse m",
                "ATE mean m", "ATE median m", "ATE max m", "scale", "RPE t rmse m", "RPE r rmse deg");
    FILE *jf = nullptr;
    if (!json.empty() && !(jf = std::fopen(json.c_str(), "w"))) {
        std::fprintf(stderr, "rigpose-eval: cannot write %s\n", json.c_str());
        return 1;
    }
    if (jf) {
        std::fprintf(jf, "{");
    }
    if (!format.empty() || !out_dir.empty()) {
        std::string *dir = format == "tum" ? &tum_dir : format == "kitti" ? &kitti_dir
                         : format == "euroc" ? &euroc_dir : nullptr;
        if (!dir || out_dir.empty()) {
            std::fprintf(stderr, "rigpose-eval: --format tum|kitti|euroc goes with --out-dir DIR\n");
            return 2;
        }
        *dir = out_dir;
    }
    if ((!tum_dir.empty() && !make_dir(tum_dir)) || (!kitti_dir.empty() && !make_dir(kitti_dir)) ||
        (!euroc_dir.empty() && !make_dir(euroc_dir))) {
        std::fprintf(stderr, "rigpose-eval: cannot create the output folder\n");
        return 1;
    }
    int rc = 0;
    bool first_json = true;
    std::vector<rpe::Series> series;
    for (const Est &e : ests) {
        rpe::Stats a, rt, rr;
        double scale = 1.0;
        if (!rpe::ate(e.traj, truth, align, max_dt, &a, nullptr, &scale, &why) ||
            !rpe::rpe(e.traj, truth, delta, max_dt, &rt, &rr, &why)) {
            std::fprintf(stderr, "rigpose-eval: %s: %s\n", e.name.c_str(), why.c_str());
            rc = 1;
            continue;
        }
        std::printf("%-10s %6zu %12.6f %12.6f %12.6f %12.6f %8.4f %14.6f %14.4f\n", e.name.c_str(),
                    a.n, a.rmse, a.mean, a.median, a.max, scale, rt.rmse, rr.rmse * 180.0 / CV_PI);
        if (jf) {
            std::fprintf(jf, "%s\"eval_%s_ate_rmse_m\": %.9g, \"eval_%s_ate_max_m\": %.9g, "
                             "\"eval_%s_rpe_trans_rmse_m\": %.9g, \"eval_%s_rpe_rot_rmse_rad\": %.9g",
                         first_json ? "" : ", ", e.name.c_str(), a.rmse, e.name.c_str(), a.max,
                         e.name.c_str(), rt.rmse, e.name.c_str(), rr.rmse);
            first_json = false;
        }
        /* exports: the associated poses of both, row for row */
        rpe::Traj ae, at;
        for (const auto &p : rpe::associate(e.traj, truth, max_dt)) {
            ae.push_back(e.traj[p.first]);
            at.push_back(truth[p.second]);
        }
        if (!tum_dir.empty() && (!rpe::write_tum(tum_dir + "/" + e.name + ".tum", ae, &why) ||
                                 !rpe::write_tum(tum_dir + "/truth.tum", truth, &why))) {
            std::fprintf(stderr, "rigpose-eval: %s\n", why.c_str());
            rc = 1;
        }
        if (!kitti_dir.empty() &&
            (!rpe::write_kitti(kitti_dir + "/" + e.name + ".kitti", ae, &why) ||
             !rpe::write_kitti(kitti_dir + "/truth_" + e.name + ".kitti", at, &why))) {
            std::fprintf(stderr, "rigpose-eval: %s\n", why.c_str());
            rc = 1;
        }
        if (!euroc_dir.empty() &&
            (!rpe::write_euroc(euroc_dir + "/" + e.name + ".csv", ae, &why) ||
             !rpe::write_euroc(euroc_dir + "/truth.csv", truth, &why))) {
            std::fprintf(stderr, "rigpose-eval: %s\n", why.c_str());
            rc = 1;
        }
        series.push_back({e.name, e.traj});
    }
    if (jf) {
        std::fprintf(jf, "}\n");
        std::fclose(jf);
    }
    if (!png.empty()) {
        if (!rpe::plot(png, truth, series, max_dt, title, &why)) {
            std::fprintf(stderr, "rigpose-eval: %s\n", why.c_str());
            return 1;
        }
        std::printf("wrote %s\n", png.c_str());
    }
    return rc;
}
