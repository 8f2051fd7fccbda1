/*
 * rigpose-gcdiag - where gc's error from rendered pixels comes from (issue 4; README "End to
 * end from rendered pixels").
 *
 * Default mode: renders runs of the paper's protocol (rp_render.hpp; 640x480, one sample per
 * pixel by default), runs the image pipeline's gc layout (rp_pipe.h) on cameras 0..3 and,
 * beside it, two more gc estimators fed variants of the same frame sets:
 *   pixels     the pipeline's own estimate (trackers -> gc), as rigpose-e2e runs it
 *   truth      the tracker's ids and lifetimes, each feature's pixel replaced by the exact
 *              projection of the surface point seen at its birth pixel (the renderer's truth)
 *   truth+iid  the same plus independent Gaussian noise of --iid-px (default 0.5) px per
 *              feature and frame: the simulation's noise model on the tracker's features
 * It prints the three rows (mean absolute error over frames 1..N-1, as rigpose-sim), the
 * features, landmarks and mature landmarks per frame set, the mean track life, and the
 * tracker's error against the truth by age (frames since birth): mean |e|, rms |e| and the
 * mean over cameras and frames of |mean error vector of the camera's features of that age|
 * (a drift common to a camera's features shows there).
 *
 * --surface-sim MIX: no images; the simulation's feature model (10,000 points, each seen while
 * it projects inside the image, 0.5 px independent noise, rigpose-sim's gc settings) with the
 * points on the rendered surface (uniform directions from the origin); a fraction MIX of them
 * keeps its direction but takes a radius uniform in the shell's volume (0.667..1 m), as
 * rp_sim's points. Per run also the single scale factor that best maps the estimated
 * translations onto the true ones, and the tx error left after it.
 * --sim KEEP: rp_sim_frame's own features (rigpose-sim's gc), keeping a fixed pseudo-random
 * fraction KEEP of the points; --init-depth / --init-sigma change gc's assumed depth.
 * --epi (with --sim): every 10 frames, the scale that the generalised epipolar constraint of
 * every feature between its first view and now gives (s (d_b - d_a) + R_b D_k - R_a D_k) .
 * (w_a x w_b) = 0, with gc's rotations, the true rotations, the true poses; and the true scale
 * of gc's translation.
 *
 * usage: rigpose-gcdiag [--runs N] [--first-run R] [--iid-px S] [--cache DIR] [--verbose]
 *                       [--target N] [--topup-below N] [--min-tracked N]
 *                       [--init-depth M] [--init-sigma M] [--mature-frac F] [--min-mature N]
 *                       [--mscale-sigma S]  (gc's metric scale step, rp_vo_gc.h step 6; 0: off)
 *                       [--ba-var-scale F]  (the factor on a window's mu variance before it is
 *                       fused; 1e12: mu stays at its start, the windows still correct the map)
 *                       [--surface-sim MIX [--thick T]] [--sim KEEP [--epi]] [render options]
 * --cache DIR keeps the rendered images as PNG files in DIR (read back when present).
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../../common/rp_cfg_diff.h"
#include "rigpose/rp_pipe.h"
#include "rp_render.hpp"
#include "rp_render_cli.hpp"
#include "rp_sim.h"

namespace {

double g_thick = 0.0;      /* --thick: surface points' radii scaled by 1 +- thick (uniform) */
double g_init_depth = 0.0;
double g_init_sigma = 0.0; /* --init-sigma: gc's depth prior sigma (0: 0.15 m) */
double g_mature = -1.0;    /* --mature-frac (< 0: default) */
int g_min_mature = -1;     /* --min-mature (< 0: default) */
double g_mscale = -1.0;    /* --mscale-sigma: gc's metric scale step prior (0: off; < 0: default) */
double g_ba_var = -1.0;    /* --ba-var-scale: a window's mu variance factor (< 0: default) */
bool g_epi = false;        /* --epi: print the generalised epipolar scale check in --sim */

void apply_gc_opts(rp_vo_gc_cfg_t *c)
{
    if (g_init_depth > 0.0) {
        c->init_depth_m = (rp_real)g_init_depth;
    }
    if (g_init_sigma > 0.0) {
        c->init_depth_sigma_m = (rp_real)g_init_sigma;
    }
    if (g_mature >= 0.0) {
        c->mature_frac = (rp_real)g_mature;
    }
    if (g_min_mature >= 0) {
        c->min_mature = (uint16_t)g_min_mature;
    }
    if (g_mscale >= 0.0) {
        c->mscale_sigma = (rp_real)g_mscale;
    }
    if (g_ba_var > 0.0) {
        c->ba_var_scale = (rp_real)g_ba_var;
    }
} /* --init-depth: gc's assumed depth in --sim (0: the shell's mid) */

const int NCOL = 6;
const char *const col_name[NCOL] = {"tx", "ty", "tz", "alpha", "beta", "gamma"};
const int NAGE = 7; /* age buckets: 0, 1, 2-3, 4-7, 8-15, 16-31, 32+ */
const char *const age_name[NAGE] = {"0", "1", "2-3", "4-7", "8-15", "16-31", "32+"};

int age_bucket(uint32_t age)
{
    int b = 0;
    while (b < NAGE - 1 && age >= (1u << b)) {
        ++b;
    }
    return age == 0 ? 0 : b;
}

double wrap_angle(double x)
{
    x = std::fmod(x + M_PI, 2.0 * M_PI);
    if (x < 0.0) {
        x += 2.0 * M_PI;
    }
    return x - M_PI;
}

struct Score {
    double err[NCOL] = {0, 0, 0, 0, 0, 0};
    unsigned long frames = 0, lost = 0;
    void add(const rp_real p[6], const double *truth, rp_status_t st)
    {
        for (int c = 0; c < NCOL; ++c) {
            const double e = (double)p[c] - truth[c];
            err[c] += std::fabs(c < 3 ? e : wrap_angle(e));
        }
        frames++;
        lost += st != RP_OK;
    }
    void print(const char *name) const
    {
        std::printf("  %-22s", name);
        for (int c = 0; c < NCOL; ++c) {
            std::printf("%10.6f", err[c] / (double)frames);
        }
        std::printf("%8lu\n", lost);
    }
};

/* A feature's truth: the world point seen at its birth pixel. */
struct Birth {
    bool ok;
    double M[3];
    uint32_t frame;
    uint32_t last; /* last frame it was seen */
};

/* The surface point seen through pixel uv of camera k at the true pose of frame j. */
bool surface_point_at(const rpr::Sequence &seq, const rp_pose_lin_t &pl, int k,
                      const rp_real uv[2], double M[3])
{
    rp_real xn[2], zero[3] = {0, 0, 0}, C[3], Q[3];
    if (rp_cam_unproject(&seq.rig().cam[k].cam, uv, xn) != RP_OK) {
        return false;
    }
    const rp_real P[3] = {xn[0], xn[1], 1};
    if (rp_rig_world_point(&seq.rig(), (uint8_t)k, &pl, zero, C) != RP_OK ||
        rp_rig_world_point(&seq.rig(), (uint8_t)k, &pl, P, Q) != RP_OK) {
        return false;
    }
    double c[3], d[3], n = 0.0, t, u[3];
    for (int a = 0; a < 3; ++a) {
        c[a] = (double)C[a];
        d[a] = (double)(Q[a] - C[a]);
        n += d[a] * d[a];
    }
    n = std::sqrt(n);
    for (double &x : d) {
        x /= n;
    }
    if (!seq.scene().intersect(c, d, &t, u)) {
        return false;
    }
    for (int a = 0; a < 3; ++a) {
        M[a] = c[a] + t * d[a];
    }
    return true;
}

/* Image of camera k at frame j, from the cache folder when it holds it (rendered and stored
 * otherwise; no cache when dir is empty). */
void render_cached(const rpr::Sequence &seq, const std::string &dir, uint32_t j, int k,
                   cv::Mat *out)
{
    if (dir.empty()) {
        seq.render(j, k, out);
        return;
    }
    const rpr::SeqCfg &c = seq.cfg();
    char name[512];
    std::snprintf(name, sizeof name, "%s/s%llu_r%u_%dx%d_ss%d_n%g_f%u_c%d.png", dir.c_str(),
                  (unsigned long long)c.seed, c.run, c.width, c.height, c.ss, c.noise_grey, j, k);
    FILE *f = std::fopen(name, "rb");
    if (f) {
        std::fclose(f);
        *out = cv::imread(name, cv::IMREAD_GRAYSCALE);
    }
    if (!f || out->empty()) {
        seq.render(j, k, out);
        cv::imwrite(name, *out);
    }
}

/* The generalised epipolar scale of a frame: every feature seen at frame a (its first view) and
 * now, cameras at d + R D_k with the rays of their pixels; s minimises
 * sum ((s (d_b - d_a) + R_b D_k - R_a D_k) . (w_a x w_b))^2 over features at least min_age old.
 * Translations from pose_t (per frame, 6 values), rotations from pose_r. */
struct View {
    uint8_t cam;
    uint32_t frame;
    rp_real uv[2];
};

bool ray_at(const rp_rig_t &rig, uint8_t k, const double *t, const double *r, const rp_real uv[2],
            double w[3], double g[3])
{
    rp_real p[6], xn[2], zero[3] = {0, 0, 0}, c[3], q[3];
    for (int i = 0; i < 3; ++i) {
        p[i] = (rp_real)t[i];
        p[3 + i] = (rp_real)r[3 + i];
    }
    rp_pose_lin_t pl;
    if (rp_pose_lin_set(&pl, p) != RP_OK || rp_cam_unproject(&rig.cam[k].cam, uv, xn) != RP_OK) {
        return false;
    }
    const rp_real P[3] = {xn[0], xn[1], 1};
    rp_rig_world_point(&rig, k, &pl, zero, c);
    rp_rig_world_point(&rig, k, &pl, P, q);
    double n = 0.0;
    for (int i = 0; i < 3; ++i) {
        w[i] = (double)(q[i] - c[i]);
        g[i] = (double)(c[i] - p[i]);
        n += w[i] * w[i];
    }
    for (int i = 0; i < 3; ++i) {
        w[i] /= std::sqrt(n);
    }
    return true;
}

double epi_scale(const rp_rig_t &rig, const std::map<uint32_t, View> &first,
                 const rp_frameset_t &fs, uint32_t j, const std::vector<double> &pose_t,
                 const std::vector<double> &pose_r, uint32_t min_age)
{
    double saa = 0.0, sab = 0.0;
    for (int k = 0; k < 4; ++k) {
        for (uint16_t f = 0; f < fs.n[k]; ++f) {
            auto it = first.find(fs.f[k][f].id);
            if (it == first.end() || it->second.frame + min_age > j) {
                continue;
            }
            const uint32_t a = it->second.frame;
            double wa[3], ga[3], wb[3], gb[3];
            if (!ray_at(rig, (uint8_t)k, &pose_t[6 * a], &pose_r[6 * a], it->second.uv, wa, ga) ||
                !ray_at(rig, (uint8_t)k, &pose_t[6 * j], &pose_r[6 * j], fs.f[k][f].uv, wb, gb)) {
                continue;
            }
            const double n[3] = {wa[1] * wb[2] - wa[2] * wb[1], wa[2] * wb[0] - wa[0] * wb[2],
                                 wa[0] * wb[1] - wa[1] * wb[0]};
            double x = 0.0, y = 0.0;
            for (int i = 0; i < 3; ++i) {
                x += (pose_t[6 * j + i] - pose_t[6 * a + i]) * n[i];
                y += (gb[i] - ga[i]) * n[i];
            }
            saa += x * x;
            sab += x * y;
        }
    }
    return saa > 0.0 ? -sab / saa : 1.0;
}

/* Feature-level gc (rp_sim_frame's features) on the same runs, keeping only a fraction keep of
 * the point ids (a fixed pseudo-random subset), with cfg's min_tracked. */
/* The single factor s that best maps the estimated translations onto the true ones (least
 * squares over frames; n rows of `stride` values, translation first), and the mean tx error
 * it leaves (*tx_left). */
double best_scale(const double *est, const double *truth, size_t stride, size_t n, double *tx_left)
{
    double num = 0.0, den = 0.0, res = 0.0;
    for (size_t j = 0; j < n; ++j) {
        for (size_t q = 0; q < 3; ++q) {
            num += est[j * stride + q] * truth[j * stride + q];
            den += est[j * stride + q] * est[j * stride + q];
        }
    }
    const double s = den > 0.0 ? num / den : 1.0;
    for (size_t j = 0; j < n; ++j) {
        res += std::fabs(s * est[j * stride] - truth[j * stride]);
    }
    *tx_left = n > 0 ? res / (double)n : 0.0;
    return s;
}

void sim_mode(uint64_t seed, uint32_t first_run, uint32_t runs, uint32_t frames, double keep,
              int min_tracked)
{
    rp_sim_cfg_t sc;
    rp_sim_default_cfg(&sc);
    sc.n_frames = frames;
    rp_vo_gc_t *gc = static_cast<rp_vo_gc_t *>(std::calloc(1, sizeof(rp_vo_gc_t)));
    rp_frameset_t *fs = static_cast<rp_frameset_t *>(std::calloc(1, sizeof(rp_frameset_t)));
    Score sum;
    double feats = 0.0;
    for (uint32_t r = first_run; r < first_run + runs; ++r) {
        rp_sim_run_t sr;
        if (rp_sim_run_init(&sr, &sc, seed, r) != 0) {
            return;
        }
        rp_vo_gc_cfg_t c = rp_sim_gc_cfg(&sc);
        apply_gc_opts(&c);
        if (min_tracked > 0) {
            c.min_tracked = (uint16_t)min_tracked;
        }
        rp_vo_gc_init(gc, &sr.rig, &c);
        Score one;
        std::map<uint32_t, View> first;
        std::vector<double> pe(6u * frames), pt(sr.truth, sr.truth + 6u * frames);
        for (uint32_t j = 0; j < frames; ++j) {
            rp_sim_frame(&sr, j, fs);
            for (int k = 0; k < RP_MAX_CAMS; ++k) {
                uint16_t m = 0;
                for (uint16_t f = 0; f < fs->n[k]; ++f) {
                    if ((double)(rpr::key(fs->f[k][f].id, 99) % 1000u) < keep * 1000.0) {
                        fs->f[k][m++] = fs->f[k][f];
                    }
                }
                fs->n[k] = m;
                feats += k < 4 ? m : 0;
            }
            rp_estimate_t est;
            const rp_status_t st = rp_vo_gc_step(gc, fs, &est);
            for (int q = 0; q < 6; ++q) {
                pe[6 * j + q] = (double)est.p[q];
            }
            for (int k = 0; k < 4; ++k) {
                for (uint16_t f = 0; f < fs->n[k]; ++f) {
                    View vw = {(uint8_t)k, j, {fs->f[k][f].uv[0], fs->f[k][f].uv[1]}};
                    first.emplace(fs->f[k][f].id, vw);
                }
            }
            if (g_epi && j % 10 == 0 && j > 0) {
                std::printf("    frame %u epipolar scale: est R %.4f, true R %.4f, true R+t "
                            "%.4f\n", j, epi_scale(sr.rig, first, *fs, j, pe, pe, 10),
                            epi_scale(sr.rig, first, *fs, j, pe, pt, 10),
                            epi_scale(sr.rig, first, *fs, j, pt, pt, 10));
            }
            if (g_epi && j % 10 == 0) {
                double tn = 0.0, te2 = 0.0;
                for (int q = 0; q < 3; ++q) {
                    tn += sr.truth[6u * j + q] * (double)est.p[q];
                    te2 += (double)est.p[q] * (double)est.p[q];
                }
                std::printf("    frame %u true scale of the estimate (t_true . t / |t|^2) %.4f\n",
                            j, te2 > 0.0 ? tn / te2 : 1.0);
            }
            if (j > 0) {
                one.add(est.p, &sr.truth[6u * j], st);
                sum.add(est.p, &sr.truth[6u * j], st);
            }
        }
        double res = 0.0;
        const double sbest = best_scale(&pe[6], &pt[6], 6, frames - 1, &res);
        std::printf("run %u: features tx %.6f; best global scale %.4f leaves tx %.6f\n", r,
                    one.err[0] / (double)one.frames, sbest, res);
        rp_sim_run_free(&sr);
    }
    std::printf("  feature level, keep %.2f of the points, %.1f features per frame set\n", keep,
                feats / ((double)runs * frames));
    sum.print("features");
    std::free(gc);
    std::free(fs);
}

/* Feature-level gc with the simulation's feature model (10,000 points, each seen while it
 * projects inside the image, independent noise of noise_px) but the points on the rendered
 * surface (uniform directions from the origin) instead of inside the shell's volume; shell_mix
 * in 0..1: that fraction of the points keeps its surface direction but takes a radius uniform
 * in the volume 0.667..1 m. */
void surface_sim_mode(const rpr::SeqCfg &base, uint32_t first, uint32_t runs, double noise_px,
                      double shell_mix)
{
    rp_vo_gc_t *gc = static_cast<rp_vo_gc_t *>(std::calloc(1, sizeof(rp_vo_gc_t)));
    rp_frameset_t *fs = static_cast<rp_frameset_t *>(std::calloc(1, sizeof(rp_frameset_t)));
    Score sum;
    for (uint32_t r = first; r < first + runs; ++r) {
        rpr::SeqCfg rc = base;
        rc.run = r;
        rpr::Sequence seq(rc);
        std::mt19937_64 rng(rpr::key(rc.seed, r, 1234));
        std::uniform_real_distribution<double> uni(0.0, 1.0);
        std::vector<double> pts =
            rpr::surface_points(seq.scene(), 10000, rpr::key(rc.seed, r, 0x5EF));
        for (size_t i = 0; i < pts.size(); i += 3) {
            double *M = &pts[i];
            double f = g_thick > 0.0 ? 1.0 + g_thick * (2.0 * uni(rng) - 1.0) : 1.0;
            if (uni(rng) < shell_mix) {
                const double n = std::sqrt(M[0] * M[0] + M[1] * M[1] + M[2] * M[2]);
                const double r3 = 0.667 * 0.667 * 0.667;
                f = std::cbrt(r3 + uni(rng) * (1.0 - r3)) / n;
            }
            for (int a = 0; a < 3; ++a) {
                M[a] *= f;
            }
        }
        rp_sim_cfg_t sc;
        rp_sim_default_cfg(&sc);
        rp_vo_gc_cfg_t gcc = rp_sim_gc_cfg(&sc);
        apply_gc_opts(&gcc);
        rp_vo_gc_init(gc, &seq.rig(), &gcc);
        Score one;
        std::vector<double> te, tt;
        for (uint32_t j = 0; j < rc.frames; ++j) {
            rpr::surface_features(seq, pts, 4, j, noise_px, rpr::key(rc.seed, r, 0x5EF, 1), fs);
            rp_estimate_t est;
            const rp_status_t st = rp_vo_gc_step(gc, fs, &est);
            if (j > 0) {
                one.add(est.p, seq.truth(j), st);
                sum.add(est.p, seq.truth(j), st);
                for (int c = 0; c < 3; ++c) {
                    te.push_back((double)est.p[c]);
                    tt.push_back(seq.truth(j)[c]);
                }
            }
        }
        double res = 0.0;
        const double sbest = best_scale(te.data(), tt.data(), 3, te.size() / 3, &res);
        std::printf("run %u: surface features tx %.6f; best global scale %.4f leaves tx %.6f\n", r,
                    one.err[0] / (double)one.frames, sbest, res);
        std::fflush(stdout);
    }
    std::printf("  feature level on the rendered surface (shell mix %.2f)\n", shell_mix);
    sum.print("surface features");
    std::free(gc);
    std::free(fs);
}

void usage(FILE *out)
{
    std::fprintf(out,
                 "usage: rigpose-gcdiag [--runs N] [--first-run R] [--iid-px S] [--cache DIR]\n"
                 "         [--verbose] [--target N] [--topup-below N] [--min-tracked N]\n"
                 "         [--init-depth M] [--init-sigma M] [--mature-frac F] [--min-mature N]\n"
                 "         [--mscale-sigma S (gc's metric scale step; 0: off)] [--ba-var-scale F]\n"
                 "         [--surface-sim MIX [--thick T]] [--sim KEEP [--epi]] [render options]\n"
                 "gc from rendered pixels against gc fed the renderer's true projections with the\n"
                 "tracker's ids (default), or feature-level gc on the rendered surface\n"
                 "(--surface-sim) or on rp_sim's points (--sim); see the source's head.\n");
    rpr::cli_usage(out);
}

} /* namespace */

int main(int argc, char **argv)
{
    rpr::SeqCfg sc;
    sc.ss = 1;
    uint32_t runs = 1, first_run = 0;
    double iid_px = 0.5;
    bool verbose = false;
    std::string cache;
    int target = 0, topup = -1, min_tracked = 0;
    double sim_keep = -1.0, surf_mix = -1.0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : nullptr;
        if (!std::strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        } else if (!std::strcmp(a, "--verbose")) {
            verbose = true;
        } else if ((!std::strcmp(a, "--runs") || !std::strcmp(a, "--first-run")) && v) {
            const long x = std::strtol(v, nullptr, 10);
            if (x < 0 || x > 100000) {
                usage(stderr);
                return 2;
            }
            (a[2] == 'r' ? runs : first_run) = (uint32_t)x;
            ++i;
        } else if (!std::strcmp(a, "--target") && v) {
            target = std::atoi(v);
            ++i;
        } else if (!std::strcmp(a, "--surface-sim") && v) {
            surf_mix = std::strtod(v, nullptr);
            ++i;
        } else if (!std::strcmp(a, "--thick") && v) {
            g_thick = std::strtod(v, nullptr);
            ++i;
        } else if (!std::strcmp(a, "--init-sigma") && v) {
            g_init_sigma = std::strtod(v, nullptr);
            ++i;
        } else if (!std::strcmp(a, "--epi")) {
            g_epi = true;
        } else if (!std::strcmp(a, "--mature-frac") && v) {
            g_mature = std::strtod(v, nullptr);
            ++i;
        } else if (!std::strcmp(a, "--min-mature") && v) {
            g_min_mature = std::atoi(v);
            ++i;
        } else if (!std::strcmp(a, "--mscale-sigma") && v) {
            g_mscale = std::strtod(v, nullptr);
            ++i;
        } else if (!std::strcmp(a, "--ba-var-scale") && v) {
            g_ba_var = std::strtod(v, nullptr);
            ++i;
        } else if (!std::strcmp(a, "--init-depth") && v) {
            g_init_depth = std::strtod(v, nullptr);
            ++i;
        } else if (!std::strcmp(a, "--sim") && v) {
            sim_keep = std::strtod(v, nullptr);
            ++i;
        } else if (!std::strcmp(a, "--min-tracked") && v) {
            min_tracked = std::atoi(v);
            ++i;
        } else if (!std::strcmp(a, "--topup-below") && v) {
            topup = std::atoi(v);
            ++i;
        } else if (!std::strcmp(a, "--cache") && v) {
            cache = v;
            ++i;
        } else if (!std::strcmp(a, "--iid-px") && v) {
            iid_px = std::strtod(v, nullptr);
            ++i;
        } else {
            const int used = rpr::cli_parse(argc, argv, i, &sc);
            if (used <= 0) {
                usage(stderr);
                return 2;
            }
            i += used - 1;
        }
    }
    if (sc.points) {
        std::fprintf(stderr, "rigpose-gcdiag: the shell scene only (--points has no surface; "
                             "there rigpose-sim's figures are the reference)\n");
        return 2;
    }

    if (sim_keep > 0.0) {
        sim_mode(sc.seed, first_run, runs, sc.frames, sim_keep, min_tracked);
        return 0;
    }
    if (surf_mix >= 0.0) {
        surface_sim_mode(sc, first_run, runs, 0.5, surf_mix);
        return 0;
    }
    enum { V_PIX, V_TRUTH, V_IID, NV };
    const char *vname[NV] = {"pixels", "truth", "truth+iid"};
    Score score[NV];
    double age_abs[NAGE] = {0}, age_sq[NAGE] = {0};
    unsigned long age_n[NAGE] = {0};
    double life_sum = 0.0, feats_sum = 0.0, mature_sum = 0.0, lm_sum = 0.0;
    unsigned long life_n = 0, fs_n = 0;
    double cam_bias[NAGE] = {0}; /* per frame and camera: |mean error vector| of the bucket */
    unsigned long cam_bias_n[NAGE] = {0};

    rp_pipe_t *pipe = static_cast<rp_pipe_t *>(std::calloc(1, sizeof(rp_pipe_t)));
    rp_vo_gc_t *gc[NV];
    rp_frameset_t *fs_v = static_cast<rp_frameset_t *>(std::calloc(1, sizeof(rp_frameset_t)));
    for (int k = 0; k < NV; ++k) {
        gc[k] = static_cast<rp_vo_gc_t *>(std::calloc(1, sizeof(rp_vo_gc_t)));
    }
    for (uint32_t r = first_run; r < first_run + runs; ++r) {
        rpr::SeqCfg rc = sc;
        rc.run = r;
        rpr::Sequence seq(rc);
        if (!seq.ok()) {
            std::fprintf(stderr, "rigpose-gcdiag: %s\n", seq.why().c_str());
            return 2;
        }
        rp_pipe_cfg_t cfg;
        rp_pipe_default_cfg(RP_PIPE_GC, &cfg);
        cfg.gc.ekf.sigma_px = (rp_real)0.5;
        cfg.gc.init_depth_m = (rp_real)0.8335;
        cfg.gc.init_depth_sigma_m = (rp_real)0.15;
        cfg.gc.init_on_sphere = 1;
        if (target > 0) {
            cfg.track.target = (uint16_t)target;
            cfg.track.topup_below = (uint16_t)(target * 4 / 5);
        }
        apply_gc_opts(&cfg.gc);
        if (min_tracked > 0) {
            cfg.gc.min_tracked = (uint16_t)min_tracked;
        }
        if (topup >= 0) {
            cfg.track.topup_below = (uint16_t)topup;
        }
        if (r == first_run) {
            static const char *const why[][2] = {
                {"gc.init_on_sphere", "the rendered shell surrounds the rig: depth along the ray"},
                {"gc.init_depth", "rigpose-sim's setting: the shell's mid radius 0.8335 m +- "
                                  "0.15 m (or --init-depth / --init-sigma)"},
                {"gc.ekf.sigma_px", "rigpose-sim's setting"},
                {"track.", "--target / --topup"},
                {"gc.", "this run's gc options"},
                {nullptr, nullptr}};
            (void)rp_cfg_diff_print(stderr, "rigpose-gcdiag", &cfg, why);
        }
        if (rp_pipe_init(pipe, &seq.rig(), &cfg) != RP_OK) {
            return 1;
        }
        for (int k = 1; k < NV; ++k) {
            rp_vo_gc_init(gc[k], &seq.rig(), &cfg.gc);
        }
        std::map<uint32_t, Birth> births;
        std::mt19937_64 rng(rpr::key(rc.seed, r, 77));
        std::normal_distribution<double> gauss(0.0, iid_px);
        std::vector<cv::Mat> img(4);
        Score run_score[NV];
        for (uint32_t j = 0; j < rc.frames; ++j) {
            rp_image_t views[RP_MAX_CAMS];
            const rp_image_t *ptrs[RP_MAX_CAMS] = {nullptr};
            for (int k = 0; k < 4; ++k) {
                render_cached(seq, cache, j, k, &img[k]);
                views[k] = rpr::image_view(img[k]);
                ptrs[k] = &views[k];
            }
            rp_estimate_t est[NV];
            rp_status_t st[NV];
            st[V_PIX] = rp_pipe_step(pipe, ptrs, 4, seq.utime(j), &est[V_PIX]);
            const rp_frameset_t *fs = nullptr;
            rp_pipe_frameset(pipe, &fs);
            rp_real tp[6];
            for (int c = 0; c < 6; ++c) {
                tp[c] = (rp_real)seq.truth(j)[c];
            }
            rp_pose_lin_t pl;
            rp_pose_lin_set(&pl, tp);
            /* truth of every feature; the tracker's error by age */
            rp_frameset_t fs_t = *fs;
            double bsum[NAGE][2] = {{0}};
            unsigned long bn[NAGE] = {0};
            for (int k = 0; k < 4; ++k) {
                std::memset(bsum, 0, sizeof bsum);
                std::memset(bn, 0, sizeof bn);
                for (uint16_t f = 0; f < fs->n[k]; ++f) {
                    const rp_feat_t &ft = fs->f[k][f];
                    auto it = births.find(ft.id);
                    if (it == births.end()) {
                        Birth b;
                        b.ok = surface_point_at(seq, pl, k, ft.uv, b.M);
                        b.frame = j;
                        b.last = j;
                        it = births.emplace(ft.id, b).first;
                    }
                    it->second.last = j;
                    rp_real M[3] = {(rp_real)it->second.M[0], (rp_real)it->second.M[1],
                                    (rp_real)it->second.M[2]};
                    rp_real uv[2];
                    if (!it->second.ok ||
                        rp_rig_project(&seq.rig(), (uint8_t)k, &pl, M, uv, nullptr, nullptr) !=
                            RP_OK) {
                        fs_t.f[k][f].uv[0] = fs_t.f[k][f].uv[1] = (rp_real)NAN;
                        continue;
                    }
                    fs_t.f[k][f].uv[0] = uv[0];
                    fs_t.f[k][f].uv[1] = uv[1];
                    const double ex = (double)(ft.uv[0] - uv[0]), ey = (double)(ft.uv[1] - uv[1]);
                    const int b = age_bucket(j - it->second.frame);
                    age_abs[b] += std::sqrt(ex * ex + ey * ey);
                    age_sq[b] += ex * ex + ey * ey;
                    age_n[b]++;
                    bsum[b][0] += ex;
                    bsum[b][1] += ey;
                    bn[b]++;
                }
                for (int b = 0; b < NAGE; ++b) {
                    if (bn[b] >= 5) {
                        cam_bias[b] += std::hypot(bsum[b][0] / bn[b], bsum[b][1] / bn[b]);
                        cam_bias_n[b]++;
                    }
                }
            }
            st[V_TRUTH] = rp_vo_gc_step(gc[V_TRUTH], &fs_t, &est[V_TRUTH]);
            {
                const rp_vo_gc_t *g = &pipe->est.gc;
                unsigned nm = 0;
                for (uint16_t s = 0; s < RP_IDMAP_MAX_SLOTS; ++s) {
                    nm += rp_lmtab_slot(&g->lm, s, NULL, NULL, NULL) == RP_OK && g->mature[s];
                }
                mature_sum += nm;
                lm_sum += g->lm.map.n;
                feats_sum += fs->n[0] + fs->n[1] + fs->n[2] + fs->n[3];
                fs_n++;
            }
            *fs_v = fs_t;
            for (int k = 0; k < 4; ++k) {
                for (uint16_t f = 0; f < fs_v->n[k]; ++f) {
                    fs_v->f[k][f].uv[0] += (rp_real)gauss(rng);
                    fs_v->f[k][f].uv[1] += (rp_real)gauss(rng);
                }
            }
            st[V_IID] = rp_vo_gc_step(gc[V_IID], fs_v, &est[V_IID]);
            if (j == 0) {
                continue;
            }
            for (int v = 0; v < NV; ++v) {
                score[v].add(est[v].p, seq.truth(j), st[v]);
                run_score[v].add(est[v].p, seq.truth(j), st[v]);
            }
            if (verbose) {
                std::printf("  run %u frame %3u feats %3u %3u %3u %3u tx err pix %+.5f truth %+.5f "
                            "iid %+.5f\n",
                            r, j, fs->n[0], fs->n[1], fs->n[2], fs->n[3],
                            (double)est[V_PIX].p[0] - seq.truth(j)[0],
                            (double)est[V_TRUTH].p[0] - seq.truth(j)[0],
                            (double)est[V_IID].p[0] - seq.truth(j)[0]);
            }
        }
        for (const auto &b : births) {
            life_sum += b.second.last - b.second.frame + 1;
            life_n++;
        }
        std::printf("run %u: tx pixels %.6f truth %.6f truth+iid %.6f\n", r,
                    run_score[V_PIX].err[0] / run_score[V_PIX].frames,
                    run_score[V_TRUTH].err[0] / run_score[V_TRUTH].frames,
                    run_score[V_IID].err[0] / run_score[V_IID].frames);
        std::fflush(stdout);
    }
    std::printf("\nrigpose-gcdiag: gc, %u runs x %u frames from run %u of seed %llu, %dx%d, "
                "ss %d, noise %.2g grey\n  %-22s",
                runs, sc.frames, first_run, (unsigned long long)sc.seed, sc.width, sc.height,
                sc.ss, sc.noise_grey, "input");
    for (const char *c : col_name) {
        std::printf("%10s", c);
    }
    std::printf("%8s\n", "lost");
    for (int v = 0; v < NV; ++v) {
        score[v].print(vname[v]);
    }
    std::printf("\n  per frame set: %.1f features (4 cameras), gc holds %.1f landmarks, %.1f "
                "mature; mean track life %.1f frames (%lu tracks)\n",
                feats_sum / fs_n, lm_sum / fs_n, mature_sum / fs_n, life_sum / life_n, life_n);
    std::printf("\n  tracker error vs the renderer's truth by age (frames since birth)\n"
                "  %-8s%10s%12s%12s%22s\n", "age", "n", "mean |e|", "rms |e|",
                "|camera mean e|");
    for (int b = 0; b < NAGE; ++b) {
        if (age_n[b]) {
            std::printf("  %-8s%10lu%12.4f%12.4f%22.4f\n", age_name[b], age_n[b],
                        age_abs[b] / age_n[b], std::sqrt(age_sq[b] / age_n[b]),
                        cam_bias_n[b] ? cam_bias[b] / cam_bias_n[b] : 0.0);
        }
    }
    return 0;
}
