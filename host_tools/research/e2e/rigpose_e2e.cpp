/*
 * rigpose-e2e - rigpose from pixels: rendered frame sets (rp_render.hpp: the paper's rig and
 * motion through the textured shell, or with --points rp_sim's own points as textured discs)
 * -> the core's image pipeline (rp_pipe.h: trackers, stereo
 * matching, the layout's estimator) -> poses, scored as rigpose-sim scores them: for every frame
 * j >= 1 (frame 0 defines the world) the absolute error of each pose column, |t_est - t_true|
 * for tx ty tz and |wrap(angle_est - angle_true)| for alpha beta gamma; the table shows the means
 * over all scored frames of all runs, one row per method.
 *
 * Beside each pixel-level row it prints the feature-level row of the same runs: the same
 * estimator configuration fed rigpose-sim's simulated features (rp_sim_frame: 10,000 shell
 * points, 0.5 px noise) along the same trajectories, and the ratio pixel / feature; and the
 * same feature model with the 10,000 points on the rendered surface (rpr::surface_features):
 * the scene's own depths, which set gc's metric scale (host_tools/research/gcdiag/README.md). With
 * --points the scene is the feature-level simulation's own (its depths too), so the surface row
 * would repeat the sim row and is left out.
 *
 * Run r of `--runs N` is run r of the experiment `--seed` (the motion of rigpose-sim's run r);
 * every method sees the same rendered images.
 *
 * usage: rigpose-e2e [--methods LIST] [--runs N] [--first-run R] [--check M=TX,...]
 *                    [--json-out FILE] [render options, see --help]
 */
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include <opencv2/core.hpp>

#include "../../common/rp_cfg_diff.h"
#include "rigpose/rp_pipe.h"
#include "rp_render.hpp"
#include "rp_render_cli.hpp"
#include "rp_sim.h"

namespace {

const int NCOL = 6;
const char *const col_name[NCOL] = {"tx", "ty", "tz", "alpha", "beta", "gamma"};

struct Method {
    rp_pipe_layout_t layout;
    std::string name;
    double check_tx = -1.0; /* --check bound on the mean tx error, m (< 0: none) */
    /* accumulated over runs */
    double err[NCOL] = {0, 0, 0, 0, 0, 0};     /* pixel level: sums of absolute errors */
    double err_sim[NCOL] = {0, 0, 0, 0, 0, 0}; /* feature level, same runs */
    double err_surf[NCOL] = {0, 0, 0, 0, 0, 0}; /* feature level on the rendered surface */
    double worst_run_tx = 0.0;
    unsigned long lost = 0, lost_sim = 0, lost_surf = 0, frames = 0;
    double us_per_frame_sum = 0.0;
    unsigned long feats = 0; /* features given to the estimator, all cameras, all frames */
    /* --track-truth: each feature's world point, picked at its first frame, and
     * the distance of later tracked positions from its true projection */
    std::unordered_map<uint32_t, std::array<double, 5>> born[RP_MAX_CAMS]; /* X, picked?, frame */
    double tt_age_sum[4] = {0, 0, 0, 0};
    unsigned long tt_age_n[4] = {0, 0, 0, 0}, tt_age_3px[4] = {0, 0, 0, 0};
    unsigned long tt_n = 0, tt_1px = 0, tt_3px = 0, tt_born = 0, tt_unpicked = 0;
    double tt_sum = 0.0;
};

/* --track-truth: scores the features of frame set fs (frame j) against the scene. */
void track_truth(const rpr::Sequence &seq, uint32_t j, const rp_frameset_t &fs, Method *m)
{
    rp_real tp[6];
    for (int c = 0; c < 6; ++c) {
        tp[c] = (rp_real)seq.truth(j)[c];
    }
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, tp) != RP_OK) {
        return;
    }
    for (int k = 0; k < RP_MAX_CAMS && k < seq.rig().n_cams; ++k) {
        for (uint16_t i = 0; i < fs.n[k]; ++i) {
            const rp_feat_t &f = fs.f[k][i];
            auto it = m->born[k].find(f.id);
            if (it == m->born[k].end()) {
                std::array<double, 5> rec = {0, 0, 0, 0, (double)j};
                rec[3] = seq.world_point_at(j, k, f.uv, rec.data()) ? 1.0 : 0.0;
                m->born[k][f.id] = rec;
                m->tt_born++;
                m->tt_unpicked += rec[3] == 0.0;
                continue;
            }
            if (it->second[3] == 0.0) {
                continue;
            }
            const rp_real M[3] = {(rp_real)it->second[0], (rp_real)it->second[1],
                                  (rp_real)it->second[2]};
            rp_real uv[2];
            if (rp_rig_project(&seq.rig(), (uint8_t)k, &pl, M, uv, nullptr, nullptr) != RP_OK) {
                continue;
            }
            const double e = std::hypot((double)(f.uv[0] - uv[0]), (double)(f.uv[1] - uv[1]));
            m->tt_n++;
            m->tt_sum += e;
            m->tt_1px += e > 1.0;
            m->tt_3px += e > 3.0;
            const double age = j - it->second[4];
            const int b = age <= 1 ? 0 : (age <= 5 ? 1 : (age <= 20 ? 2 : 3));
            m->tt_age_sum[b] += e;
            m->tt_age_n[b]++;
            m->tt_age_3px[b] += e > 3.0;
        }
    }
}

double wrap_angle(double x)
{
    x = std::fmod(x + M_PI, 2.0 * M_PI);
    if (x < 0.0) {
        x += 2.0 * M_PI;
    }
    return x - M_PI;
}

/* With --motion turn / pitch the angles are compared as rigpose-sim does then: with the nearer
 * of the truth's two triples (a, b, g) and (a + pi, pi - b, g + pi), the same rotation. */
bool g_equiv_angles = false;

void add_err(const rp_real p[6], const double *truth, double acc[NCOL])
{
    for (int c = 0; c < 3; ++c) {
        acc[c] += std::fabs((double)p[c] - truth[c]);
    }
    double ea[3], eb[3];
    for (int c = 3; c < NCOL; ++c) {
        ea[c - 3] = std::fabs(wrap_angle((double)p[c] - truth[c]));
    }
    eb[0] = std::fabs(wrap_angle((double)p[3] - truth[3] - M_PI));
    eb[1] = std::fabs(wrap_angle((double)p[4] - (M_PI - truth[4])));
    eb[2] = std::fabs(wrap_angle((double)p[5] - truth[5] - M_PI));
    const bool alt = g_equiv_angles && eb[0] + eb[1] + eb[2] < ea[0] + ea[1] + ea[2];
    for (int c = 3; c < NCOL; ++c) {
        acc[c] += alt ? eb[c - 3] : ea[c - 3];
    }
}

/* The layout's pipeline configuration on the paper's rig, with rigpose-sim's estimator settings:
 * sigma 0.5 px; single-camera features start at the shell's mid radius 0.8335 m +- 0.15 m;
 * with `plain`, every update is the plain gated one (1-point RANSAC off); with `est_offsets`
 * the filters estimate each camera's clock offset but the first (from 0).
 * main() prints what this changes from the core's defaults (e2e_why). */
rp_status_t make_cfg(rp_pipe_layout_t layout, double sigma_px, bool plain, bool est_offsets,
                     rp_pipe_cfg_t *cfg)
{
    const rp_status_t st = rp_pipe_default_cfg(layout, cfg);
    if (st != RP_OK) {
        return st;
    }
    if (plain) { /* --no-one-point: the filters' plain gated update */
        cfg->stereo.one_point = 0;
        cfg->gc.one_point = 0;
        cfg->mono.one_point = 0;
    }
    if (est_offsets) { /* --estimate-offsets */
        cfg->stereo.ekf.toff_estimate = 1;
        cfg->gc.ekf.toff_estimate = 1;
        cfg->mono.ekf.toff_estimate = 1;
    }
    const rp_real sigma = (rp_real)sigma_px;
    cfg->stereo.ekf.sigma_px = sigma;
    cfg->gc.ekf.sigma_px = sigma;
    cfg->gc.init_depth_m = (rp_real)0.8335;
    cfg->gc.init_depth_sigma_m = (rp_real)0.15;
    cfg->gc.init_on_sphere = 1;
    cfg->mono.ekf.sigma_px = sigma;
    cfg->mono.init_depth_m = (rp_real)0.8335;
    cfg->mono.init_depth_sigma_m = (rp_real)0.15;
    return RP_OK;
}

const char *const e2e_why[][2] = {
    {"stereo.ekf.sigma_px", "--sigma-px"},
    {"gc.ekf.sigma_px", "--sigma-px"},
    {"mono.ekf.sigma_px", "--sigma-px"},
    {"stereo.one_point", "--no-one-point"},
    {"gc.one_point", "--no-one-point"},
    {"mono.one_point", "--no-one-point"},
    {"stereo.ekf.toff_estimate", "--estimate-offsets"},
    {"gc.ekf.toff_estimate", "--estimate-offsets"},
    {"mono.ekf.toff_estimate", "--estimate-offsets"},
    {"gc.init_on_sphere", "the rendered shell surrounds the rig: depth along the ray"},
    {"gc.init_depth", "rigpose-sim's setting: the shell's mid radius 0.8335 m +- 0.15 m"},
    {"mono.init_depth", "rigpose-sim's setting: the shell's mid depth 0.8335 m +- 0.15 m"},
    {nullptr, nullptr}};

/* The feature-level reference: the estimator of cfg on rp_sim_frame's features of the same run.
 * Only the estimator is used (the pipeline's trackers are not). */
struct SimRef {
    rp_vo_stereo_t stereo;
    rp_vo_gc_t gc;
    rp_frameset_t fs;
};

/* The estimator of cfg on the frame sets next(j, fs) makes, frames 1.. scored against truth(j)
 * into err and lost. Only the estimator is used (the pipeline's trackers are not). */
template <class Next, class Truth>
bool run_reference(SimRef *s, const rp_pipe_cfg_t &cfg, const rp_rig_t &rig, uint32_t frames,
                   Next next, Truth truth, double err[NCOL], unsigned long *lost)
{
    const bool stereo = cfg.layout == RP_PIPE_STEREO4 || cfg.layout == RP_PIPE_STEREO2;
    rp_status_t st = stereo ? rp_vo_stereo_init(&s->stereo, &rig, &cfg.stereo)
                            : rp_vo_gc_init(&s->gc, &rig, &cfg.gc);
    for (uint32_t j = 0; st == RP_OK && j < frames; ++j) {
        next(j, &s->fs);
        rp_estimate_t est;
        const rp_status_t sj = stereo ? rp_vo_stereo_step(&s->stereo, &s->fs, &est)
                                      : rp_vo_gc_step(&s->gc, &s->fs, &est);
        if (j > 0) {
            *lost += sj != RP_OK;
            add_err(est.p, truth(j), err);
        }
    }
    return st == RP_OK;
}

bool sim_reference(SimRef *s, const rp_pipe_cfg_t &cfg, const rp_rig_t &rig, uint64_t seed,
                   uint32_t run, uint32_t frames, const rpr::SeqCfg &rc, Method *m)
{
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.motion = (rp_sim_motion_t)rc.motion; /* the rendered run's motion and clocks */
    for (int k = 0; k < RP_SIM_NCAMS; ++k) {
        sc.cam_offset_s[k] = rc.cam_offset_s[k];
    }
    sc.jitter_s = rc.jitter_s;
    sc.width = rig.cam[0].cam.width;
    sc.height = rig.cam[0].cam.height;
    sc.focal_px = (double)rig.cam[0].cam.fx;
    sc.n_frames = frames;
    rp_sim_run_t sr;
    if (rp_sim_run_init(&sr, &sc, seed, run) != 0) {
        return false;
    }
    const bool ok = run_reference(
        s, cfg, sr.rig, frames, [&](uint32_t j, rp_frameset_t *fs) { rp_sim_frame(&sr, j, fs); },
        [&](uint32_t j) { return &sr.truth[6u * j]; }, m->err_sim, &m->lost_sim);
    rp_sim_run_free(&sr);
    return ok;
}

/* The same feature model with 10,000 points on the rendered surface of seq (0.5 px noise). */
bool surface_reference(SimRef *s, const rp_pipe_cfg_t &cfg, const rpr::Sequence &seq,
                       Method *m)
{
    const rpr::SeqCfg &c = seq.cfg();
    const std::vector<double> pts =
        rpr::surface_points(seq.scene(), 10000, rpr::key(c.seed, c.run, 0x5EF));
    return run_reference(
        s, cfg, seq.rig(), c.frames,
        [&](uint32_t j, rp_frameset_t *fs) {
            rpr::surface_features(seq, pts, seq.rig().n_cams, j, 0.5,
                                  rpr::key(c.seed, c.run, 0x5EF, 1), fs);
        },
        [&](uint32_t j) { return seq.truth(j); }, m->err_surf, &m->lost_surf);
}

void usage(FILE *out)
{
    std::fprintf(out,
                 "usage: rigpose-e2e [options]\n"
                 "Renders the paper's rig and motion, runs the image pipeline, scores the poses\n"
                 "as rigpose-sim does (mean absolute error over frames 1..N-1 of every run).\n"
                 "  --methods LIST   pipeline layouts (default stereo4,gc): stereo4 stereo2 gc\n"
                 "  --runs N         runs (default 5); run r renders rigpose-sim's run r\n"
                 "  --first-run R    first run index (default 0)\n"
                 "  --sigma-px S     the estimators' pixel sigma (default 0.5)\n"
                 "  --no-one-point   every update the filters' plain gated one (1-point\n"
                 "                   RANSAC off)\n"
                 "  --estimate-offsets  the filters estimate each camera's clock offset but\n"
                 "                   the first, from 0 (estimator.estimate_time_offsets; with\n"
                 "                   --cam-offsets-ms)\n"
                 "  --no-sim-ref     skip the feature-level reference rows (rp_sim's points and\n"
                 "                   the same model on the rendered surface)\n"
                 "  --check M=TX,..  exit 1 if method M's mean tx error exceeds TX metres\n"
                 "  --json-out FILE  write {\"render_<method>_<col>_m|rad\": ...} to FILE\n"
                 "                   (render_[points_][moving_][plain_][estoff_]... with\n"
                 "                   --points, --moving-object, --no-one-point,\n"
                 "                   --estimate-offsets)\n"
                 "  --quiet          no per-run lines\n"
                 "  --verbose        one line per frame set and method (status, features and those\n"
                 "                   used per camera, landmarks, gated, the six errors; with\n"
                 "                   --moving-object also the features on the object per camera)\n"
                 "  --track-truth    tracked features against the true projection of the scene\n"
                 "                   point each was born on: mean px, share over 1 and 3 px, by age\n"
                 "  --check-track PX exit 1 if a method's tracks are off by more than PX px mean one\n"
                 "                   frame after birth (implies --track-truth)\n");
    rpr::cli_usage(out);
}

bool parse_methods(const char *list, std::vector<Method> *ms)
{
    ms->clear();
    std::string s(list);
    size_t p = 0;
    while (p <= s.size()) {
        const size_t c = s.find(',', p);
        const std::string tok = s.substr(p, c == std::string::npos ? std::string::npos : c - p);
        Method m;
        if (rp_pipe_layout_from_name(tok.c_str(), &m.layout) != RP_OK ||
            !(m.layout == RP_PIPE_STEREO4 || m.layout == RP_PIPE_STEREO2 ||
              m.layout == RP_PIPE_GC)) {
            std::fprintf(stderr, "rigpose-e2e: method '%s' not supported (stereo4 stereo2 gc)\n",
                         tok.c_str());
            return false;
        }
        m.name = tok;
        ms->push_back(m);
        if (c == std::string::npos) {
            break;
        }
        p = c + 1;
    }
    return !ms->empty();
}

bool parse_checks(const char *list, std::vector<Method> *ms)
{
    std::string s(list);
    size_t p = 0;
    while (p < s.size()) {
        size_t c = s.find(',', p);
        if (c == std::string::npos) {
            c = s.size();
        }
        const std::string tok = s.substr(p, c - p);
        const size_t eq = tok.find('=');
        bool found = false;
        if (eq != std::string::npos) {
            char *end = nullptr;
            const double v = std::strtod(tok.c_str() + eq + 1, &end);
            for (Method &m : *ms) {
                if (m.name == tok.substr(0, eq) && end && !*end && v > 0.0) {
                    m.check_tx = v;
                    found = true;
                }
            }
        }
        if (!found) {
            std::fprintf(stderr, "rigpose-e2e: bad --check item '%s' (method=metres, method "
                                 "among --methods)\n", tok.c_str());
            return false;
        }
        p = c + 1;
    }
    return true;
}

} /* namespace */

int main(int argc, char **argv)
{
    rpr::SeqCfg sc;
    std::vector<Method> methods;
    parse_methods("stereo4,gc", &methods);
    const char *checks = nullptr;
    std::string json_out;
    uint32_t runs = 5, first_run = 0;
    double sigma_px = 0.5;
    bool sim_ref = true, quiet = false, verbose = false, ttruth = false, plain = false;
    bool est_offsets = false;
    double check_track_px = -1.0; /* --check-track bound, px (< 0: none) */
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : nullptr;
        if (!std::strcmp(a, "--help") || !std::strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!std::strcmp(a, "--no-one-point")) {
            plain = true;
        } else if (!std::strcmp(a, "--estimate-offsets")) {
            est_offsets = true;
        } else if (!std::strcmp(a, "--no-sim-ref")) {
            sim_ref = false;
        } else if (!std::strcmp(a, "--verbose")) {
            verbose = true;
        } else if (!std::strcmp(a, "--track-truth")) {
            ttruth = true;
        } else if (!std::strcmp(a, "--check-track") && v) {
            char *end = nullptr;
            check_track_px = std::strtod(v, &end);
            if (*end || !(check_track_px > 0.0 && check_track_px < 1e3)) {
                std::fprintf(stderr, "rigpose-e2e: bad value for --check-track: '%s'\n", v);
                return 2;
            }
            ttruth = true;
            ++i;
        } else if (!std::strcmp(a, "--quiet")) {
            quiet = true;
        } else if (!std::strcmp(a, "--methods") && v) {
            if (!parse_methods(v, &methods)) {
                return 2;
            }
            ++i;
        } else if (!std::strcmp(a, "--check") && v) {
            checks = v;
            ++i;
        } else if (!std::strcmp(a, "--json-out") && v) {
            json_out = v;
            ++i;
        } else if ((!std::strcmp(a, "--runs") || !std::strcmp(a, "--first-run")) && v) {
            char *end = nullptr;
            const long x = std::strtol(v, &end, 10);
            if (*end || x < (a[2] == 'r' ? 1 : 0) || x > 100000) {
                std::fprintf(stderr, "rigpose-e2e: bad value for %s: '%s'\n", a, v);
                return 2;
            }
            (a[2] == 'r' ? runs : first_run) = (uint32_t)x;
            ++i;
        } else if (!std::strcmp(a, "--sigma-px") && v) {
            char *end = nullptr;
            sigma_px = std::strtod(v, &end);
            if (*end || !(sigma_px > 0.0 && sigma_px <= 100.0)) {
                std::fprintf(stderr, "rigpose-e2e: bad value for --sigma-px: '%s'\n", v);
                return 2;
            }
            ++i;
        } else {
            const int used = rpr::cli_parse(argc, argv, i, &sc);
            if (used <= 0) {
                if (used == 0) {
                    std::fprintf(stderr, "rigpose-e2e: unknown option '%s'\n", a);
                }
                usage(stderr);
                return 2;
            }
            i += used - 1;
        }
    }
    if (checks && !parse_checks(checks, &methods)) {
        return 2;
    }
    g_equiv_angles = sc.motion != 0;
    if (sc.frames < 2) {
        std::fprintf(stderr, "rigpose-e2e: --frames must be >= 2 (frame 0 is not scored)\n");
        return 2;
    }

    std::vector<rp_pipe_t *> pipes;
    for (size_t m = 0; m < methods.size(); ++m) {
        pipes.push_back(static_cast<rp_pipe_t *>(std::calloc(1, sizeof(rp_pipe_t))));
    }
    SimRef *ref = static_cast<SimRef *>(std::calloc(1, sizeof(SimRef)));
    for (rp_pipe_t *p : pipes) {
        if (!p || !ref) {
            std::fprintf(stderr, "rigpose-e2e: out of memory\n");
            return 1;
        }
    }

    double render_s = 0.0;
    for (uint32_t r = first_run; r < first_run + runs; ++r) {
        rpr::SeqCfg rc = sc;
        rc.run = r;
        rpr::Sequence seq(rc);
        if (!seq.ok()) {
            std::fprintf(stderr, "rigpose-e2e: %s\n", seq.why().c_str());
            return 2;
        }
        std::vector<rp_pipe_cfg_t> cfgs(methods.size());
        for (size_t m = 0; m < methods.size(); ++m) {
            rp_status_t st = make_cfg(methods[m].layout, sigma_px, plain, est_offsets, &cfgs[m]);
            if (st == RP_OK && r == first_run) {
                (void)rp_cfg_diff_print(stderr, "rigpose-e2e", &cfgs[m], e2e_why);
            }
            if (st == RP_OK) {
                st = rp_pipe_init(pipes[m], &seq.rig(), &cfgs[m]);
            }
            if (st != RP_OK) {
                std::fprintf(stderr, "rigpose-e2e: %s: pipeline init failed: %s\n",
                             methods[m].name.c_str(), rp_status_str(st));
                return 1;
            }
        }
        std::vector<double> run_err(methods.size(), 0.0);
        for (Method &mm : methods) {
            for (auto &b : mm.born) {
                b.clear();
            }
        }
        std::vector<cv::Mat> img(seq.rig().n_cams);
        for (uint32_t j = 0; j < rc.frames; ++j) {
            const auto t0 = std::chrono::steady_clock::now();
            rp_image_t views[RP_MAX_CAMS];
            const rp_image_t *ptrs[RP_MAX_CAMS];
            for (int k = 0; k < seq.rig().n_cams; ++k) {
                seq.render(j, k, &img[k]);
                views[k] = rpr::image_view(img[k]);
                ptrs[k] = &views[k];
            }
            render_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            for (size_t m = 0; m < methods.size(); ++m) {
                rp_estimate_t est;
                const auto t1 = std::chrono::steady_clock::now();
                const rp_status_t st =
                    rp_pipe_step(pipes[m], ptrs, seq.rig().n_cams, seq.utime(j), &est);
                methods[m].us_per_frame_sum +=
                    std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t1)
                        .count();
                const rp_frameset_t *fs = nullptr;
                if (rp_pipe_frameset(pipes[m], &fs) == RP_OK) {
                    for (int k = 0; k < RP_MAX_CAMS; ++k) {
                        methods[m].feats += fs->n[k];
                    }
                    if (ttruth) {
                        track_truth(seq, j, *fs, &methods[m]);
                    }
                }
                if (verbose) {
                    const rp_pipe_info_t *inf = nullptr;
                    rp_pipe_info(pipes[m], &inf);
                    unsigned on_obj[RP_MAX_CAMS] = {0}; /* features whose ray meets the object */
                    for (int k = 0; fs && sc.moving_object && k < seq.rig().n_cams; ++k) {
                        rpr::ObjView ov;
                        for (unsigned f = 0; seq.object_view(j, k, &ov) && f < fs->n[k]; ++f) {
                            const rp_real uv[2] = {fs->f[k][f].uv[0], fs->f[k][f].uv[1]};
                            rp_real xn[2];
                            double t;
                            if (rp_cam_unproject(&seq.rig().cam[k].cam, uv, xn) == RP_OK) {
                                const double nn = std::sqrt(1.0 + (double)xn[0] * xn[0] +
                                                            (double)xn[1] * xn[1]);
                                const float ry[3] = {(float)(xn[0] / nn), (float)(xn[1] / nn),
                                                    (float)(1.0 / nn)};
                                on_obj[k] += ov.hit_t(ry, &t) ? 1u : 0u;
                            }
                        }
                    }
                    if (sc.moving_object) { /* features on the object, per camera */
                        std::printf("  run %u frame %u on object %u %u %u %u\n", r, j,
                                    on_obj[0], on_obj[1], on_obj[2], on_obj[3]);
                    }
                    std::printf("  run %u frame %u %-8s st %-12s flags 0x%02x feats %u %u %u %u %u %u "
                                "used %u %u %u %u %u %u lm %u gated %u "
                                "err tx %+.5f ty %+.5f tz %+.5f alpha %+.5f beta %+.5f gamma %+.5f\n",
                                r, j, methods[m].name.c_str(), rp_status_str(st),
                                (unsigned)est.flags, fs ? fs->n[0] : 0, fs ? fs->n[1] : 0,
                                fs ? fs->n[2] : 0, fs ? fs->n[3] : 0, fs ? fs->n[4] : 0,
                                fs ? fs->n[5] : 0, est.n_used[0], est.n_used[1], est.n_used[2],
                                est.n_used[3], est.n_used[4], est.n_used[5],
                                (unsigned)est.n_landmarks, (unsigned)est.n_gated,
                                (double)est.p[0] - seq.truth(j)[0],
                                (double)est.p[1] - seq.truth(j)[1],
                                (double)est.p[2] - seq.truth(j)[2],
                                (double)est.p[3] - seq.truth(j)[3],
                                (double)est.p[4] - seq.truth(j)[4],
                                (double)est.p[5] - seq.truth(j)[5]);
                    for (int q = 0; inf && q < RP_MAX_PAIRS; ++q) {
                        const rp_smatch_stats_t &ms = inf->match[q];
                        if (ms.n_in) {
                            std::printf("    pair %d: in %u matched %u outside %u flat %u low %u "
                                        "ambiguous %u lr %u epipolar %u\n",
                                        q, ms.n_in, ms.n_matched, ms.n_outside, ms.n_flat,
                                        ms.n_low_score, ms.n_ambiguous, ms.n_lr_fail,
                                        ms.n_epi_fail);
                        }
                    }
                }
                if (j == 0) {
                    continue;
                }
                methods[m].frames++;
                methods[m].lost += st != RP_OK;
                double before = methods[m].err[0];
                add_err(est.p, seq.truth(j), methods[m].err);
                run_err[m] += methods[m].err[0] - before;
            }
        }
        for (size_t m = 0; m < methods.size(); ++m) {
            const double tx = run_err[m] / (rc.frames - 1);
            methods[m].worst_run_tx = std::max(methods[m].worst_run_tx, tx);
            double sim_tx = -1.0;
            if (sim_ref) {
                const double before = methods[m].err_sim[0];
                if (!sim_reference(ref, cfgs[m], seq.rig(), rc.seed, r, rc.frames, rc,
                                   &methods[m])) {
                    std::fprintf(stderr, "rigpose-e2e: feature-level reference failed\n");
                    return 1;
                }
                sim_tx = (methods[m].err_sim[0] - before) / (rc.frames - 1);
                if (!seq.points() && !surface_reference(ref, cfgs[m], seq, &methods[m])) {
                    std::fprintf(stderr, "rigpose-e2e: surface reference failed\n");
                    return 1;
                }
            }
            if (!quiet) {
                std::printf("  run %u %-8s pixels tx %.6f m", r, methods[m].name.c_str(), tx);
                if (sim_ref) {
                    std::printf("   features tx %.6f m", sim_tx);
                }
                std::printf("\n");
                std::fflush(stdout);
            }
        }
    }

    const double fx = sc.focal_px > 0.0 ? sc.focal_px : 800.0 * sc.width / 640.0;
    std::printf("\nrigpose-e2e: from rendered pixels, %u run%s x %u frames (runs %u..%u of seed "
                "%llu), scene %s\n  6 cameras %dx%d, fx = fy = %.1f px, principal point at the centre; "
                "image noise %.2g grey levels, blur %.2g px, brightness %.2g, %dx%d samples/px\n"
                "  mean absolute error per frame over frames 1..%u (frame 0 defines the world); "
                "m and rad\n\n  %-26s",
                runs, runs == 1 ? "" : "s", sc.frames, first_run, first_run + runs - 1,
                (unsigned long long)sc.seed,
                sc.points ? "points (rp_sim's points as discs)" : (sc.flat ? "sphere" : "shell"),
                sc.width, sc.height, fx, sc.noise_grey,
                sc.blur_sigma, sc.brightness, sc.ss, sc.ss, sc.frames - 1, "");
    for (const char *cn : col_name) {
        std::printf("%10s", cn);
    }
    std::printf("%8s%10s%10s\n", "lost", "feats/fs", "us/fs");
    bool checks_ok = true;
    FILE *js = json_out.empty() ? nullptr : std::fopen(json_out.c_str(), "w");
    /* JSON key prefix: render_[points_][moving_][plain_][estoff_] */
    const std::string jps = std::string("render_") + (sc.points ? "points_" : "") +
                            (sc.moving_object ? "moving_" : "") + (plain ? "plain_" : "") +
                            (est_offsets ? "estoff_" : "");
    const char *jp = jps.c_str();
    if (!json_out.empty() && !js) {
        std::fprintf(stderr, "rigpose-e2e: cannot write %s\n", json_out.c_str());
        return 1;
    }
    if (js) {
        std::fprintf(js, "{\"%sruns\": %u, \"%sframes\": %u", jp, runs, jp, sc.frames);
    }
    for (Method &m : methods) {
        const double n = (double)m.frames;
        std::printf("  %-26s", (m.name + " (pixels)").c_str());
        for (int c = 0; c < NCOL; ++c) {
            std::printf("%10.6f", m.err[c] / n);
        }
        const double fs_total = (double)runs * sc.frames;
        std::printf("%8lu%10.0f%10.0f\n", m.lost, m.feats / fs_total, m.us_per_frame_sum / fs_total);
        if (sim_ref) {
            std::printf("  %-26s", (m.name + " (features, sim)").c_str());
            for (int c = 0; c < NCOL; ++c) {
                std::printf("%10.6f", m.err_sim[c] / n);
            }
            std::printf("%8lu\n  %-26s", m.lost_sim, "pixels / features");
            for (int c = 0; c < NCOL; ++c) {
                std::printf("%10.2f", m.err[c] / m.err_sim[c]);
            }
            if (!sc.points) { /* the points scene's surface row would be the sim row */
                std::printf("\n  %-26s", (m.name + " (surface feats)").c_str());
                for (int c = 0; c < NCOL; ++c) {
                    std::printf("%10.6f", m.err_surf[c] / n);
                }
                std::printf("%8lu\n  %-26s", m.lost_surf, "pixels / surface feats");
                for (int c = 0; c < NCOL; ++c) {
                    std::printf("%10.2f", m.err[c] / m.err_surf[c]);
                }
            }
            std::printf("\n");
        }
        std::printf("  %-26s%10.6f\n", "worst run (pixels), tx", m.worst_run_tx);
        if (ttruth && m.tt_n > 0) {
            std::printf("  %-26s%10.3f px mean, %.1f %% over 1 px, %.1f %% over 3 px (%lu "
                        "positions; %lu features born, %lu seeing nothing)\n",
                        "tracks vs truth", m.tt_sum / m.tt_n, 100.0 * m.tt_1px / m.tt_n,
                        100.0 * m.tt_3px / m.tt_n, m.tt_n, m.tt_born, m.tt_unpicked);
            static const char *const age_name[4] = {"1", "2-5", "6-20", "> 20"};
            for (int b = 0; b < 4; ++b) {
                if (m.tt_age_n[b]) {
                    std::printf("    %-24s%10.3f px mean, %.1f %% over 3 px (%lu)\n",
                                (std::string("frames since birth ") + age_name[b]).c_str(),
                                m.tt_age_sum[b] / m.tt_age_n[b],
                                100.0 * m.tt_age_3px[b] / m.tt_age_n[b], m.tt_age_n[b]);
                }
            }
        }
        if (check_track_px > 0.0) {
            /* tracking against the scene one frame after birth (--track-truth) */
            const double e1 = m.tt_age_n[0] ? m.tt_age_sum[0] / m.tt_age_n[0] : 1e300;
            const bool ok = e1 <= check_track_px;
            std::printf("  check %s: tracks 1 frame after birth %.3f px <= %.3f px: %s\n",
                        m.name.c_str(), e1, check_track_px, ok ? "ok" : "FAILED");
            checks_ok = checks_ok && ok;
        }
        if (m.check_tx > 0.0) {
            const bool ok = m.err[0] / n <= m.check_tx && std::isfinite(m.err[0]);
            std::printf("  check %s: mean tx %.6f m <= %.6f m: %s\n", m.name.c_str(), m.err[0] / n,
                        m.check_tx, ok ? "ok" : "FAILED");
            checks_ok = checks_ok && ok;
        }
        if (js) {
            for (int c = 0; c < NCOL; ++c) {
                std::fprintf(js, ", \"%s%s_%s_%s\": %.6g", jp, m.name.c_str(), col_name[c],
                             c < 3 ? "m" : "rad", m.err[c] / n);
            }
            if (sim_ref) {
                std::fprintf(js, ", \"%s%s_vs_sim_tx_ratio\": %.4g", jp, m.name.c_str(),
                             m.err[0] / m.err_sim[0]);
                if (!sc.points) {
                    std::fprintf(js, ", \"%s%s_vs_surface_tx_ratio\": %.4g", jp,
                                 m.name.c_str(), m.err[0] / m.err_surf[0]);
                }
            }
            std::fprintf(js, ", \"%s%s_lost_frames\": %lu", jp, m.name.c_str(), m.lost);
        }
    }
    std::printf("\n  rendering: %.1f s per frame set (6 cameras)\n",
                render_s / ((double)runs * sc.frames));
    if (js) {
        std::fprintf(js, "}\n");
        std::fclose(js);
    }
    for (rp_pipe_t *p : pipes) {
        std::free(p);
    }
    std::free(ref);
    return checks_ok ? 0 : 1;
}
