/*
 * rp_render_cli.hpp - the command-line options of a rendered sequence (rpr::SeqCfg), shared by
 * rigpose-render and rigpose-e2e.
 */
#ifndef RP_RENDER_CLI_HPP
#define RP_RENDER_CLI_HPP

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "rp_render.hpp"

namespace rpr {

inline void cli_usage(FILE *out)
{
    std::fprintf(out,
                 "  --seed S         experiment seed: motion of rigpose-sim's run, scene (default 1)\n"
                 "  --run R          run index within the experiment (default 0)\n"
                 "  --frames N       frame sets (default 100)\n"
                 "  --width W --height H   image size (default 640x480)\n"
                 "  --focal-px F     fx = fy (default 800 x W / 640); principal point at the centre\n"
                 "  --dist k1,k2,p1,p2,k3  OpenCV distortion of every camera (default none)\n"
                 "  --ss N           sub-pixel samples per axis, 1..8 (default 2)\n"
                 "  --noise-grey S   Gaussian image noise, grey levels (default 1)\n"
                 "  --blur S         Gaussian blur sigma, px (default 0)\n"
                 "  --brightness A   gain change 1 + A sin(2 pi j / 40 + k) (default 0)\n"
                 "  --flat           sphere of radius 0.8335 m instead of the bumpy shell\n"
                 "  --points         rp_sim's own 10,000 points as textured discs instead of the shell\n"
                 "  --disc-r M       disc radius of --points, m (default 0.012)\n"
                 "  --face-px N      texture cube map face side (default 1024)\n"
                 "  --motion M       paper (default): rigpose-sim's run; turn: a turn on the spot,\n"
                 "                   0.035 rad/frame of yaw (use --frames 200 for the full turn);\n"
                 "                   pitch: the same about cam1's x axis; smooth: a smooth wander,\n"
                 "                   peaks about 0.5 m/s and 1 rad/s (rp_sim.h)\n"
                 "  --cam-offsets-ms LIST  per camera (rp_sim.h's order: cam1,cam2,cam3,cam4,\n"
                 "                   cam1b,cam3b; missing ones 0) its clock offset, unknown to the\n"
                 "                   estimators: each image is rendered at set time + offset and\n"
                 "                   stamped with the set's time (turn, pitch or smooth only)\n"
                 "  --jitter-ms S    Gaussian capture-time noise per image, sigma S ms, not stamped\n"
                 "  --moving-object  add an independently moving textured sphere covering\n"
                 "                   --object-cover of camera --object-cam's view\n"
                 "  --object-cam K   rig camera 0..5 (rp_sim.h's order; default 0 = cam1)\n"
                 "  --object-cover F fraction of that view, 0..0.6 (default 0.30)\n");
}

/* Parses the option at argv[i] (and its value) into cfg. Returns the number of arguments used,
 * 0 if argv[i] is not one of these options, -1 on a bad value (message printed). */
inline int cli_parse(int argc, char **argv, int i, SeqCfg *cfg)
{
    const char *o = argv[i];
    if (!std::strcmp(o, "--flat")) {
        cfg->flat = true;
        return 1;
    }
    if (!std::strcmp(o, "--points")) {
        cfg->points = true;
        return 1;
    }
    if (!std::strcmp(o, "--moving-object")) {
        cfg->moving_object = true;
        return 1;
    }
    if (!std::strcmp(o, "--motion")) {
        const char *v = i + 1 < argc ? argv[i + 1] : "";
        static const char *const names[] = {"paper", "turn", "pitch", "smooth"}; /* rp_sim.h */
        for (int m = 0; m < 4; ++m) {
            if (!std::strcmp(v, names[m])) {
                cfg->motion = m;
                return 2;
            }
        }
        std::fprintf(stderr, "bad value for --motion: '%s' (paper, turn, pitch or smooth)\n", v);
        return -1;
    }
    if (!std::strcmp(o, "--cam-offsets-ms")) {
        const char *p = i + 1 < argc ? argv[i + 1] : "";
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            cfg->cam_offset_s[k] = 0.0;
        }
        for (int k = 0; k < RP_SIM_NCAMS; ++k) {
            char *end = nullptr;
            errno = 0;
            const double ms = std::strtod(p, &end);
            if (errno || end == p || (*end && *end != ',') || !(std::fabs(ms) <= 1000.0) ||
                (*end == ',' && k == RP_SIM_NCAMS - 1)) {
                std::fprintf(stderr, "bad value for --cam-offsets-ms: '%s' (up to %d numbers, "
                             "-1000..1000 ms)\n", i + 1 < argc ? argv[i + 1] : "", RP_SIM_NCAMS);
                return -1;
            }
            cfg->cam_offset_s[k] = ms * 1e-3;
            if (!*end) {
                break;
            }
            p = end + 1;
        }
        return 2;
    }
    static const char *const with_value[] = {"--seed",  "--run",        "--frames", "--width",
                                             "--height", "--focal-px",  "--dist",   "--ss",
                                             "--noise-grey", "--blur",  "--brightness",
                                             "--face-px", "--disc-r", "--object-cam",
                                             "--object-cover", "--jitter-ms"};
    bool known = false;
    for (const char *w : with_value) {
        known = known || !std::strcmp(o, w);
    }
    if (!known) {
        return 0;
    }
    if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", o);
        return -1;
    }
    const char *v = argv[i + 1];
    char *end = nullptr;
    errno = 0;
    bool bad = false;
    if (!std::strcmp(o, "--dist")) {
        const char *p = v;
        for (int c = 0; c < 5 && !bad; ++c) {
            cfg->dist[c] = std::strtod(p, &end);
            bad = end == p || (c < 4 && *end != ',') || (c == 4 && *end) || !std::isfinite(cfg->dist[c]);
            p = end + 1;
        }
    } else if (!std::strcmp(o, "--seed")) {
        cfg->seed = std::strtoull(v, &end, 0);
        bad = *v == '-';
    } else {
        const double x = std::strtod(v, &end);
        bad = !std::isfinite(x);
        if (!std::strcmp(o, "--run")) {
            bad = bad || x < 0 || x > 1e9 || x != std::floor(x);
            cfg->run = (uint32_t)x;
        } else if (!std::strcmp(o, "--frames")) {
            bad = bad || x < 1 || x > 1e6 || x != std::floor(x);
            cfg->frames = (uint32_t)x;
        } else if (!std::strcmp(o, "--width")) {
            bad = bad || x < 32 || x > 4096 || x != std::floor(x);
            cfg->width = (int)x;
        } else if (!std::strcmp(o, "--height")) {
            bad = bad || x < 32 || x > 4096 || x != std::floor(x);
            cfg->height = (int)x;
        } else if (!std::strcmp(o, "--focal-px")) {
            bad = bad || x <= 0 || x > 1e6;
            cfg->focal_px = x;
        } else if (!std::strcmp(o, "--ss")) {
            bad = bad || x < 1 || x > 8 || x != std::floor(x);
            cfg->ss = (int)x;
        } else if (!std::strcmp(o, "--noise-grey")) {
            bad = bad || x < 0 || x > 255;
            cfg->noise_grey = x;
        } else if (!std::strcmp(o, "--blur")) {
            bad = bad || x < 0 || x > 50;
            cfg->blur_sigma = x;
        } else if (!std::strcmp(o, "--brightness")) {
            bad = bad || x < 0 || x > 0.9;
            cfg->brightness = x;
        } else if (!std::strcmp(o, "--object-cam")) {
            bad = bad || x < 0 || x > 5 || x != std::floor(x);
            cfg->object_cam = (int)x;
        } else if (!std::strcmp(o, "--object-cover")) {
            bad = bad || !(x > 0 && x <= 0.6);
            cfg->object_cover = x;
        } else if (!std::strcmp(o, "--jitter-ms")) {
            bad = bad || !(x >= 0 && x <= 100);
            cfg->jitter_s = x * 1e-3;
        } else if (!std::strcmp(o, "--disc-r")) {
            bad = bad || !(x > 0 && x <= 0.05);
            cfg->disc_radius = x;
        } else { /* --face-px */
            bad = bad || x < 64 || x > 8192 || x != std::floor(x);
            cfg->face_px = (int)x;
        }
    }
    if (bad || errno || (end && *end && std::strcmp(o, "--dist"))) {
        std::fprintf(stderr, "bad value for %s: '%s'\n", o, v);
        return -1;
    }
    return 2;
}

} /* namespace rpr */

#endif /* RP_RENDER_CLI_HPP */
