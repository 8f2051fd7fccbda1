/*
 * rigpose-render - renders the paper's six-camera rig moving through the textured shell scene
 * (rp_render.hpp) and writes a replay folder (the shared format):
 *   frames.csv  utime_us,cam0,...,cam5   then one row per frame set (paths relative to the folder)
 *   truth.csv   utime_us,tx,ty,tz,alpha,beta,gamma   pose of the rig's reference camera (the
 *               paper's cam1 = cam0 here) in the world, as rp_estimate_t.p
 *   rig.yaml    the daemon's configuration (config/README.md): replay source, the six cameras'
 *               calibration, method stereo4
 *   camK/NNNNNN.png  8-bit grey images
 * Column camK is rig camera K in rp_sim.h's order: cam0 = cam1 (front), cam1 = cam2 (right),
 * cam2 = cam3 (back), cam3 = cam4 (left), cam4 = cam1's stereo partner, cam5 = cam3's.
 * The motion is run `--run` of rigpose-sim's experiment `--seed` (the paper's Table 1 motion,
 * or with --motion turn / pitch / smooth rigpose-sim's); --cam-offsets-ms / --jitter-ms render
 * each camera at its own (unknown) capture time, stamped with the set's; --moving-object adds
 * an independently moving textured sphere in front of one camera (rp_render.hpp, MovingObject).
 */
#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "rp_render.hpp"
#include "rp_render_cli.hpp"

static void usage(FILE *out)
{
    std::fprintf(out,
                 "usage: rigpose-render --out DIR [options]\n"
                 "Renders the six-camera rig through a textured scene; writes a replay folder.\n"
                 "  --out DIR        output folder (created)\n");
    rpr::cli_usage(out);
}

static bool mkdir_p(const std::string &dir)
{
    return mkdir(dir.c_str(), 0755) == 0 || errno == EEXIST;
}

/* rig.yaml in the daemon's configuration schema (config/README.md): a replay source reading
 * this folder's frames.csv, the six cameras, method stereo4 on the two pairs. */
static bool write_rig_yaml(const std::string &path, const rpr::Sequence &seq)
{
    static const char *const names[6] = {"cam1", "cam2", "cam3", "cam4", "cam1b", "cam3b"};
    FILE *f = std::fopen(path.c_str(), "w");
    if (!f) {
        return false;
    }
    const rp_rig_t &rig = seq.rig();
    const rpr::SeqCfg &c = seq.cfg();
    /* Only what differs from the defaults, so that default runs write the same bytes. */
    std::string extra;
    if (c.motion) {
        static const char *const motions[] = {"paper", "turn", "pitch", "smooth"};
        extra += std::string("  motion: ") + motions[c.motion] + "\n";
    }
    bool clocks = c.jitter_s != 0.0;
    for (int k = 0; k < 6; ++k) {
        clocks = clocks || c.cam_offset_s[k] != 0.0;
    }
    if (clocks) {
        /* the truth of the clocks, for whoever scores an offset estimator on this folder */
        char b[256];
        std::snprintf(b, sizeof b, "  cam_offsets_ms: [%g, %g, %g, %g, %g, %g]\n  jitter_ms: %g\n",
                      c.cam_offset_s[0] * 1e3, c.cam_offset_s[1] * 1e3, c.cam_offset_s[2] * 1e3,
                      c.cam_offset_s[3] * 1e3, c.cam_offset_s[4] * 1e3, c.cam_offset_s[5] * 1e3,
                      c.jitter_s * 1e3);
        extra += b;
    }
    if (c.moving_object) {
        char b[96];
        std::snprintf(b, sizeof b, "  moving_object: {camera: %d, cover: %g}\n", c.object_cam,
                      c.object_cover);
        extra += b;
    }
    std::fprintf(f,
                 "# Written by rigpose-render: the paper's six-camera rig (docs/design.md). Schema:\n"
                 "# config/README.md. Camera order = rig index; device = column of frames.csv.\n"
                 "version: 1\n\n"
                 "meta:\n  tool: rigpose-render\n  seed: %llu\n  run: %u\n  frames: %u\n"
                 "  noise_grey: %g\n  blur_sigma: %g\n  brightness: %g\n  scene: %s\n%s\n"
                 "source:\n  kind: replay\n  replay_index: frames.csv\n  realtime: false\n\n"
                 "cameras:\n",
                 (unsigned long long)c.seed, c.run, c.frames, c.noise_grey, c.blur_sigma,
                 c.brightness, c.points ? "points" : (c.flat ? "sphere" : "shell"), extra.c_str());
    for (int k = 0; k < rig.n_cams && k < 6; ++k) {
        const rp_rig_cam_t &rc = rig.cam[k];
        std::fprintf(f,
                     "  - name: %s\n    device: cam%d\n    width: %u\n    height: %u\n"
                     "    fps: 30\n    intrinsics: [%.17g, %.17g, %.17g, %.17g]\n"
                     "    distortion: [%.17g, %.17g, %.17g, %.17g, %.17g]\n"
                     "    position: [%.17g, %.17g, %.17g]\n    rotation: [",
                     names[k], k, rc.cam.width, rc.cam.height, (double)rc.cam.fx,
                     (double)rc.cam.fy, (double)rc.cam.cx, (double)rc.cam.cy, (double)rc.cam.k1,
                     (double)rc.cam.k2, (double)rc.cam.p1, (double)rc.cam.p2, (double)rc.cam.k3,
                     (double)rc.D[0], (double)rc.D[1], (double)rc.D[2]);
        for (int i = 0; i < 9; ++i) {
            std::fprintf(f, "%s%.17g", i ? ", " : "", (double)rc.R[i]);
        }
        std::fprintf(f, "]\n");
    }
    std::fprintf(f, "\nestimator:\n  method: stereo4\n  pairs: [[cam1, cam1b], [cam3, cam3b]]\n"
                    "  sigma_px: 0.5\n");
    return std::fclose(f) == 0;
}

int main(int argc, char **argv)
{
    rpr::SeqCfg cfg;
    std::string out;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        }
        if (!std::strcmp(argv[i], "--out") && i + 1 < argc) {
            out = argv[++i];
            continue;
        }
        const int used = rpr::cli_parse(argc, argv, i, &cfg);
        if (used <= 0) {
            if (used == 0) {
                std::fprintf(stderr, "rigpose-render: unknown option '%s'\n", argv[i]);
            }
            usage(stderr);
            return 2;
        }
        i += used - 1;
    }
    if (out.empty()) {
        std::fprintf(stderr, "rigpose-render: --out DIR is required\n");
        usage(stderr);
        return 2;
    }
    rpr::Sequence seq(cfg);
    if (!seq.ok()) {
        std::fprintf(stderr, "rigpose-render: %s\n", seq.why().c_str());
        return 2;
    }
    const int n_cams = seq.rig().n_cams;
    if (!mkdir_p(out)) {
        std::fprintf(stderr, "rigpose-render: cannot create %s: %s\n", out.c_str(),
                     std::strerror(errno));
        return 1;
    }
    for (int k = 0; k < n_cams; ++k) {
        if (!mkdir_p(out + "/cam" + std::to_string(k))) {
            std::fprintf(stderr, "rigpose-render: cannot create folders in %s\n", out.c_str());
            return 1;
        }
    }
    FILE *frames = std::fopen((out + "/frames.csv").c_str(), "w");
    FILE *truth = std::fopen((out + "/truth.csv").c_str(), "w");
    if (!frames || !truth || !write_rig_yaml(out + "/rig.yaml", seq)) {
        std::fprintf(stderr, "rigpose-render: cannot write into %s\n", out.c_str());
        return 1;
    }
    std::fprintf(frames, "utime_us");
    for (int k = 0; k < n_cams; ++k) {
        std::fprintf(frames, ",cam%d", k);
    }
    std::fprintf(frames, "\n");
    std::fprintf(truth, "utime_us,tx,ty,tz,alpha,beta,gamma\n");
    for (uint32_t j = 0; j < cfg.frames; ++j) {
        const long long ut = (long long)seq.utime(j);
        std::fprintf(frames, "%lld", ut);
        for (int k = 0; k < n_cams; ++k) {
            char rel[64];
            std::snprintf(rel, sizeof rel, "cam%d/%06u.png", k, j);
            cv::Mat img;
            seq.render(j, k, &img);
            if (!cv::imwrite(out + "/" + rel, img)) {
                std::fprintf(stderr, "rigpose-render: cannot write %s/%s\n", out.c_str(), rel);
                return 1;
            }
            std::fprintf(frames, ",%s", rel);
        }
        std::fprintf(frames, "\n");
        const double *t = seq.truth(j);
        std::fprintf(truth, "%lld,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", ut, t[0], t[1], t[2],
                     t[3], t[4], t[5]);
    }
    if (std::fclose(frames) != 0 || std::fclose(truth) != 0) {
        std::fprintf(stderr, "rigpose-render: write error in %s\n", out.c_str());
        return 1;
    }
    std::printf("rigpose-render: %u frame sets x %d cameras (%dx%d, fx %.1f px) in %s\n",
                cfg.frames, n_cams, cfg.width, cfg.height, (double)seq.rig().cam[0].cam.fx,
                out.c_str());
    if (cfg.jitter_s != 0.0 || cfg.cam_offset_s[0] != 0.0 || cfg.cam_offset_s[1] != 0.0 ||
        cfg.cam_offset_s[2] != 0.0 || cfg.cam_offset_s[3] != 0.0 || cfg.cam_offset_s[4] != 0.0 ||
        cfg.cam_offset_s[5] != 0.0) {
        std::printf("  camera clocks: each image rendered at set time + offset + jitter, stamped "
                    "with the set's time; offsets (ms, cam0..cam5) %g %g %g %g %g %g, jitter "
                    "sigma %g ms (also in rig.yaml's meta)\n",
                    cfg.cam_offset_s[0] * 1e3, cfg.cam_offset_s[1] * 1e3, cfg.cam_offset_s[2] * 1e3,
                    cfg.cam_offset_s[3] * 1e3, cfg.cam_offset_s[4] * 1e3, cfg.cam_offset_s[5] * 1e3,
                    cfg.jitter_s * 1e3);
    }
    return 0;
}
