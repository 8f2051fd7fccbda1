/*
 * rigpose-ba - the offline optimum as a yardstick (issue 16): the bundle adjustment of a whole
 * run with the rig model (rp_ba.hpp), fed exactly the measurements rigpose's estimator saw,
 * printed beside rigpose's own errors, with their ratio; on the simulation also the
 * Cramér-Rao bound of the same problem.
 *
 *   rigpose-ba --sim [--methods LIST] [--runs N] [--frames N] [--seed S] [--noise-px S]
 *              [--loss huber|cauchy|none] [--loss-scale K] [--json FILE] [--per-run]
 *   rigpose-ba --tracks FILE [--sigma-px S] [--loss L] [--loss-scale K] [--name NAME]
 *              [--json FILE]
 *
 * --sim: the paper's Table 1 protocol (rp_sim.h) run by run, in one process: each run's frame
 * sets are made once (rp_sim_frame), fed to rigpose's estimator configured as rigpose-sim
 * configures it (rp_sim_stereo_cfg, rp_sim_gc_cfg), and their features in the method's cameras
 * (stereo4: cam1, cam1b, cam3, cam3b; stereo2: cam1, cam1b; gc: cam1..cam4) become the batch
 * problem, started from rigpose's trajectory. Errors as rigpose-sim scores them (mean absolute
 * error per frame of tx ty tz alpha beta gamma over frames 1..N-1 of every run).
 * --tracks: a tracks file (rp_tracks.hpp; rigpose-realdata --tracks-out writes one), every
 * camera's features, started from the file's estimates; ATE (RMSE of the position error, no
 * alignment: both start at the world) of both against the file's truth by rp_eval.hpp.
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rigpose/rp_vo_gc.h"
#include "rigpose/rp_vo_stereo.h"
#include "rp_ba.hpp"
#include "rp_eval.hpp"
#include "rp_sim.h"
#include "rp_tracks.hpp"

namespace {

const char *const col_name[6] = {"tx", "ty", "tz", "alpha", "beta", "gamma"};

struct Figures {
    std::vector<std::pair<std::string, double>> v;
    void set(const std::string &k, double x)
    {
        if (std::isfinite(x)) {
            v.emplace_back(k, x); /* a figure that could not be measured is left out */
        }
    }
    bool write(const std::string &path) const
    {
        std::FILE *f = std::fopen(path.c_str(), "w");
        if (!f) {
            std::fprintf(stderr, "rigpose-ba: %s: cannot write\n", path.c_str());
            return false;
        }
        std::fprintf(f, "{");
        for (size_t i = 0; i < v.size(); ++i) {
            std::fprintf(f, "%s\n  \"%s\": %.9g", i ? "," : "", v[i].first.c_str(), v[i].second);
        }
        std::fprintf(f, "\n}\n");
        return std::fclose(f) == 0;
    }
};

struct Opts {
    bool sim = false;
    std::string tracks, name, json;
    std::vector<std::string> methods{"stereo4", "stereo2", "gc"};
    uint32_t runs = 50, frames = 100;
    uint64_t seed = 1;
    double noise_px = 0.5;
    double sigma_px = 1.0; /* --tracks: the pixel noise assumed */
    rpba::Loss loss = rpba::Loss::huber;
    double loss_scale = 2.0;
    double reject = -1;    /* sigmas; < 0: the mode's default (--sim 0: no outliers there;
                            * --tracks 5) */
    bool per_run = false;
};

void usage(std::FILE *out)
{
    std::fprintf(out,
        "usage: rigpose-ba --sim [options] | --tracks FILE [options]\n"
        "The batch optimum (bundle adjustment with the rig model, gauge at frame 0) over the\n"
        "measurements rigpose's estimator saw, beside rigpose's errors.\n"
        "  --sim              the paper's Table 1 protocol (rp_sim.h), run by run; also the\n"
        "                     Cramer-Rao bound of each run's problem\n"
        "  --methods LIST     with --sim: stereo4, stereo2, gc (default all three)\n"
        "  --runs N           with --sim: runs (default 50)\n"
        "  --frames N         with --sim: frames per run (default 100)\n"
        "  --seed S           with --sim: experiment seed (default 1)\n"
        "  --noise-px S       with --sim: pixel noise sigma (default 0.5); the batch's sigma\n"
        "  --per-run          with --sim: one line per run and method\n"
        "  --tracks FILE      a tracks file (rigpose-realdata --tracks-out): ATE of rigpose's\n"
        "                     estimates and of the batch optimum against the file's truth\n"
        "  --sigma-px S       with --tracks: pixel noise assumed (default 1)\n"
        "  --name NAME        with --tracks: figure prefix (default: the file's name)\n"
        "  --loss L           huber (default), cauchy or none\n"
        "  --loss-scale K     the robust loss's threshold in sigmas (default 2)\n"
        "  --reject K         after solving, leave out observations over K sigmas and solve\n"
        "                     again (up to 3 more rounds); 0: never (default: --sim 0, the\n"
        "                     simulation has no outliers; --tracks 5)\n"
        "  --json FILE        write the figures as one flat JSON object\n"
        "  --help             this text\n");
}

bool split_methods(const std::string &s, std::vector<std::string> *out)
{
    out->clear();
    size_t p = 0;
    while (p <= s.size()) {
        const size_t c = s.find(',', p);
        const std::string m = s.substr(p, c == std::string::npos ? std::string::npos : c - p);
        if (m != "stereo4" && m != "stereo2" && m != "gc") {
            std::fprintf(stderr, "rigpose-ba: unknown method '%s' (stereo4, stereo2, gc)\n",
                         m.c_str());
            return false;
        }
        out->push_back(m);
        if (c == std::string::npos) {
            break;
        }
        p = c + 1;
    }
    return !out->empty();
}

/* 0 ok, 1 help, 2 bad. */
int parse(int argc, char **argv, Opts *o)
{
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--help" || a == "-h") {
            return 1;
        }
        if (a == "--sim") {
            o->sim = true;
            continue;
        }
        if (a == "--per-run") {
            o->per_run = true;
            continue;
        }
        if (i + 1 >= argc) {
            std::fprintf(stderr, "rigpose-ba: %s needs a value (or is unknown)\n", a.c_str());
            return 2;
        }
        const char *v = argv[++i];
        char *end = nullptr;
        bool bad = false;
        if (a == "--tracks") {
            o->tracks = v;
        } else if (a == "--name") {
            o->name = v;
        } else if (a == "--json") {
            o->json = v;
        } else if (a == "--methods") {
            bad = !split_methods(v, &o->methods);
        } else if (a == "--runs") {
            const unsigned long x = std::strtoul(v, &end, 10);
            bad = *end || x < 1 || x > 100000;
            o->runs = (uint32_t)x;
        } else if (a == "--frames") {
            const unsigned long x = std::strtoul(v, &end, 10);
            bad = *end || x < 2 || x > 100000;
            o->frames = (uint32_t)x;
        } else if (a == "--seed") {
            o->seed = std::strtoull(v, &end, 0);
            bad = *end != 0;
        } else if (a == "--noise-px" || a == "--sigma-px" || a == "--loss-scale") {
            const double x = std::strtod(v, &end);
            bad = *end || !(x > 0 && x < 100);
            (a == "--noise-px" ? o->noise_px : a == "--sigma-px" ? o->sigma_px : o->loss_scale) = x;
        } else if (a == "--reject") {
            const double x = std::strtod(v, &end);
            bad = *end || !(x >= 0 && x < 1000);
            o->reject = x;
        } else if (a == "--loss") {
            const std::string l = v;
            bad = l != "huber" && l != "cauchy" && l != "none";
            o->loss = l == "cauchy" ? rpba::Loss::cauchy : l == "none" ? rpba::Loss::none
                                                                        : rpba::Loss::huber;
        } else {
            std::fprintf(stderr, "rigpose-ba: unknown option '%s'\n", a.c_str());
            return 2;
        }
        if (bad) {
            std::fprintf(stderr, "rigpose-ba: bad value for %s: '%s'\n", a.c_str(), v);
            return 2;
        }
    }
    if (o->sim == !o->tracks.empty()) {
        std::fprintf(stderr, "rigpose-ba: one of --sim or --tracks FILE\n");
        return 2;
    }
    return 0;
}

double wrap(double x)
{
    return std::remainder(x, 2.0 * M_PI);
}

/* Sums over the scored frames of one method: absolute and squared errors per column of
 * rigpose and of the batch optimum, and the bound's sqrt(C_ii) and C_ii. */
struct Acc {
    double abs[2][6] = {}, sq[2][6] = {}, crb_sd[6] = {}, crb_var[6] = {};
    size_t n = 0, n_crb = 0, landmarks = 0, obs = 0, fallback = 0, not_converged = 0;
    double seconds = 0, rms_px = 0;
    size_t runs = 0, failed = 0, crb_failed = 0;
};

/* One simulated method: the cameras whose features it takes, its estimator. */
struct SimMethod {
    std::string name;
    std::vector<uint8_t> cams;
    bool gc;
    bool both_pairs;
};

SimMethod sim_method(const std::string &m)
{
    if (m == "stereo4") {
        return {m, {RP_SIM_CAM1, RP_SIM_CAM1B, RP_SIM_CAM3, RP_SIM_CAM3B}, false, true};
    }
    if (m == "stereo2") {
        return {m, {RP_SIM_CAM1, RP_SIM_CAM1B}, false, false};
    }
    return {m, {RP_SIM_CAM1, RP_SIM_CAM2, RP_SIM_CAM3, RP_SIM_CAM4}, true, false};
}

/* rigpose's estimates of run `sr` by method m, and the problem of what it saw. */
bool run_rigpose(const SimMethod &m, const rp_sim_run_t &sr, uint32_t frames,
                 std::vector<rpba::Pose6> *est, rpba::Problem *pb)
{
    std::unique_ptr<rp_frameset_t> fs(new rp_frameset_t());
    std::unique_ptr<rp_vo_stereo_t> st;
    std::unique_ptr<rp_vo_gc_t> gc;
    rp_status_t s;
    if (m.gc) {
        gc.reset(new rp_vo_gc_t());
        const rp_vo_gc_cfg_t cfg = rp_sim_gc_cfg(&sr.cfg);
        s = rp_vo_gc_init(gc.get(), &sr.rig, &cfg);
    } else {
        st.reset(new rp_vo_stereo_t());
        const rp_vo_stereo_cfg_t cfg = rp_sim_stereo_cfg(&sr.cfg, m.both_pairs);
        s = rp_vo_stereo_init(st.get(), &sr.rig, &cfg);
    }
    if (s != RP_OK) {
        std::fprintf(stderr, "rigpose-ba: %s: init: %s\n", m.name.c_str(), rp_status_str(s));
        return false;
    }
    pb->rig = sr.rig;
    pb->n_frames = frames;
    pb->obs.clear();
    est->assign(frames, rpba::Pose6());
    for (uint32_t j = 0; j < frames; ++j) {
        (void)rp_sim_frame(&sr, j, fs.get());
        rp_estimate_t e;
        (void)(m.gc ? rp_vo_gc_step(gc.get(), fs.get(), &e)
                    : rp_vo_stereo_step(st.get(), fs.get(), &e));
        for (int i = 0; i < 6; ++i) {
            (*est)[j][i] = (double)e.p[i];
        }
        for (uint8_t k : m.cams) {
            for (unsigned i = 0; i < fs->n[k]; ++i) {
                pb->obs.push_back({j, k, fs->f[k][i].id,
                                   {(double)fs->f[k][i].uv[0], (double)fs->f[k][i].uv[1]}});
            }
        }
    }
    return true;
}

void print_row(const char *what, const double v[6], double t, double r)
{
    std::printf("  %-24s", what);
    for (int c = 0; c < 6; ++c) {
        std::printf(" %9.6f", v[c]);
    }
    std::printf("  %9.6f %9.6f\n", t, r);
}

void print_ratio(const char *what, const double a[6], const double b[6])
{
    std::printf("  %-24s", what);
    double ta = 0, tb = 0, ra = 0, rb = 0;
    for (int c = 0; c < 6; ++c) {
        std::printf(" %9.2f", a[c] / b[c]);
        (c < 3 ? ta : ra) += a[c];
        (c < 3 ? tb : rb) += b[c];
    }
    std::printf("  %9.2f %9.2f\n", ta / tb, ra / rb);
}

double mean3(const double v[6], int from)
{
    return (v[from] + v[from + 1] + v[from + 2]) / 3.0;
}

int run_sim(const Opts &o)
{
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.noise_px = o.noise_px;
    cfg.n_frames = o.frames;
    rpba::Options bo;
    bo.sigma_px = o.noise_px;
    bo.loss = o.loss;
    bo.loss_scale = o.loss_scale;
    bo.fallback_depth = (cfg.r_in + cfg.r_out) / 2.0;
    bo.reject_sigma = o.reject < 0 ? 0.0 : o.reject;
    Figures fig;
    std::printf("rigpose-ba: the batch optimum and the Cramer-Rao bound on the paper's "
                "simulation protocol (Table 1)\n"
                "  %u runs x %u frames, seed %llu, pixel noise %.3g px; fx = fy = %.0f px, "
                "640x480, principal point at the centre\n"
                "  batch: poses + every landmark seen in >= 2 frames, %s loss at %.3g sigma, "
                "frame 0 fixed, started from rigpose's trajectory\n"
                "  mean absolute error per frame over frames 1..%u of every run (m, rad); "
                "t, r: means of the three columns\n"
                "  CRB: the bound's sqrt(C_ii) x sqrt(2/pi), the mean absolute error of an "
                "unbiased Gaussian estimator at the bound\n",
                o.runs, o.frames, (unsigned long long)o.seed, o.noise_px, cfg.focal_px,
                o.loss == rpba::Loss::huber ? "Huber" : o.loss == rpba::Loss::cauchy ? "Cauchy"
                                                                                     : "no robust",
                o.loss_scale, o.frames - 1);
    fig.set("ba_runs", o.runs);
    const double gauss_mae = std::sqrt(2.0 / M_PI);
    for (const std::string &mname : o.methods) {
        const SimMethod m = sim_method(mname);
        Acc acc;
        for (uint32_t r = 0; r < o.runs; ++r) {
            rp_sim_run_t sr;
            if (rp_sim_run_init(&sr, &cfg, o.seed, r) != 0) {
                std::fprintf(stderr, "rigpose-ba: out of memory\n");
                return 1;
            }
            std::vector<rpba::Pose6> est, truth(o.frames);
            rpba::Problem pb;
            if (!run_rigpose(m, sr, o.frames, &est, &pb)) {
                rp_sim_run_free(&sr);
                return 1;
            }
            for (uint32_t j = 0; j < o.frames; ++j) {
                for (int i = 0; i < 6; ++i) {
                    truth[j][i] = sr.truth[6u * j + (unsigned)i];
                }
            }
            rpba::Result res;
            std::string why;
            ++acc.runs;
            if (!rpba::solve(pb, est, bo, &res, &why)) {
                std::fprintf(stderr, "rigpose-ba: %s run %u: %s\n", mname.c_str(), r, why.c_str());
                ++acc.failed;
                rp_sim_run_free(&sr);
                continue;
            }
            std::vector<std::pair<uint32_t, rpba::Vec3>> lm;
            std::vector<char> seen(cfg.n_points, 0);
            for (const rpba::Obs &ob : pb.obs) {
                if (!seen[ob.id]) {
                    seen[ob.id] = 1;
                    lm.push_back({ob.id, {sr.points[3 * ob.id], sr.points[3 * ob.id + 1],
                                          sr.points[3 * ob.id + 2]}});
                }
            }
            std::vector<rpba::Cov6> cov;
            const bool have_crb = rpba::crb(pb, truth, lm, o.noise_px, &cov, &why);
            if (!have_crb) {
                std::fprintf(stderr, "rigpose-ba: %s run %u: %s\n", mname.c_str(), r, why.c_str());
                ++acc.crb_failed;
            }
            double run_abs[2][6] = {};
            for (uint32_t j = 1; j < o.frames; ++j) {
                const rpba::Pose6 *p[2] = {&est[j], &res.pose[j]};
                for (int w = 0; w < 2; ++w) {
                    for (int c = 0; c < 6; ++c) {
                        const double e = c < 3 ? (*p[w])[c] - truth[j][c]
                                               : wrap((*p[w])[c] - truth[j][c]);
                        acc.abs[w][c] += std::fabs(e);
                        acc.sq[w][c] += e * e;
                        run_abs[w][c] += std::fabs(e);
                    }
                }
                ++acc.n;
                if (have_crb && std::isfinite(cov[j][0])) {
                    double Cw[9], Ca[9];
                    for (int e = 0; e < 9; ++e) {
                        Cw[e] = cov[j][6 * (3 + e / 3) + 3 + e % 3];
                    }
                    rpba::angles_cov(truth[j], Cw, Ca);
                    for (int c = 0; c < 6; ++c) {
                        const double var = c < 3 ? cov[j][7 * c] : Ca[4 * (c - 3)];
                        acc.crb_sd[c] += std::sqrt(var);
                        acc.crb_var[c] += var;
                    }
                    ++acc.n_crb;
                }
            }
            acc.landmarks += res.n_landmarks;
            acc.obs += res.n_obs;
            acc.fallback += res.n_fallback;
            acc.not_converged += res.converged ? 0 : 1;
            acc.seconds += res.seconds;
            acc.rms_px += res.rms_px_final;
            if (o.per_run) {
                const double n = (double)(o.frames - 1);
                std::printf("  run %3u %-8s t rigpose %.6f batch %.6f  r rigpose %.6f batch %.6f"
                            "  %zu landmarks, %d iterations, rms %.3f -> %.3f px, %.2f s\n",
                            r, mname.c_str(), mean3(run_abs[0], 0) / n, mean3(run_abs[1], 0) / n,
                            mean3(run_abs[0], 3) / n, mean3(run_abs[1], 3) / n, res.n_landmarks,
                            res.iterations, res.rms_px_initial, res.rms_px_final, res.seconds);
            }
            rp_sim_run_free(&sr);
        }
        if (acc.n == 0) {
            continue;
        }
        double mae[2][6], crb_mae[6];
        for (int c = 0; c < 6; ++c) {
            for (int w = 0; w < 2; ++w) {
                mae[w][c] = acc.abs[w][c] / (double)acc.n;
            }
            crb_mae[c] = acc.n_crb ? gauss_mae * acc.crb_sd[c] / (double)acc.n_crb : NAN;
        }
        const double nr = (double)(acc.runs - acc.failed);
        std::printf("\n  %-24s %9s %9s %9s %9s %9s %9s  %9s %9s\n", mname.c_str(), "tx", "ty", "tz",
                    "alpha", "beta", "gamma", "t", "r");
        print_row("rigpose", mae[0], mean3(mae[0], 0), mean3(mae[0], 3));
        print_row("batch optimum", mae[1], mean3(mae[1], 0), mean3(mae[1], 3));
        print_row("CRB (as mean abs.)", crb_mae, mean3(crb_mae, 0), mean3(crb_mae, 3));
        print_ratio("rigpose / batch", mae[0], mae[1]);
        print_ratio("rigpose / CRB", mae[0], crb_mae);
        print_ratio("batch / CRB", mae[1], crb_mae);
        std::printf("  RMS: rigpose t %.6f r %.6f, batch t %.6f r %.6f, CRB t %.6f r %.6f "
                    "(RMS over the three columns)\n",
                    std::sqrt(mean3(acc.sq[0], 0) / (double)acc.n),
                    std::sqrt(mean3(acc.sq[0], 3) / (double)acc.n),
                    std::sqrt(mean3(acc.sq[1], 0) / (double)acc.n),
                    std::sqrt(mean3(acc.sq[1], 3) / (double)acc.n),
                    std::sqrt(mean3(acc.crb_var, 0) / (double)acc.n_crb),
                    std::sqrt(mean3(acc.crb_var, 3) / (double)acc.n_crb));
        std::printf("  batch: %.0f landmarks, %.0f observations per run (%.1f started at the "
                    "fallback depth), rms %.3f px, %.2f s per run; %zu runs not converged, %zu "
                    "failed, %zu without a bound\n",
                    (double)acc.landmarks / nr, (double)acc.obs / nr, (double)acc.fallback / nr,
                    acc.rms_px / nr, acc.seconds / nr, acc.not_converged, acc.failed,
                    acc.crb_failed);
        const std::string p = "ba_" + mname + "_";
        const char *wn[2] = {"rigpose", "batch"};
        for (int w = 0; w < 2; ++w) {
            fig.set(p + wn[w] + "_t", mean3(mae[w], 0));
            fig.set(p + wn[w] + "_r", mean3(mae[w], 3));
            fig.set(p + wn[w] + "_rms_t", std::sqrt(mean3(acc.sq[w], 0) / (double)acc.n));
            fig.set(p + wn[w] + "_rms_r", std::sqrt(mean3(acc.sq[w], 3) / (double)acc.n));
        }
        for (int c = 0; c < 6; ++c) {
            fig.set(p + "batch_" + col_name[c], mae[1][c]);
            fig.set(p + "crb_" + col_name[c], crb_mae[c]);
        }
        fig.set(p + "crb_t", mean3(crb_mae, 0));
        fig.set(p + "crb_r", mean3(crb_mae, 3));
        if (acc.n_crb) {
            fig.set(p + "crb_rms_t", std::sqrt(mean3(acc.crb_var, 0) / (double)acc.n_crb));
            fig.set(p + "crb_rms_r", std::sqrt(mean3(acc.crb_var, 3) / (double)acc.n_crb));
        }
        fig.set(p + "ratio_t", mean3(mae[0], 0) / mean3(mae[1], 0));
        fig.set(p + "ratio_r", mean3(mae[0], 3) / mean3(mae[1], 3));
        fig.set(p + "rigpose_crb_ratio_t", mean3(mae[0], 0) / mean3(crb_mae, 0));
        fig.set(p + "rigpose_crb_ratio_r", mean3(mae[0], 3) / mean3(crb_mae, 3));
        fig.set(p + "batch_crb_ratio_t", mean3(mae[1], 0) / mean3(crb_mae, 0));
        fig.set(p + "batch_crb_ratio_r", mean3(mae[1], 3) / mean3(crb_mae, 3));
        fig.set(p + "s_per_run", acc.seconds / nr);
        fig.set(p + "failed_runs", (double)acc.failed);
    }
    return o.json.empty() || fig.write(o.json) ? 0 : 1;
}

rpe::Traj to_traj(const std::vector<rptk::Frame> &fr, const std::vector<rpba::Pose6> &p)
{
    rpe::Traj t;
    for (size_t j = 0; j < p.size(); ++j) {
        rpe::Pose q;
        q.utime = fr[j].utime;
        q.t = cv::Vec3d(p[j][0], p[j][1], p[j][2]);
        q.R = rpe::rot_from_angles(cv::Vec3d(p[j][3], p[j][4], p[j][5]));
        t.push_back(q);
    }
    return t;
}

int run_tracks(const Opts &o)
{
    rptk::Tracks tk;
    std::string why;
    if (!rptk::read(o.tracks, &tk, &why)) {
        std::fprintf(stderr, "rigpose-ba: %s\n", why.c_str());
        return 2;
    }
    const std::string name = !o.name.empty() ? o.name : !tk.name.empty() ? tk.name : "tracks";
    rpba::Problem pb;
    pb.rig = tk.rig;
    pb.n_frames = tk.frames.size();
    std::vector<rpba::Pose6> est(pb.n_frames), truth(pb.n_frames);
    bool all_truth = true;
    size_t n_lost = 0;
    for (size_t j = 0; j < pb.n_frames; ++j) {
        const rptk::Frame &f = tk.frames[j];
        for (int i = 0; i < 6; ++i) {
            est[j][i] = f.est[i];
            truth[j][i] = f.truth[i];
        }
        all_truth = all_truth && f.has_truth;
        n_lost += (f.est_flags & RP_EST_LOST) ? 1 : 0;
        for (const rptk::Feat &ft : f.f) {
            pb.obs.push_back({(uint32_t)j, ft.cam, ft.id, {ft.uv[0], ft.uv[1]}});
        }
    }
    rpba::Options bo;
    bo.sigma_px = o.sigma_px;
    bo.loss = o.loss;
    bo.loss_scale = o.loss_scale;
    bo.reject_sigma = o.reject < 0 ? 5.0 : o.reject;
    rpba::Result res;
    if (!rpba::solve(pb, est, bo, &res, &why)) {
        std::fprintf(stderr, "rigpose-ba: %s\n", why.c_str());
        return 1;
    }
    size_t n_free = 0;
    for (size_t j = 1; j < pb.n_frames; ++j) {
        n_free += res.constrained[j] ? 0 : 1;
    }
    std::printf("rigpose-ba: %s, %zu frames, %u cameras; %zu observations of %zu landmarks "
                "(seen in >= 2 frames; %zu started at the median depth), %zu frames rigpose lost, "
                "%zu frames without observations (kept at rigpose's pose)\n"
                "  batch: %s loss at %.3g x %.3g px, frame 0 fixed, rejection over %.3g sigma "
                "(%zu observations left out); %d iterations (%s), RMS reprojection %.3f -> %.3f "
                "px, median %.3f px, %.2f s\n",
                name.c_str(), pb.n_frames, (unsigned)pb.rig.n_cams, res.n_obs, res.n_landmarks,
                res.n_fallback, n_lost, n_free,
                o.loss == rpba::Loss::huber ? "Huber" : o.loss == rpba::Loss::cauchy ? "Cauchy"
                                                                                     : "no robust",
                o.loss_scale, o.sigma_px, bo.reject_sigma, res.n_obs_rejected, res.iterations,
                res.converged ? "converged" : "not converged", res.rms_px_initial,
                res.rms_px_final, res.median_px_final, res.seconds);
    Figures fig;
    const std::string p = "ba_" + name + "_";
    fig.set(p + "frames", (double)pb.n_frames);
    fig.set(p + "landmarks", (double)res.n_landmarks);
    fig.set(p + "rms_px", res.rms_px_final);
    fig.set(p + "rejected_obs", (double)res.n_obs_rejected);
    if (!all_truth) {
        std::printf("  no ground truth in the file: no ATE\n");
    } else {
        const rpe::Traj ref = to_traj(tk.frames, truth);
        rpe::Stats s[2];
        for (int w = 0; w < 2; ++w) {
            if (!rpe::ate(to_traj(tk.frames, w ? res.pose : est), ref, rpe::Align::none, 1000,
                          &s[w], nullptr, nullptr, &why)) {
                std::fprintf(stderr, "rigpose-ba: ATE: %s\n", why.c_str());
                return 1;
            }
        }
        std::printf("\n  | %s | ATE (RMSE, no alignment) | max |\n  |---|---|---|\n",
                    name.c_str());
        std::printf("  | rigpose | %.4f m | %.4f m |\n", s[0].rmse, s[0].max);
        std::printf("  | batch optimum over rigpose's tracks | %.4f m | %.4f m |\n", s[1].rmse,
                    s[1].max);
        std::printf("  | rigpose / batch | %.2f | |\n", s[0].rmse / s[1].rmse);
        fig.set(p + "rigpose_ate_m", s[0].rmse);
        fig.set(p + "batch_ate_m", s[1].rmse);
        fig.set(p + "ratio_ate", s[0].rmse / s[1].rmse);
    }
    return o.json.empty() || fig.write(o.json) ? 0 : 1;
}

}  // namespace

int main(int argc, char **argv)
{
    Opts o;
    const int r = parse(argc, argv, &o);
    if (r == 1) {
        usage(stdout);
        return 0;
    }
    if (r) {
        usage(stderr);
        return 2;
    }
    return o.sim ? run_sim(o) : run_tracks(o);
}
