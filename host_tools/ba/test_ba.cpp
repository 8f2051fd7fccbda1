/*
 * test_ba.cpp - rigpose-ba's library (rp_ba.hpp, rp_tracks.hpp), run by `make test` (ASan +
 * UBSan, the sanitised double/Eigen core and simulator):
 *  - the residual's projection (templated for Ceres) is the core's eq. 2 (rp_rig_project) for a
 *    rotated, offset camera with distortion;
 *  - noise-free measurements: the batch optimum is the truth, whatever the start (1 cm / 10 mrad
 *    off), and frame 0 stays the identity (the gauge);
 *  - the bound: variance proportional to sigma^2, zero at frame 0;
 *  - on simulated runs (stereo2, Table 1 protocol): the batch's mean squared error is the bound
 *    (an efficient estimator) within sampling, and rigpose's is not below it;
 *  - the tracks file: written and read back, and a malformed line named.
 * Prints the measured figures; ends with "[  PASSED  ] N test(s)." and exit 0 when all pass.
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "rigpose/rp_rot.h"
#include "rigpose/rp_vo_stereo.h"
#include "rp_ba.hpp"
#include "rp_sim.h"
#include "rp_tracks.hpp"

static int n_pass = 0, n_fail = 0;

static void check(bool ok, const char *what)
{
    std::printf("%s %s\n", ok ? "[       OK ]" : "[  FAILED  ]", what);
    (ok ? n_pass : n_fail)++;
}

/* A simulated run's truth and what a method's cameras saw; est: rigpose stereo2's poses. */
struct SimRun {
    rpba::Problem pb;
    std::vector<rpba::Pose6> truth, est;
    std::vector<std::pair<uint32_t, rpba::Vec3>> lm;
};

static SimRun sim_run(double noise_px, uint32_t frames, uint32_t run, bool run_rigpose)
{
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    cfg.noise_px = noise_px;
    cfg.n_frames = frames;
    rp_sim_run_t sr;
    SimRun out;
    if (rp_sim_run_init(&sr, &cfg, 1, run) != 0) {
        return out;
    }
    std::unique_ptr<rp_frameset_t> fs(new rp_frameset_t());
    std::unique_ptr<rp_vo_stereo_t> vo(new rp_vo_stereo_t());
    const rp_vo_stereo_cfg_t vcfg = rp_sim_stereo_cfg(&cfg, 0);
    if (run_rigpose && rp_vo_stereo_init(vo.get(), &sr.rig, &vcfg) != RP_OK) {
        rp_sim_run_free(&sr);
        return out;
    }
    out.pb.rig = sr.rig;
    out.pb.n_frames = frames;
    std::vector<char> seen(cfg.n_points, 0);
    for (uint32_t j = 0; j < frames; ++j) {
        (void)rp_sim_frame(&sr, j, fs.get());
        rpba::Pose6 t, e = {0, 0, 0, 0, 0, 0};
        for (int i = 0; i < 6; ++i) {
            t[i] = sr.truth[6 * j + (unsigned)i];
        }
        if (run_rigpose) {
            rp_estimate_t est;
            (void)rp_vo_stereo_step(vo.get(), fs.get(), &est);
            for (int i = 0; i < 6; ++i) {
                e[i] = (double)est.p[i];
            }
        }
        out.truth.push_back(t);
        out.est.push_back(e);
        for (uint8_t k : {(uint8_t)RP_SIM_CAM1, (uint8_t)RP_SIM_CAM1B}) {
            for (unsigned i = 0; i < fs->n[k]; ++i) {
                const rp_feat_t &f = fs->f[k][i];
                out.pb.obs.push_back({j, k, f.id, {(double)f.uv[0], (double)f.uv[1]}});
                if (!seen[f.id]) {
                    seen[f.id] = 1;
                    out.lm.push_back({f.id, {sr.points[3 * f.id], sr.points[3 * f.id + 1],
                                             sr.points[3 * f.id + 2]}});
                }
            }
        }
    }
    rp_sim_run_free(&sr);
    return out;
}

static void test_projection(void)
{
    rp_rig_t rig;
    rig.n_cams = 2;
    rig.cam[0].cam = rp_cam_pinhole(752, 480, 458.654, 457.296, 367.215, 248.375);
    rig.cam[1] = rig.cam[0];
    rig.cam[1].cam.k1 = -0.28340811;
    rig.cam[1].cam.k2 = 0.07395907;
    rig.cam[1].cam.p1 = 0.00019359;
    rig.cam[1].cam.p2 = 1.76187114e-05;
    rig.cam[1].cam.k3 = 0.01;
    const rp_real abg[3] = {0.1, -0.2, 0.3};
    rp_rot_from_angles(abg, rig.cam[1].R);
    rig.cam[1].D[0] = 0.11;
    rig.cam[1].D[1] = -0.02;
    rig.cam[1].D[2] = 0.03;
    for (int i = 0; i < 9; ++i) {
        rig.cam[0].R[i] = (i % 4 == 0) ? 1 : 0;
    }
    rig.cam[0].D[0] = rig.cam[0].D[1] = rig.cam[0].D[2] = 0;
    double worst = 0;
    int n = 0;
    for (int t = 0; t < 50; ++t) {
        const rpba::Pose6 p = {0.3 * std::sin(t), 0.1 * t * 0.01, -0.2 * std::cos(t),
                               0.05 * std::sin(3.0 * t), 0.3 * std::cos(2.0 * t), 1.5 * std::sin(t)};
        rp_real pr[6];
        for (int i = 0; i < 6; ++i) {
            pr[i] = (rp_real)p[i];
        }
        rp_pose_lin_t pl;
        rp_pose_lin_set(&pl, pr);
        for (uint8_t k = 0; k < 2; ++k) {
            /* a point 2 m in front of camera k, off its axis */
            const rp_real P[3] = {(rp_real)(0.5 * std::sin(7.0 * t)), (rp_real)(0.3 * std::cos(5.0 * t)),
                                  2};
            rp_real Mw[3], uv[2];
            rp_rig_world_point(&rig, k, &pl, P, Mw);
            if (rp_rig_project(&rig, k, &pl, Mw, uv, NULL, NULL) != RP_OK) {
                continue;
            }
            double uvb[2];
            const rpba::Vec3 M = {(double)Mw[0], (double)Mw[1], (double)Mw[2]};
            if (!rpba::project(rig, k, p, M, uvb)) {
                worst = INFINITY;
                continue;
            }
            worst = std::fmax(worst, std::hypot(uvb[0] - (double)uv[0], uvb[1] - (double)uv[1]));
            ++n;
        }
    }
    std::printf("  projection vs rp_rig_project: %d points, largest difference %.3g px\n", n, worst);
    /* the same equations in double: only rounding differs (1e-9 px is 1e-12 of the image) */
    check(n == 100 && worst < 1e-9, "the residual's projection is the core's eq. 2 with distortion");
}

static void test_noise_free(void)
{
    SimRun r = sim_run(0.0, 15, 3, false);
    std::vector<rpba::Pose6> start = r.truth;
    for (size_t j = 1; j < start.size(); ++j) {
        for (int i = 0; i < 6; ++i) {
            start[j][i] += (i < 3 ? 0.01 : 0.01) * ((j + (size_t)i) % 2 ? 1.0 : -1.0);
        }
    }
    rpba::Options o;
    o.sigma_px = 0.5;
    o.fallback_depth = 0.8335;
    rpba::Result res;
    std::string why;
    const bool ok = rpba::solve(r.pb, start, o, &res, &why);
    double worst_t = 0, worst_r = 0;
    for (size_t j = 0; ok && j < res.pose.size(); ++j) {
        for (int i = 0; i < 6; ++i) {
            const double e = std::fabs(std::remainder(res.pose[j][i] - r.truth[j][i], 2 * M_PI));
            (i < 3 ? worst_t : worst_r) = std::fmax(i < 3 ? worst_t : worst_r, e);
        }
    }
    std::printf("  noise-free, 15 frames, start 1 cm / 10 mrad off: %s; largest error %.3g m, "
                "%.3g rad; %zu landmarks, %d iterations, final RMS %.3g px\n",
                ok ? "solved" : why.c_str(), worst_t, worst_r, res.n_landmarks, res.iterations,
                res.rms_px_final);
    /* noise-free measurements and the exact model: the truth has zero cost; 1e-6 m / rad is
     * 10,000 times below the start's offset and 10 times below the noisy runs' errors */
    check(ok && worst_t < 1e-6 && worst_r < 1e-6, "noise-free: the batch optimum is the truth");
    bool gauge = ok;
    for (int i = 0; ok && i < 6; ++i) {
        gauge = gauge && res.pose[0][i] == 0.0;
    }
    check(gauge, "frame 0 stays the identity (the gauge)");
}

static void test_bound_and_efficiency(void)
{
    /* stereo2, 4 runs of 20 frames at 0.5 px: squared errors of rigpose and of the batch against
     * the bound's variances, summed over the six columns and the frames 1..19 */
    double se[2] = {0, 0}, var = 0, var1 = 0, gauge = 0;
    int runs_ok = 0;
    for (uint32_t run = 0; run < 4; ++run) {
        SimRun r = sim_run(0.5, 20, run, true);
        rpba::Options o;
        o.sigma_px = 0.5;
        o.fallback_depth = 0.8335;
        rpba::Result res;
        std::vector<rpba::Cov6> cov, cov1;
        std::string why;
        if (!rpba::solve(r.pb, r.est, o, &res, &why) ||
            !rpba::crb(r.pb, r.truth, r.lm, 0.5, &cov, &why) ||
            !rpba::crb(r.pb, r.truth, r.lm, 1.0, &cov1, &why)) {
            std::printf("  run %u: %s\n", run, why.c_str());
            continue;
        }
        ++runs_ok;
        for (int e = 0; e < 36; ++e) {
            gauge += std::fabs(cov[0][e]);
        }
        for (size_t j = 1; j < r.truth.size(); ++j) {
            double Cw[9], Ca[9], Cw1[9], Ca1[9];
            for (int e = 0; e < 9; ++e) {
                Cw[e] = cov[j][6 * (3 + e / 3) + 3 + e % 3];
                Cw1[e] = cov1[j][6 * (3 + e / 3) + 3 + e % 3];
            }
            rpba::angles_cov(r.truth[j], Cw, Ca);
            rpba::angles_cov(r.truth[j], Cw1, Ca1);
            for (int c = 0; c < 6; ++c) {
                var += c < 3 ? cov[j][7 * c] : Ca[4 * (c - 3)];
                var1 += c < 3 ? cov1[j][7 * c] : Ca1[4 * (c - 3)];
                const rpba::Pose6 *p[2] = {&r.est[j], &res.pose[j]};
                for (int w = 0; w < 2; ++w) {
                    const double e = std::remainder((*p[w])[c] - r.truth[j][c], c < 3 ? 1e9 : 2 * M_PI);
                    se[w] += e * e;
                }
            }
        }
    }
    std::printf("  stereo2, %d runs x 20 frames: mean squared error / bound: rigpose %.3f, batch "
                "%.3f; bound at 1 px / at 0.5 px %.6f; frame 0's bound %.3g\n",
                runs_ok, se[0] / var, se[1] / var, var1 / var, gauge);
    check(runs_ok == 4, "4 runs solved, each with a bound");
    /* variance of an unbiased estimate is proportional to sigma^2 (the information is
     * J^T J / sigma^2 with J independent of sigma) */
    check(std::fabs(var1 / var - 4.0) < 1e-9, "the bound scales with sigma^2");
    check(gauge == 0.0, "the bound is zero at frame 0 (the gauge)");
    /* the batch is the maximum-likelihood estimate, efficient for Gaussian noise: its mean
     * squared error is the bound up to sampling (4 runs of correlated errors: a factor 2 either
     * way); a bound off by sigma instead of sigma^2 would be 2x at 0.5 px, one missing a
     * camera's offset or the landmarks' uncertainty many times more */
    check(se[1] / var > 0.5 && se[1] / var < 2.0, "the batch's error is the bound's, within 2x");
    /* no unbiased estimator is below the bound; 0.7 leaves room for sampling */
    check(se[0] / var > 0.7, "rigpose is not below the bound");
}

static void test_tracks_file(void)
{
    const char *dir = std::getenv("RP_BA_WORK");
    const std::string work = dir ? dir : "build/ba/work";
    if (std::system(("mkdir -p '" + work + "'").c_str()) != 0) {
        check(false, "work folder");
        return;
    }
    rp_sim_cfg_t cfg;
    rp_sim_default_cfg(&cfg);
    rp_rig_t rig;
    rp_sim_make_rig(&cfg, &rig);
    rig.cam[1].cam.k1 = (rp_real)-0.25;
    std::unique_ptr<rp_frameset_t> fs(new rp_frameset_t());
    const std::string path = work + "/t.tracks";
    std::FILE *f = std::fopen(path.c_str(), "w");
    std::string why;
    bool ok = f && rptk::write_header(f, "simclip", rig, &why);
    rp_estimate_t est = {};
    const double truth[6] = {0.1, -0.2, 0.3, 0.01, -0.02, 0.03};
    for (uint32_t j = 0; ok && j < 2; ++j) {
        *fs = rp_frameset_t();
        fs->utime = 1000 + j;
        fs->n[0] = 1;
        fs->f[0][0].id = 7;
        fs->f[0][0].uv[0] = (rp_real)(10.25 + j);
        fs->f[0][0].uv[1] = (rp_real)20.5;
        fs->n[4] = 1;
        fs->f[4][0].id = 7;
        fs->f[4][0].uv[0] = (rp_real)5.125;
        fs->f[4][0].uv[1] = (rp_real)6.0;
        est.p[0] = (rp_real)(0.5 * j);
        est.flags = RP_EST_TRACKING;
        ok = rptk::write_frame(f, j, *fs, est, j ? truth : nullptr, &why);
    }
    ok = f && std::fclose(f) == 0 && ok;
    rptk::Tracks tk;
    ok = ok && rptk::read(path, &tk, &why);
    bool same = ok && tk.name == "simclip" && tk.rig.n_cams == rig.n_cams &&
                tk.frames.size() == 2 && tk.frames[1].utime == 1001 &&
                tk.frames[1].f.size() == 2 && tk.frames[1].f[0].uv[0] == 11.25 &&
                tk.frames[1].f[1].cam == 4 && tk.frames[1].f[1].id == 7 &&
                tk.frames[1].est[0] == 0.5 && tk.frames[1].est_flags == RP_EST_TRACKING &&
                !tk.frames[0].has_truth && tk.frames[1].has_truth && tk.frames[1].truth[5] == 0.03;
    for (unsigned k = 0; same && k < rig.n_cams; ++k) {
        same = tk.rig.cam[k].cam.fx == rig.cam[k].cam.fx && tk.rig.cam[k].cam.k1 == rig.cam[k].cam.k1;
        for (int i = 0; i < 9; ++i) {
            same = same && tk.rig.cam[k].R[i] == rig.cam[k].R[i];
        }
        for (int i = 0; i < 3; ++i) {
            same = same && tk.rig.cam[k].D[i] == rig.cam[k].D[i];
        }
    }
    check(same, "a tracks file written and read back is the same, to the bit");
    f = std::fopen(path.c_str(), "a");
    if (f) {
        std::fprintf(f, "f 9 1 2 3\n");
        std::fclose(f);
    }
    const bool refused = !rptk::read(path, &tk, &why);
    std::printf("  malformed: %s\n", why.c_str());
    check(refused && why.find("t.tracks:") != std::string::npos &&
              why.find(": f: K ID U V") != std::string::npos,
          "a feature of a camera not in the rig is refused with its file and line");
}

int main()
{
    test_projection();
    test_tracks_file();
    test_noise_free();
    test_bound_and_efficiency();
    std::printf("%s %d test(s).\n", n_fail ? "[  FAILED  ]" : "[  PASSED  ]", n_fail ? n_fail : n_pass);
    return n_fail ? 1 : 0;
}
