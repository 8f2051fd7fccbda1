/*
 * rp_tracks.cpp - the tracks file of rp_tracks.hpp: writer and reader.
 */
#include "rp_tracks.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace rptk {

static bool io_fail(std::FILE *out, std::string *why)
{
    if (std::ferror(out)) {
        *why = std::string("write failed: ") + std::strerror(errno);
        return false;
    }
    return true;
}

bool write_header(std::FILE *out, const std::string &name, const rp_rig_t &rig, std::string *why)
{
    std::fprintf(out, "rigpose-tracks 1\nname %s\n", name.c_str());
    for (unsigned k = 0; k < rig.n_cams; ++k) {
        const rp_rig_cam_t &c = rig.cam[k];
        std::fprintf(out, "cam %u %u %u %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g", k,
                     (unsigned)c.cam.width, (unsigned)c.cam.height, (double)c.cam.fx,
                     (double)c.cam.fy, (double)c.cam.cx, (double)c.cam.cy, (double)c.cam.k1,
                     (double)c.cam.k2, (double)c.cam.p1, (double)c.cam.p2, (double)c.cam.k3);
        for (int i = 0; i < 9; ++i) {
            std::fprintf(out, " %.17g", (double)c.R[i]);
        }
        for (int i = 0; i < 3; ++i) {
            std::fprintf(out, " %.17g", (double)c.D[i]);
        }
        std::fprintf(out, "\n");
    }
    return io_fail(out, why);
}

bool write_frame(std::FILE *out, uint32_t j, const rp_frameset_t &fs, const rp_estimate_t &est,
                 const double *truth, std::string *why)
{
    std::fprintf(out, "frame %u %lld\nest", j, (long long)fs.utime);
    for (int i = 0; i < 6; ++i) {
        std::fprintf(out, " %.17g", (double)est.p[i]);
    }
    std::fprintf(out, " %u\n", (unsigned)est.flags);
    if (truth) {
        std::fprintf(out, "truth %.17g %.17g %.17g %.17g %.17g %.17g\n", truth[0], truth[1],
                     truth[2], truth[3], truth[4], truth[5]);
    }
    for (unsigned k = 0; k < RP_MAX_CAMS; ++k) {
        for (unsigned i = 0; i < fs.n[k]; ++i) {
            std::fprintf(out, "f %u %u %.9g %.9g\n", k, (unsigned)fs.f[k][i].id,
                         (double)fs.f[k][i].uv[0], (double)fs.f[k][i].uv[1]);
        }
    }
    return io_fail(out, why);
}

bool read(const std::string &path, Tracks *out, std::string *why)
{
    std::ifstream in(path);
    if (!in) {
        *why = path + ": cannot open";
        return false;
    }
    *out = Tracks();
    std::memset(&out->rig, 0, sizeof out->rig);
    std::string line;
    size_t ln = 0;
    bool header = false;
    auto fail = [&](const std::string &what) {
        *why = path + ":" + std::to_string(ln) + ": " + what;
        return false;
    };
    while (std::getline(in, line)) {
        ++ln;
        if (line.empty() || line[0] == '#') {
            continue;
        }
        std::istringstream ss(line);
        std::string rec;
        ss >> rec;
        if (!header) {
            int v = 0;
            if (rec != "rigpose-tracks" || !(ss >> v) || v != 1) {
                return fail("not a tracks file (first line 'rigpose-tracks 1')");
            }
            header = true;
            continue;
        }
        if (rec == "name") {
            ss >> out->name;
        } else if (rec == "cam") {
            unsigned k, w, h;
            double v[9 + 9 + 3];
            if (!(ss >> k >> w >> h)) {
                return fail("cam: K W H expected");
            }
            for (double &x : v) {
                if (!(ss >> x)) {
                    return fail("cam: 21 numbers after K W H expected");
                }
            }
            if (k >= RP_MAX_CAMS || k != out->rig.n_cams || w == 0 || h == 0 || w > 65535 ||
                h > 65535) {
                return fail("cam: cameras 0, 1, ... in order, under RP_MAX_CAMS, size > 0");
            }
            rp_rig_cam_t &c = out->rig.cam[k];
            c.cam = rp_cam_pinhole((uint16_t)w, (uint16_t)h, (rp_real)v[0], (rp_real)v[1],
                                   (rp_real)v[2], (rp_real)v[3]);
            c.cam.k1 = (rp_real)v[4];
            c.cam.k2 = (rp_real)v[5];
            c.cam.p1 = (rp_real)v[6];
            c.cam.p2 = (rp_real)v[7];
            c.cam.k3 = (rp_real)v[8];
            for (int i = 0; i < 9; ++i) {
                c.R[i] = (rp_real)v[9 + i];
            }
            for (int i = 0; i < 3; ++i) {
                c.D[i] = (rp_real)v[18 + i];
            }
            out->rig.n_cams = (uint8_t)(k + 1);
        } else if (rec == "frame") {
            unsigned j;
            long long t;
            if (!(ss >> j >> t) || j != out->frames.size()) {
                return fail("frame: J UTIME with J = 0, 1, ... in order");
            }
            if (!out->frames.empty() && t <= out->frames.back().utime) {
                return fail("frame: utime not after the previous frame's");
            }
            out->frames.emplace_back();
            out->frames.back().utime = (int64_t)t;
        } else if (rec == "est" || rec == "truth" || rec == "f") {
            if (out->frames.empty()) {
                return fail(rec + " before the first frame line");
            }
            Frame &fr = out->frames.back();
            if (rec == "f") {
                unsigned k, id;
                Feat f;
                if (!(ss >> k >> id >> f.uv[0] >> f.uv[1]) || k >= out->rig.n_cams) {
                    return fail("f: K ID U V with K a camera of the rig");
                }
                f.cam = (uint8_t)k;
                f.id = id;
                fr.f.push_back(f);
            } else {
                double *p = rec == "est" ? fr.est : fr.truth;
                for (int i = 0; i < 6; ++i) {
                    if (!(ss >> p[i])) {
                        return fail(rec + ": 6 numbers expected");
                    }
                }
                if (rec == "est") {
                    unsigned fl;
                    if (!(ss >> fl)) {
                        return fail("est: FLAGS expected after the pose");
                    }
                    fr.est_flags = fl;
                } else {
                    fr.has_truth = true;
                }
            }
        } else {
            return fail("unknown record '" + rec + "'");
        }
    }
    if (!header) {
        ln = 0;
        return fail("empty file");
    }
    if (out->rig.n_cams == 0 || out->frames.empty()) {
        return fail("no camera or no frame");
    }
    if (rp_rig_check(&out->rig) != RP_OK) {
        return fail("the rig is not usable (rp_rig_check)");
    }
    return true;
}

}  // namespace rptk
