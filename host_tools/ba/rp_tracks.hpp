/*
 * rp_tracks.hpp - a run's tracks as a text file: the rig, and per frame set the features the
 * estimator received (rp_frameset_t), the estimator's pose and the ground truth. Written by
 * rigpose-realdata --tracks-out (the frame sets rp_pipe_frameset returns after each
 * rp_pipe_step), read by rigpose-ba --tracks: the batch optimum over exactly what rigpose saw.
 * Host only, C++, no OpenCV.
 *
 * Format (one record per line, '#' comments, numbers in C locale, "%.17g" for doubles):
 *   rigpose-tracks 1
 *   name NAME                        the clip (figure prefix)
 *   cam K W H fx fy cx cy k1 k2 p1 p2 k3 R00 R01 .. R22 D0 D1 D2
 *                                    rig camera K (rp_rig.h: R_k camera-to-cam1, row-major;
 *                                    D_k in cam1's frame, m; intrinsics px, OpenCV distortion)
 *   frame J UTIME                    frame set J (0, 1, ...), capture time (us)
 *   est tx ty tz alpha beta gamma FLAGS   the estimator's pose of cam1 in the world (m, rad;
 *                                    R = Rz(gamma) Ry(beta) Rx(alpha)), its RP_EST_* flags
 *   truth tx ty tz alpha beta gamma  the ground truth, same convention (optional)
 *   f K ID U V                       a feature of camera K: track id, distorted pixel (u, v)
 * Lines after a "frame" line belong to it. The world is cam1 at frame 0.
 */
#ifndef RP_TRACKS_HPP
#define RP_TRACKS_HPP

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "rigpose/rp_frame.h"
#include "rigpose/rp_rig.h"

namespace rptk {

struct Feat {
    uint8_t cam;
    uint32_t id;
    double uv[2]; /* px, distorted */
};

struct Frame {
    int64_t utime = 0;
    double est[6] = {0, 0, 0, 0, 0, 0};   /* m, rad */
    uint32_t est_flags = 0;
    bool has_truth = false;
    double truth[6] = {0, 0, 0, 0, 0, 0}; /* m, rad */
    std::vector<Feat> f;
};

struct Tracks {
    std::string name;
    rp_rig_t rig;
    std::vector<Frame> frames;
};

/* Writer: header (name, rig) once, then one frame per call. Each returns false with errno's
 * text in *why when the write fails. */
bool write_header(std::FILE *out, const std::string &name, const rp_rig_t &rig, std::string *why);
bool write_frame(std::FILE *out, uint32_t j, const rp_frameset_t &fs, const rp_estimate_t &est,
                 const double *truth /* 6 or NULL */, std::string *why);

/* Reader: false with "FILE:LINE: what" in *why on a malformed or missing file (unknown record,
 * wrong count of numbers, a camera index over the rig, frames out of order, no frame). */
bool read(const std::string &path, Tracks *out, std::string *why);

}  // namespace rptk

#endif /* RP_TRACKS_HPP */
