/*
 * rp_ba.hpp - the offline optimum as a yardstick: a full bundle adjustment of a whole run with
 * the rig model, and the Cramér-Rao bound of the same problem. Host only (C++, Ceres Solver,
 * Eigen); never linked into core/ or the daemon.
 *
 * The problem (the paper's eq. 2): one pose per frame set, p_j = (d_j, R_j) of cam1 in the
 * world; every landmark M_i free (one per track id: a stereo pair's two cameras share ids);
 * camera k of the rig fixed at (R_k, D_k) in cam1's frame with its intrinsics and distortion.
 * Observation of landmark i by camera k in frame j, pixel z (px):
 *     P = R_k^T (R_j^T (M_i - d_j) - D_k),   r = (proj_k(P) - z) / sigma_px,
 * minimised as sum rho(|r|^2) with a robust rho (Huber or Cauchy, threshold in sigmas). The
 * gauge is fixed at the first frame: p_0 = (0, I), constant (the world is cam1 at frame 0).
 * A landmark seen in a single frame carries no information on the poses (its position absorbs
 * its observations whatever the pose) and is left out; so is a frame without any observation
 * of a kept landmark (its pose stays at its initial value; `Result::constrained` says which).
 *
 * The bound: with Gaussian pixel noise of sigma_px and the observations of the problem, the
 * Fisher information at the true parameters is J^T J / sigma^2 (J: d proj / d (poses, landmarks)
 * in the estimators' chart of rp_rig.h: translation, world-frame rotation vector). Landmarks are
 * eliminated (Schur complement, exact: a pseudo-inverse where a landmark's 3x3 block is
 * singular), frame 0 is held fixed, and the inverse of the reduced information is the bound on
 * the covariance of any unbiased estimate of the poses from these measurements. It is a bound
 * for a batch (smoothing) estimator: a causal filter uses fewer measurements per pose.
 */
#ifndef RP_BA_HPP
#define RP_BA_HPP

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "rigpose/rp_rig.h"

namespace rpba {

typedef std::array<double, 6> Pose6; /* [tx ty tz alpha beta gamma], m and rad (rp_rig.h) */
typedef std::array<double, 3> Vec3;
typedef std::array<double, 36> Cov6; /* row-major 6x6 */

struct Obs {
    uint32_t frame;
    uint8_t cam;   /* rig camera */
    uint32_t id;   /* landmark (track id) */
    double uv[2];  /* px, distorted, as measured */
};

struct Problem {
    rp_rig_t rig;
    size_t n_frames = 0;
    std::vector<Obs> obs;
};

enum class Loss { none, huber, cauchy };

struct Options {
    double sigma_px = 1.0;   /* pixel noise: residuals are in sigmas */
    Loss loss = Loss::huber;
    double loss_scale = 2.0; /* threshold of the robust loss, in sigmas */
    int max_iterations = 200;  /* per round */
    double reject_sigma = 0;   /* > 0: after solving, observations whose reprojection error
                                * |uv - z| exceeds this many sigmas are left out and the problem
                                * solved again (up to 3 more rounds, until none is); 0: never */
    int threads = 1;
    double fallback_depth = 0; /* m: a landmark whose rays are nearly parallel (smallest
                                * eigenvalue of sum (I - r r^T) under 1e-6 per ray, about 0.1
                                * degree of parallax) or meet behind one of its cameras starts
                                * at this depth along its first ray; 0: the median depth of
                                * the others */
};

struct Result {
    std::vector<Pose6> pose;       /* per frame, the optimum (frame 0 = identity) */
    std::vector<char> constrained; /* per frame: 1 if it has observations of kept landmarks */
    size_t n_landmarks = 0;        /* kept: seen in at least two frames */
    size_t n_obs = 0;              /* their observations */
    size_t n_fallback = 0;         /* landmarks started at the fallback depth */
    size_t n_obs_dropped = 0;      /* observations of those that put the start behind their
                                    * camera: left out (with the landmark when what remains
                                    * spans one frame) */
    size_t n_obs_rejected = 0;     /* observations left out by the rejection (Options) */
    double rms_px_initial = 0;     /* RMS reprojection error (px per coordinate) of the
                                    * observations in the problem, at the start and at the end */
    double rms_px_final = 0;
    double median_px_final = 0;    /* median reprojection error |uv - z| (px) at the end */
    int iterations = 0;
    bool converged = false;
    double seconds = 0;
};

/* The batch optimum, started from `init` (per frame; typically the estimator's trajectory)
 * with every landmark triangulated from it (least-squares intersection of its rays). False with
 * a reason in *why: sizes that disagree, no usable landmark, Ceres refusing the problem. */
bool solve(const Problem &pb, const std::vector<Pose6> &init, const Options &o, Result *res,
           std::string *why);

/* The Cramér-Rao bound of `pb` at the true poses and landmarks (landmarks by id; every
 * observed id with at least two frames must be there), for Gaussian noise of sigma_px: per
 * frame the 6x6 covariance bound in the chart [dt (m, world); w (rad, world-frame rotation
 * vector)], frame 0 zero (the gauge). Frames without information get NaN. False with a reason
 * if the reduced information is not positive definite. */
bool crb(const Problem &pb, const std::vector<Pose6> &truth,
         const std::vector<std::pair<uint32_t, Vec3>> &landmarks, double sigma_px,
         std::vector<Cov6> *cov, std::string *why);

/* The covariance of the angles (alpha, beta, gamma) from that of the rotation vector w at
 * the pose's rotation: C_abg = A C_w A^T, A = d abg / d w (central differences). */
void angles_cov(const Pose6 &p, const double C_w[9], double C_abg[9]);

/* The pixel of world point M seen by camera k at pose p, by the same templated code as the
 * Ceres residual (for the test against the core's rp_rig_project). False behind the camera. */
bool project(const rp_rig_t &rig, uint8_t k, const Pose6 &p, const Vec3 &M, double uv[2]);

}  // namespace rpba

#endif /* RP_BA_HPP */
