/*
 * rigpose-timesync - each camera's clock offset from the rig's rotation, for free-running
 * cameras (docs/time.md).
 *
 * Reads the image source of a rigpose configuration file through the HAL (a replay folder, or
 * the V4L2 cameras themselves while the rig is turned by hand), feeds each camera's images with
 * its own stamps to a rate tracker (rp_timesync.hpp: the camera's rotation between consecutive
 * images, in cam1's frame through the extrinsics), and fits each camera's lag against the first
 * camera's. The lag is the offset of the camera's stamps (capture = stamp + offset, rp_ekf.h),
 * relative to the first camera's own configured offset: what `cameras[i].time_offset_s` should
 * say. Writes them as JSON (--json-out) for `rigpose-offsets --timesync-json F --write CONFIG`.
 *
 * usage: rigpose-timesync --config FILE [--sets N] [--max-lag-ms M] [--json-out FILE]
 *            [--rates-out FILE]
 * Exit status: 0 every camera's offset found; 1 some camera's could not be told (too little
 * rotation, too few images) or the output could not be written; 2 bad usage or configuration;
 * 3 the source failed to open.
 */
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "rigpose/rp_config.h"
#include "rigpose/rp_hal.h"
#include "rp_timesync.hpp"

namespace {

void usage(FILE *f)
{
    std::fprintf(f,
                 "usage: rigpose-timesync --config FILE [options]\n"
                 "  --config FILE     the rig's configuration (config/README.md): its cameras\n"
                 "                    (intrinsics, extrinsics) and its image source (replay or\n"
                 "                    v4l2; not sim). Turn the rig while it records: the fit\n"
                 "                    needs a rotation rate that varies\n"
                 "  --sets N          read at most N frame sets (default 600; a replay ends\n"
                 "                    earlier at its end)\n"
                 "  --max-lag-ms M    search offsets within +-M ms (default 200)\n"
                 "  --json-out FILE   write {\"cameras\": [...], \"time_offset_s\": [...],\n"
                 "                    \"sigma_s\": [...]} (null where not found), for\n"
                 "                    rigpose-offsets --timesync-json FILE --write CONFIG\n"
                 "  --rates-out FILE  every camera's rate samples: camera, stamp time s (the\n"
                 "                    interval's mid-point), w x y z rad/s in cam1's frame,\n"
                 "                    inliers (csv)\n");
}

}  // namespace

int main(int argc, char **argv)
{
    std::string config, json_out, rates_out;
    long sets_max = 600;
    double max_lag_ms = 200.0;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--help" || a == "-h") {
            usage(stdout);
            return 0;
        }
        if (i + 1 >= argc) {
            std::fprintf(stderr, "rigpose-timesync: %s: unknown option or missing value\n",
                         a.c_str());
            usage(stderr);
            return 2;
        }
        const char *v = argv[++i];
        if (a == "--config") {
            config = v;
        } else if (a == "--sets") {
            sets_max = std::strtol(v, nullptr, 10);
        } else if (a == "--max-lag-ms") {
            max_lag_ms = std::atof(v);
        } else if (a == "--json-out") {
            json_out = v;
        } else if (a == "--rates-out") {
            rates_out = v;
        } else {
            std::fprintf(stderr, "rigpose-timesync: %s: unknown option\n", a.c_str());
            usage(stderr);
            return 2;
        }
    }
    if (config.empty() || sets_max < 3 || !(max_lag_ms > 0.0 && max_lag_ms <= 5000.0)) {
        std::fprintf(stderr, "rigpose-timesync: need --config FILE, --sets >= 3, "
                             "--max-lag-ms in (0, 5000]\n");
        usage(stderr);
        return 2;
    }
    static rp_config_t cfg;
    char err[RP_CFG_ERR_MAX];
    if (rp_config_load(config.c_str(), &cfg, err, sizeof err) != RP_CFG_OK) {
        std::fprintf(stderr, "rigpose-timesync: %s\n", err);
        return 2;
    }
    if (cfg.hal.kind == RP_HAL_SRC_SIM || cfg.hal.kind == RP_HAL_SRC_LCM) {
        std::fprintf(stderr, "rigpose-timesync: %s: the source delivers features, not images: "
                             "give a replay or v4l2 source\n",
                     config.c_str());
        return 2;
    }
    cfg.hal.realtime = 0; /* a replay as fast as it reads */
    const int n = cfg.rig.n_cams;
    rp_hal_source_t *src = nullptr;
    if (rp_hal_open(&src, &cfg.hal) != RP_HAL_OK || rp_hal_start(src) != RP_HAL_OK) {
        std::fprintf(stderr, "rigpose-timesync: source: %s\n", rp_hal_errmsg(src));
        if (src) {
            rp_hal_close(src);
        }
        return 3;
    }
    std::vector<rpts::RateTracker> rt;
    for (int k = 0; k < n; ++k) {
        rt.emplace_back(cfg.rig.cam[k]);
    }
    static rp_hal_set_t set;
    long sets = 0, failed = 0;
    while (sets < sets_max) {
        const rp_hal_status_t st = rp_hal_grab(src, &set);
        if (st == RP_HAL_E_END) {
            break;
        }
        if (st != RP_HAL_OK) {
            std::fprintf(stderr, "rigpose-timesync: set lost (%s): %s\n", rp_hal_status_str(st),
                         rp_hal_errmsg(src));
            if (++failed >= 20) {
                std::fprintf(stderr, "rigpose-timesync: 20 failures in a row: giving up\n");
                break;
            }
            continue;
        }
        failed = 0;
        ++sets;
        for (int k = 0; k < n && k < set.n_cams; ++k) {
            const rp_hal_frame_t &f = set.cam[k];
            if (!f.img.data || (f.flags & RP_HAL_CAM_MISSING)) {
                rt[(size_t)k].restart(); /* the next image starts a new interval */
                continue;
            }
            const cv::Mat view(f.img.h, f.img.w, CV_8UC1, const_cast<uint8_t *>(f.img.data),
                               (size_t)f.img.stride);
            rt[(size_t)k].add(view, f.utime);
        }
    }
    rp_hal_close(src);

    if (!rates_out.empty()) {
        FILE *f = std::fopen(rates_out.c_str(), "w");
        if (!f) {
            std::fprintf(stderr, "rigpose-timesync: %s: cannot write\n", rates_out.c_str());
            return 1;
        }
        std::fprintf(f, "camera,t_s,wx,wy,wz,inliers\n");
        for (int k = 0; k < n; ++k) {
            for (const rpts::RateSample &r : rt[(size_t)k].samples()) {
                std::fprintf(f, "%s,%.6f,%.6f,%.6f,%.6f,%d\n", cfg.cam_name[k], r.t_s, r.w[0],
                             r.w[1], r.w[2], r.inliers);
            }
        }
        if (std::fclose(f) != 0) {
            std::fprintf(stderr, "rigpose-timesync: %s: write failed\n", rates_out.c_str());
            return 1;
        }
    }
    /* the first camera's configured offset: the lags are relative to its stamps */
    const double off0 = cfg.cam_time_offset_s[0];
    std::vector<double> off((size_t)n, 0.0), sd((size_t)n, INFINITY);
    off[0] = off0;
    sd[0] = 0.0;
    int rc = 0;
    std::printf("rigpose-timesync: %ld sets of %s; offsets relative to %s (capture = stamp + "
                "offset)\n",
                sets, config.c_str(), cfg.cam_name[0]);
    std::printf("%-12s %8s %12s %10s %12s %8s\n", "camera", "samples", "offset_ms", "sigma_ms",
                "configured", "snr");
    std::printf("%-12s %8zu %12.3f %10s %12.3f %8s\n", cfg.cam_name[0], rt[0].samples().size(),
                1e3 * off0, "(ref)", 1e3 * off0, "-");
    for (int k = 1; k < n; ++k) {
        rpts::OffsetFit fit;
        const bool ok = rpts::fit_offset(rt[0].samples(), rt[(size_t)k].samples(),
                                         1e-3 * max_lag_ms, 0.001, &fit);
        const double conf = cfg.cam_time_offset_s[k];
        if (ok && std::isfinite(fit.sigma_s)) {
            off[(size_t)k] = off0 + fit.offset_s;
            sd[(size_t)k] = fit.sigma_s;
            std::printf("%-12s %8zu %12.3f %10.3f %12.3f %8.1f\n", cfg.cam_name[k],
                        rt[(size_t)k].samples().size(), 1e3 * off[(size_t)k], 1e3 * fit.sigma_s,
                        1e3 * conf, fit.snr);
        } else {
            std::printf("%-12s %8zu %12s %10s %12.3f %8.1f  (not found: %s)\n", cfg.cam_name[k],
                        rt[(size_t)k].samples().size(), "-", "-", 1e3 * conf, fit.snr,
                        ok ? "its rate and the reference's disagree by more than a third of "
                             "the rate's variation: too little rotation, or a scene too near "
                             "for its motion"
                           : "too few rate samples overlap");
            rc = 1;
        }
    }
    if (!json_out.empty()) {
        FILE *f = std::fopen(json_out.c_str(), "w");
        if (!f) {
            std::fprintf(stderr, "rigpose-timesync: %s: cannot write\n", json_out.c_str());
            return 1;
        }
        std::fprintf(f, "{\"config\": \"%s\", \"sets\": %ld, \"cameras\": [", config.c_str(), sets);
        for (int k = 0; k < n; ++k) {
            std::fprintf(f, "%s\"%s\"", k ? ", " : "", cfg.cam_name[k]);
        }
        std::fprintf(f, "], \"time_offset_s\": [");
        for (int k = 0; k < n; ++k) {
            if (std::isfinite(sd[(size_t)k])) {
                std::fprintf(f, "%s%.9f", k ? ", " : "", off[(size_t)k]);
            } else {
                std::fprintf(f, "%snull", k ? ", " : "");
            }
        }
        std::fprintf(f, "], \"sigma_s\": [");
        for (int k = 0; k < n; ++k) {
            if (std::isfinite(sd[(size_t)k])) {
                std::fprintf(f, "%s%.9f", k ? ", " : "", sd[(size_t)k]);
            } else {
                std::fprintf(f, "%snull", k ? ", " : "");
            }
        }
        std::fprintf(f, "]}\n");
        if (std::fclose(f) != 0) {
            std::fprintf(stderr, "rigpose-timesync: %s: write failed\n", json_out.c_str());
            return 1;
        }
    }
    return rc;
}
