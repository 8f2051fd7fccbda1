/*
 * rp_mirror.cpp - the mirror image of a stereo sequence and a writer of KITTI / EuRoC folders
 * (rp_mirror.hpp says the geometry).
 */
#include "rp_mirror.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "rigpose/rp_rot.h"

namespace fs = std::filesystem;

namespace rprd {

namespace {

Pose rig_pose(const rp_rig_cam_t &c)
{
    Pose T;
    for (int i = 0; i < 9; ++i) {
        T.R[i] = (double)c.R[i];
    }
    for (int i = 0; i < 3; ++i) {
        T.t[i] = (double)c.D[i];
    }
    return T;
}

void set_rig_pose(rp_rig_cam_t *c, const Pose &T)
{
    for (int i = 0; i < 9; ++i) {
        c->R[i] = (rp_real)T.R[i];
    }
    for (int i = 0; i < 3; ++i) {
        c->D[i] = (rp_real)T.t[i];
    }
}

bool fail(std::string *err, const std::string &msg)
{
    if (err) {
        *err = msg;
    }
    return false;
}

/* Copy an image, flipped left-right if asked. */
bool copy_image(const std::string &from, const std::string &to, bool flip, std::string *err)
{
    cv::Mat im = cv::imread(from, cv::IMREAD_UNCHANGED);
    if (im.empty()) {
        return fail(err, from + ": cannot read");
    }
    if (flip) {
        cv::flip(im, im, 1);
    }
    if (!cv::imwrite(to, im)) {
        return fail(err, to + ": cannot write");
    }
    return true;
}

bool write_kitti(const Sequence &seq, const std::string &dir, bool flip, std::string *err)
{
    const rp_rig_cam_t &c0 = seq.rig.cam[0], &c1 = seq.rig.cam[1];
    const double b = (double)c1.D[0];
    bool rectified = b > 0.0 && c1.D[1] == 0 && c1.D[2] == 0;
    for (int i = 0; i < 9; ++i) {
        rectified = rectified && c1.R[i] == (i % 4 == 0 ? 1 : 0);
    }
    for (const rp_camera_t *c : {&c0.cam, &c1.cam}) {
        rectified = rectified && c->k1 == 0 && c->k2 == 0 && c->p1 == 0 && c->p2 == 0 && c->k3 == 0;
    }
    if (!rectified) {
        return fail(err, "KITTI folder: the pair must be rectified (camera 1 at (b > 0, 0, 0), no "
                         "rotation, no distortion)");
    }
    std::error_code ec;
    fs::create_directories(dir + "/left", ec);
    fs::create_directories(dir + "/right", ec);
    if (ec) {
        return fail(err, dir + ": " + ec.message());
    }
    FILE *fc = std::fopen((dir + "/calib.txt").c_str(), "w");
    FILE *fp = std::fopen((dir + "/poses.txt").c_str(), "w");
    FILE *ft = std::fopen((dir + "/times.txt").c_str(), "w");
    bool ok = fc && fp && ft;
    if (ok) {
        for (int k = 0; k < 2; ++k) {
            const rp_camera_t &c = seq.rig.cam[k].cam;
            std::fprintf(fc, "P%d: %.12e 0 %.12e %.12e 0 %.12e %.12e 0 0 0 1 0\n", k, (double)c.fx,
                         (double)c.cx, k ? -(double)c.fx * b : 0.0, (double)c.fy, (double)c.cy);
        }
    }
    for (size_t j = 0; ok && j < seq.utime.size(); ++j) {
        const Pose &T = seq.truth[j];
        std::fprintf(fp, "%.12e %.12e %.12e %.12e %.12e %.12e %.12e %.12e %.12e %.12e %.12e %.12e\n",
                     T.R[0], T.R[1], T.R[2], T.t[0], T.R[3], T.R[4], T.R[5], T.t[1], T.R[6],
                     T.R[7], T.R[8], T.t[2]);
        std::fprintf(ft, "%.6f\n", (double)(seq.utime[j] - seq.utime[0]) * 1e-6);
        char name[32];
        std::snprintf(name, sizeof name, "%06zu.png", j);
        ok = copy_image(seq.img[0][j], dir + "/left/" + name, flip, err) &&
             copy_image(seq.img[1][j], dir + "/right/" + name, flip, err);
    }
    for (FILE *f : {fc, fp, ft}) {
        ok = (f && std::fclose(f) == 0) && ok;
    }
    return ok || fail(err, err && !err->empty() ? *err : dir + ": cannot write");
}

bool write_euroc(const Sequence &seq, const std::string &dir, bool flip, std::string *err)
{
    bool ok = true;
    for (int k = 0; k < 2 && ok; ++k) {
        const std::string cdir = dir + "/cam" + std::to_string(k);
        std::error_code ec;
        fs::create_directories(cdir + "/data", ec);
        if (ec) {
            return fail(err, cdir + ": " + ec.message());
        }
        const rp_rig_cam_t &rc = seq.rig.cam[k];
        const rp_camera_t &c = rc.cam;
        FILE *fy = std::fopen((cdir + "/sensor.yaml").c_str(), "w");
        FILE *fl = std::fopen((cdir + "/data.csv").c_str(), "w");
        ok = fy && fl;
        if (ok) {
            std::fprintf(fy,
                         "# written by rigpose-realdata (rp_mirror.cpp); the body frame is cam0's\n"
                         "sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [");
            for (int r = 0; r < 3; ++r) {
                std::fprintf(fy, "%.15g, %.15g, %.15g, %.15g,\n         ", (double)rc.R[3 * r],
                             (double)rc.R[3 * r + 1], (double)rc.R[3 * r + 2], (double)rc.D[r]);
            }
            std::fprintf(fy,
                         "0.0, 0.0, 0.0, 1.0]\nresolution: [%u, %u]\ncamera_model: pinhole\n"
                         "intrinsics: [%.15g, %.15g, %.15g, %.15g]\n"
                         "distortion_model: radial-tangential\n"
                         "distortion_coefficients: [%.15g, %.15g, %.15g, %.15g, %.15g]\n",
                         (unsigned)c.width, (unsigned)c.height, (double)c.fx, (double)c.fy,
                         (double)c.cx, (double)c.cy, (double)c.k1, (double)c.k2, (double)c.p1,
                         (double)c.p2, (double)c.k3);
            std::fprintf(fl, "#timestamp [ns],filename\n");
        }
        for (size_t j = 0; ok && j < seq.utime.size(); ++j) {
            const long long t_ns = (long long)seq.utime[j] * 1000;
            const std::string name = std::to_string(t_ns) + ".png";
            std::fprintf(fl, "%lld,%s\n", t_ns, name.c_str());
            ok = copy_image(seq.img[k][j], cdir + "/data/" + name, flip, err);
        }
        for (FILE *f : {fy, fl}) {
            ok = (f && std::fclose(f) == 0) && ok;
        }
    }
    FILE *fg = ok ? std::fopen((dir + "/groundtruth.txt").c_str(), "w") : nullptr;
    ok = ok && fg;
    if (ok) {
        std::fprintf(fg, "# timestamp(s) tx ty tz qx qy qz qw (cam0's pose: the body is cam0)\n");
        for (size_t j = 0; j < seq.utime.size(); ++j) {
            const Pose &T = seq.truth[j];
            rp_real R[9], q[4];
            for (int i = 0; i < 9; ++i) {
                R[i] = (rp_real)T.R[i];
            }
            rp_rot_to_quat(R, q); /* q = (w, x, y, z) */
            std::fprintf(fg, "%lld.%06lld %.15g %.15g %.15g %.15g %.15g %.15g %.15g\n",
                         (long long)(seq.utime[j] / 1000000), (long long)(seq.utime[j] % 1000000),
                         T.t[0], T.t[1], T.t[2], (double)q[1], (double)q[2], (double)q[3],
                         (double)q[0]);
        }
    }
    ok = (fg && std::fclose(fg) == 0) && ok;
    return ok || fail(err, err && !err->empty() ? *err : dir + ": cannot write");
}

}  // namespace

rp_camera_t mirror_camera(const rp_camera_t &c)
{
    rp_camera_t m = c;
    m.cx = (rp_real)(c.width - 1) - c.cx;
    m.p2 = -c.p2;
    return m;
}

Pose mirror_pose(const Pose &T)
{
    Pose m = T;
    /* (M R M)_rc = s_r s_c R_rc, (M t)_r = s_r t_r, s = (-1, 1, 1) */
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            m.R[3 * r + c] = ((r == 0) != (c == 0) ? -1.0 : 1.0) * T.R[3 * r + c];
        }
    }
    m.t[0] = -T.t[0];
    return m;
}

Sequence mirror_sequence(const Sequence &seq)
{
    Sequence m = seq;
    const Pose E = rig_pose(seq.rig.cam[1]); /* right camera in the left camera */
    const Pose Ei = pose_inv(E);
    /* camera 0: the original right camera's mirror image, the reference (identity) */
    m.rig.cam[0] = seq.rig.cam[1];
    m.rig.cam[0].cam = mirror_camera(seq.rig.cam[1].cam);
    set_rig_pose(&m.rig.cam[0], Pose());
    /* camera 1: the original left camera's mirror image, at M E^-1 M in camera 0 */
    m.rig.cam[1] = seq.rig.cam[0];
    m.rig.cam[1].cam = mirror_camera(seq.rig.cam[0].cam);
    set_rig_pose(&m.rig.cam[1], mirror_pose(Ei));
    for (size_t j = 0; j < seq.truth.size(); ++j) {
        m.truth[j] = mirror_pose(pose_mul(pose_mul(Ei, seq.truth[j]), E));
    }
    m.img[0] = seq.img[1];
    m.img[1] = seq.img[0];
    m.name = seq.name + "_mirror";
    m.notes.clear();
    return m;
}

bool write_sequence(const Sequence &seq, const std::string &dir, bool flip, std::string *err)
{
    if (seq.rig.n_cams != 2 || seq.utime.empty()) {
        return fail(err, "write_sequence: a stereo pair with frames expected");
    }
    return seq.format == Format::KITTI ? write_kitti(seq, dir, flip, err)
                                       : write_euroc(seq, dir, flip, err);
}

}  // namespace rprd
