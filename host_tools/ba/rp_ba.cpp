/*
 * rp_ba.cpp - bundle adjustment with the rig model on Ceres, and its Cramér-Rao bound
 * (rp_ba.hpp).
 */
#include "rp_ba.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "rigpose/rp_camera.h"
#include "rigpose/rp_rot.h"

namespace rpba {

namespace {

/* Camera k of the rig as the residual needs it (double, whatever rp_real is). */
struct CamModel {
    double R[9]; /* R_k, camera-to-cam1, row-major */
    double D[3]; /* m, cam1's frame */
    double fx, fy, cx, cy, k1, k2, p1, p2, k3;
};

CamModel cam_model(const rp_rig_t &rig, uint8_t k)
{
    const rp_rig_cam_t &c = rig.cam[k];
    CamModel m;
    for (int i = 0; i < 9; ++i) {
        m.R[i] = (double)c.R[i];
    }
    for (int i = 0; i < 3; ++i) {
        m.D[i] = (double)c.D[i];
    }
    m.fx = (double)c.cam.fx;
    m.fy = (double)c.cam.fy;
    m.cx = (double)c.cam.cx;
    m.cy = (double)c.cam.cy;
    m.k1 = (double)c.cam.k1;
    m.k2 = (double)c.cam.k2;
    m.p1 = (double)c.cam.p1;
    m.p2 = (double)c.cam.p2;
    m.k3 = (double)c.cam.k3;
    return m;
}

/* Eq. 2 and the camera model of rp_camera.h: P = R_k^T (R_j^T (M - d_j) - D_k), then pinhole
 * and OpenCV's radial-tangential distortion. q: R_j as a unit quaternion (w, x, y, z). False
 * when P is less than 1 mm in front of the camera (as RP_MIN_DEPTH). */
template <typename T>
bool project_t(const CamModel &c, const T q[4], const T d[3], const T M[3], T uv[2])
{
    const T a[3] = {M[0] - d[0], M[1] - d[1], M[2] - d[2]};
    const T qc[4] = {q[0], -q[1], -q[2], -q[3]}; /* R_j^T */
    T b[3];
    ceres::UnitQuaternionRotatePoint(qc, a, b);
    b[0] -= c.D[0];
    b[1] -= c.D[1];
    b[2] -= c.D[2];
    T P[3];
    for (int i = 0; i < 3; ++i) {
        P[i] = c.R[i] * b[0] + c.R[3 + i] * b[1] + c.R[6 + i] * b[2]; /* R_k^T b */
    }
    if (!(P[2] > T(1e-3))) {
        return false;
    }
    const T x = P[0] / P[2], y = P[1] / P[2];
    const T r2 = x * x + y * y;
    const T radial = T(1.0) + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
    const T xd = x * radial + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x);
    const T yd = y * radial + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y;
    uv[0] = c.fx * xd + c.cx;
    uv[1] = c.fy * yd + c.cy;
    return true;
}

/* One observation's residual in sigmas: parameter blocks q_j (4), d_j (3), M_i (3). */
struct RigReprojection {
    CamModel c;
    double z[2];
    double inv_sigma;
    template <typename T>
    bool operator()(const T *q, const T *d, const T *M, T *r) const
    {
        T uv[2];
        if (!project_t(c, q, d, M, uv)) {
            return false;
        }
        r[0] = (uv[0] - z[0]) * inv_sigma;
        r[1] = (uv[1] - z[1]) * inv_sigma;
        return true;
    }
};

void pose_to_qd(const Pose6 &p, double q[4], double d[3])
{
    rp_real abg[3] = {(rp_real)p[3], (rp_real)p[4], (rp_real)p[5]}, R[9], qq[4];
    rp_rot_from_angles(abg, R);
    rp_rot_to_quat(R, qq);
    for (int i = 0; i < 4; ++i) {
        q[i] = (double)qq[i];
    }
    for (int i = 0; i < 3; ++i) {
        d[i] = p[i];
    }
}

Pose6 qd_to_pose(const double q[4], const double d[3])
{
    rp_real qq[4] = {(rp_real)q[0], (rp_real)q[1], (rp_real)q[2], (rp_real)q[3]}, R[9], abg[3];
    Pose6 p = {d[0], d[1], d[2], 0, 0, 0};
    if (rp_rot_from_quat(qq, R) == RP_OK && rp_rot_to_angles(R, abg) == RP_OK) {
        p[3] = (double)abg[0];
        p[4] = (double)abg[1];
        p[5] = (double)abg[2];
    }
    return p;
}

Eigen::Matrix3d rot_of(const Pose6 &p)
{
    rp_real abg[3] = {(rp_real)p[3], (rp_real)p[4], (rp_real)p[5]}, R[9];
    rp_rot_from_angles(abg, R);
    Eigen::Matrix3d m;
    for (int i = 0; i < 9; ++i) {
        m(i / 3, i % 3) = (double)R[i];
    }
    return m;
}

/* Observations grouped by landmark, in id order; only landmarks seen in >= 2 frames. */
std::map<uint32_t, std::vector<size_t>> landmark_obs(const Problem &pb)
{
    std::map<uint32_t, std::vector<size_t>> by_id;
    for (size_t i = 0; i < pb.obs.size(); ++i) {
        by_id[pb.obs[i].id].push_back(i);
    }
    for (auto it = by_id.begin(); it != by_id.end();) {
        uint32_t f0 = pb.obs[it->second[0]].frame;
        bool two = false;
        for (size_t i : it->second) {
            two = two || pb.obs[i].frame != f0;
        }
        it = two ? std::next(it) : by_id.erase(it);
    }
    return by_id;
}

}  // namespace

bool project(const rp_rig_t &rig, uint8_t k, const Pose6 &p, const Vec3 &M, double uv[2])
{
    double q[4], d[3];
    pose_to_qd(p, q, d);
    return project_t(cam_model(rig, k), q, d, M.data(), uv);
}

bool solve(const Problem &pb, const std::vector<Pose6> &init, const Options &o, Result *res,
           std::string *why)
{
    const auto t0 = std::chrono::steady_clock::now();
    if (init.size() != pb.n_frames || pb.n_frames < 2 || !(o.sigma_px > 0)) {
        *why = "solve: " + std::to_string(init.size()) + " initial poses for " +
               std::to_string(pb.n_frames) + " frames (at least 2), sigma > 0";
        return false;
    }
    for (const Obs &ob : pb.obs) {
        if (ob.frame >= pb.n_frames || ob.cam >= pb.rig.n_cams) {
            *why = "solve: an observation's frame or camera is out of range";
            return false;
        }
    }
    *res = Result();
    const std::map<uint32_t, std::vector<size_t>> by_id = landmark_obs(pb);
    std::vector<CamModel> cams;
    for (uint8_t k = 0; k < pb.rig.n_cams; ++k) {
        cams.push_back(cam_model(pb.rig, k));
    }

    /* Poses: the initial trajectory; frame 0 is the gauge, the identity. */
    std::vector<std::array<double, 4>> q(pb.n_frames);
    std::vector<Vec3> d(pb.n_frames);
    for (size_t j = 0; j < pb.n_frames; ++j) {
        pose_to_qd(j == 0 ? Pose6{{0, 0, 0, 0, 0, 0}} : init[j], q[j].data(), d[j].data());
    }

    /* Landmarks: least-squares intersection of their rays, sum_i (I - r_i r_i^T)(M - c_i) = 0,
     * c_i the camera centre d_j + R_j D_k, r_i the unit ray R_j R_k (xn, yn, 1) / |.|. A
     * landmark whose normal matrix is near singular (rays nearly parallel: smallest eigenvalue
     * under 1e-6 per ray, about 0.1 degree of parallax) or whose intersection lies behind one
     * of its cameras starts at the fallback depth along its first ray. */
    std::vector<uint32_t> ids;
    std::vector<Vec3> M;
    std::vector<std::vector<size_t>> lm_obs;
    std::vector<char> ok_lm;
    std::vector<double> depths;
    struct Ray {
        Eigen::Vector3d c, r; /* centre; R_j R_k (xn, yn, 1): the point at depth z is c + z r */
    };
    std::vector<Eigen::Matrix3d> Rj_of(pb.n_frames);
    for (size_t j = 0; j < pb.n_frames; ++j) {
        Rj_of[j] = rot_of(j == 0 ? Pose6{{0, 0, 0, 0, 0, 0}} : init[j]);
    }
    std::vector<Ray> first_ray;
    for (const auto &kv : by_id) {
        Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
        Eigen::Vector3d b = Eigen::Vector3d::Zero();
        std::vector<size_t> used;
        Ray fr{};
        for (size_t i : kv.second) {
            const Obs &ob = pb.obs[i];
            rp_real uv[2] = {(rp_real)ob.uv[0], (rp_real)ob.uv[1]}, xn[2];
            if (rp_cam_unproject(&pb.rig.cam[ob.cam].cam, uv, xn) != RP_OK) {
                continue; /* no ray: the observation is not used */
            }
            const Eigen::Matrix3d &Rj = Rj_of[ob.frame];
            Eigen::Matrix3d Rk;
            for (int e = 0; e < 9; ++e) {
                Rk(e / 3, e % 3) = cams[ob.cam].R[e];
            }
            const Eigen::Vector3d Dk(cams[ob.cam].D[0], cams[ob.cam].D[1], cams[ob.cam].D[2]);
            const Eigen::Vector3d c = Eigen::Vector3d(d[ob.frame][0], d[ob.frame][1],
                                                      d[ob.frame][2]) + Rj * Dk;
            const Eigen::Vector3d cam_ray((double)xn[0], (double)xn[1], 1.0);
            const Eigen::Vector3d r = (Rj * Rk * cam_ray).normalized();
            if (used.empty()) {
                fr = Ray{c, Rj * Rk * cam_ray};
            }
            const Eigen::Matrix3d Pn = Eigen::Matrix3d::Identity() - r * r.transpose();
            A += Pn;
            b += Pn * c;
            used.push_back(i);
        }
        if (used.empty()) {
            continue;
        }
        uint32_t f0 = pb.obs[used[0]].frame;
        bool two = false;
        for (size_t i : used) {
            two = two || pb.obs[i].frame != f0;
        }
        if (!two) {
            continue;
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(A);
        bool good = es.eigenvalues()(0) > 1e-6 * (double)used.size();
        Vec3 m = {0, 0, 0};
        if (good) {
            const Eigen::Vector3d x = A.ldlt().solve(b);
            m = {x(0), x(1), x(2)};
            for (size_t i : used) {
                const Obs &ob = pb.obs[i];
                double uvp[2];
                good = good && project_t(cams[ob.cam], q[ob.frame].data(), d[ob.frame].data(),
                                         m.data(), uvp);
            }
            if (good) {
                depths.push_back(fr.r.dot(Eigen::Vector3d(m[0], m[1], m[2]) - fr.c) /
                                 fr.r.squaredNorm());
            }
        }
        ids.push_back(kv.first);
        M.push_back(m);
        lm_obs.push_back(used);
        ok_lm.push_back(good ? 1 : 0);
        first_ray.push_back(fr);
    }
    if (ids.empty()) {
        *why = "solve: no landmark seen in two frames";
        return false;
    }
    double fb = o.fallback_depth;
    if (!(fb > 0)) {
        if (depths.empty()) {
            *why = "solve: no landmark could be triangulated and no fallback depth given";
            return false;
        }
        std::nth_element(depths.begin(), depths.begin() + (long)depths.size() / 2, depths.end());
        fb = depths[depths.size() / 2];
    }
    for (size_t l = 0; l < ids.size(); ++l) {
        if (!ok_lm[l]) {
            const Eigen::Vector3d x = first_ray[l].c + first_ray[l].r * fb;
            M[l] = {x(0), x(1), x(2)};
            ++res->n_fallback;
            /* an observation that puts this start behind its camera cannot be evaluated (Ceres
             * refuses a problem whose first evaluation fails): it is left out, and so is the
             * landmark if what remains spans a single frame */
            std::vector<size_t> keep;
            for (size_t i : lm_obs[l]) {
                const Obs &ob = pb.obs[i];
                double uvp[2];
                if (project_t(cams[ob.cam], q[ob.frame].data(), d[ob.frame].data(), M[l].data(),
                              uvp)) {
                    keep.push_back(i);
                }
            }
            bool two = false;
            for (size_t i : keep) {
                two = two || pb.obs[i].frame != pb.obs[keep[0]].frame;
            }
            res->n_obs_dropped += two ? lm_obs[l].size() - keep.size() : lm_obs[l].size();
            lm_obs[l] = two ? keep : std::vector<size_t>();
        }
    }

    /* The reprojection errors (px) of the landmarks' observations at the current estimate;
     * an observation that cannot be projected (behind its camera) gets infinity. */
    auto errors_px = [&](std::vector<std::vector<double>> *err) {
        err->assign(ids.size(), std::vector<double>());
        for (size_t l = 0; l < ids.size(); ++l) {
            for (size_t i : lm_obs[l]) {
                const Obs &ob = pb.obs[i];
                double uv[2];
                (*err)[l].push_back(project_t(cams[ob.cam], q[ob.frame].data(), d[ob.frame].data(),
                                              M[l].data(), uv)
                                        ? std::hypot(uv[0] - ob.uv[0], uv[1] - ob.uv[1])
                                        : INFINITY);
            }
        }
    };
    auto rms_of = [](const std::vector<std::vector<double>> &err) {
        double ss = 0;
        size_t n = 0;
        for (const auto &v : err) {
            for (double e : v) {
                if (std::isfinite(e)) {
                    ss += e * e;
                    ++n;
                }
            }
        }
        return n ? std::sqrt(ss / (2.0 * (double)n)) : 0.0; /* per coordinate */
    };
    std::vector<std::vector<double>> err;
    errors_px(&err);
    res->rms_px_initial = rms_of(err);

    ceres::Solver::Summary sum;
    std::vector<char> seen;
    for (int round = 0;; ++round) {
        ceres::Problem problem;
        seen.assign(pb.n_frames, 0);
        res->n_landmarks = 0;
        res->n_obs = 0;
        for (size_t l = 0; l < ids.size(); ++l) {
            res->n_landmarks += lm_obs[l].empty() ? 0 : 1;
            for (size_t i : lm_obs[l]) {
                const Obs &ob = pb.obs[i];
                RigReprojection *f = new RigReprojection{cams[ob.cam], {ob.uv[0], ob.uv[1]},
                                                         1.0 / o.sigma_px};
                ceres::LossFunction *loss =
                    o.loss == Loss::huber    ? (ceres::LossFunction *)new ceres::HuberLoss(o.loss_scale)
                    : o.loss == Loss::cauchy ? (ceres::LossFunction *)new ceres::CauchyLoss(o.loss_scale)
                                             : nullptr;
                problem.AddResidualBlock(
                    new ceres::AutoDiffCostFunction<RigReprojection, 2, 4, 3, 3>(f), loss,
                    q[ob.frame].data(), d[ob.frame].data(), M[l].data());
                seen[ob.frame] = 1;
                ++res->n_obs;
            }
        }
        for (size_t j = 0; j < pb.n_frames; ++j) {
            if (seen[j]) {
                problem.SetManifold(q[j].data(), new ceres::QuaternionManifold);
            }
        }
        if (seen[0]) {
            problem.SetParameterBlockConstant(q[0].data());
            problem.SetParameterBlockConstant(d[0].data());
        }
        ceres::Solver::Options so;
        /* poses x 6 is small (a few hundred): the reduced camera system is solved densely */
        so.linear_solver_type = pb.n_frames <= 400 ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
        so.max_num_iterations = o.max_iterations;
        so.num_threads = o.threads;
        so.function_tolerance = 1e-10;
        so.gradient_tolerance = 1e-12;
        so.parameter_tolerance = 1e-10;
        so.logging_type = ceres::SILENT;
        ceres::Solve(so, &problem, &sum);
        if (sum.termination_type == ceres::FAILURE || !sum.IsSolutionUsable()) {
            *why = "solve: Ceres: " + sum.message;
            return false;
        }
        res->iterations += (int)sum.iterations.size() - 1;
        errors_px(&err);
        if (!(o.reject_sigma > 0) || round == 3) {
            break;
        }
        /* Rejection: observations over reject_sigma sigmas are left out and the problem solved
         * again from here (at most 3 times), as a front end's outlier gate would. */
        size_t dropped = 0;
        for (size_t l = 0; l < ids.size(); ++l) {
            std::vector<size_t> keep;
            for (size_t e = 0; e < lm_obs[l].size(); ++e) {
                if (err[l][e] <= o.reject_sigma * o.sigma_px) {
                    keep.push_back(lm_obs[l][e]);
                }
            }
            bool two = false;
            for (size_t i : keep) {
                two = two || pb.obs[i].frame != pb.obs[keep[0]].frame;
            }
            if (!two) {
                keep.clear();
            }
            dropped += lm_obs[l].size() - keep.size();
            lm_obs[l] = keep;
        }
        res->n_obs_rejected += dropped;
        if (dropped == 0) {
            break;
        }
    }
    res->rms_px_final = rms_of(err);
    std::vector<double> all;
    for (const auto &v : err) {
        all.insert(all.end(), v.begin(), v.end());
    }
    if (!all.empty()) {
        std::nth_element(all.begin(), all.begin() + (long)all.size() / 2, all.end());
        res->median_px_final = all[all.size() / 2];
    }
    res->pose.resize(pb.n_frames);
    res->constrained = seen;
    for (size_t j = 0; j < pb.n_frames; ++j) {
        res->pose[j] = qd_to_pose(q[j].data(), d[j].data());
    }
    res->converged = sum.termination_type == ceres::CONVERGENCE;
    res->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return true;
}

bool crb(const Problem &pb, const std::vector<Pose6> &truth,
         const std::vector<std::pair<uint32_t, Vec3>> &landmarks, double sigma_px,
         std::vector<Cov6> *cov, std::string *why)
{
    if (truth.size() != pb.n_frames || !(sigma_px > 0)) {
        *why = "crb: one true pose per frame and sigma > 0";
        return false;
    }
    std::map<uint32_t, Vec3> lm(landmarks.begin(), landmarks.end());
    const std::map<uint32_t, std::vector<size_t>> by_id = landmark_obs(pb);
    std::vector<rp_pose_lin_t> pl(pb.n_frames);
    for (size_t j = 0; j < pb.n_frames; ++j) {
        rp_real p[6];
        for (int i = 0; i < 6; ++i) {
            p[i] = (rp_real)truth[j][i];
        }
        if (rp_pose_lin_set(&pl[j], p) != RP_OK) {
            *why = "crb: a true pose is not finite";
            return false;
        }
    }
    /* The reduced information over frames 1..n-1 that have information, 6 each. */
    std::vector<long> slot(pb.n_frames, -1);
    long n_slots = 0;
    for (const auto &kv : by_id) {
        for (size_t i : kv.second) {
            const uint32_t f = pb.obs[i].frame;
            if (f != 0 && slot[f] < 0) {
                slot[f] = n_slots++;
            }
        }
    }
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(6 * n_slots, 6 * n_slots);
    const double w = 1.0 / (sigma_px * sigma_px);
    typedef Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J26;
    typedef Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J23;
    typedef Eigen::Matrix<double, 6, 3> M63;
    for (const auto &kv : by_id) {
        const auto it = lm.find(kv.first);
        if (it == lm.end()) {
            *why = "crb: no true position for landmark " + std::to_string(kv.first);
            return false;
        }
        const rp_real Mi[3] = {(rp_real)it->second[0], (rp_real)it->second[1],
                               (rp_real)it->second[2]};
        Eigen::Matrix3d Hll = Eigen::Matrix3d::Zero();
        std::map<long, M63> Hpl; /* per slot: sum of J_pose^T J_M */
        for (size_t i : kv.second) {
            const Obs &ob = pb.obs[i];
            rp_real uv[2], Jp[12], Jm[6];
            if (rp_rig_project(&pb.rig, ob.cam, &pl[ob.frame], Mi, uv, Jp, Jm) != RP_OK) {
                *why = "crb: landmark " + std::to_string(kv.first) + " behind camera " +
                       std::to_string(ob.cam) + " in frame " + std::to_string(ob.frame);
                return false;
            }
            J26 A;
            J23 B;
            for (int e = 0; e < 12; ++e) {
                A(e / 6, e % 6) = (double)Jp[e];
            }
            for (int e = 0; e < 6; ++e) {
                B(e / 3, e % 3) = (double)Jm[e];
            }
            Hll += w * B.transpose() * B;
            const long s = slot[ob.frame];
            if (s < 0) {
                continue; /* frame 0: the gauge */
            }
            S.block<6, 6>(6 * s, 6 * s) += w * A.transpose() * A;
            auto h = Hpl.find(s);
            if (h == Hpl.end()) {
                h = Hpl.emplace(s, M63::Zero()).first;
            }
            h->second += w * A.transpose() * B;
        }
        /* S -= H_pl H_ll^+ H_lp; the pseudo-inverse keeps the Schur complement exact where
         * the landmark's rays leave a direction undetermined (J_M v = 0 there). */
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(Hll);
        const Eigen::Vector3d ev = es.eigenvalues();
        Eigen::Vector3d inv;
        for (int e = 0; e < 3; ++e) {
            inv(e) = ev(e) > 1e-12 * ev(2) ? 1.0 / ev(e) : 0.0;
        }
        const Eigen::Matrix3d Hinv = es.eigenvectors() * inv.asDiagonal() *
                                     es.eigenvectors().transpose();
        for (const auto &a : Hpl) {
            const M63 W = a.second * Hinv;
            for (const auto &b : Hpl) {
                S.block<6, 6>(6 * a.first, 6 * b.first) -= W * b.second.transpose();
            }
        }
    }
    cov->assign(pb.n_frames, Cov6());
    for (size_t j = 0; j < pb.n_frames; ++j) {
        (*cov)[j].fill(j == 0 ? 0.0 : std::nan(""));
    }
    if (n_slots == 0) {
        return true;
    }
    const Eigen::MatrixXd Ss = 0.5 * (S + S.transpose());
    Eigen::LLT<Eigen::MatrixXd> llt(Ss);
    if (llt.info() != Eigen::Success) {
        *why = "crb: the reduced information is not positive definite (a pose the measurements "
               "do not determine)";
        return false;
    }
    const Eigen::MatrixXd C = llt.solve(Eigen::MatrixXd::Identity(6 * n_slots, 6 * n_slots));
    for (size_t j = 0; j < pb.n_frames; ++j) {
        if (slot[j] < 0) {
            continue;
        }
        for (int r = 0; r < 6; ++r) {
            for (int c = 0; c < 6; ++c) {
                (*cov)[j][6 * r + c] = C(6 * slot[j] + r, 6 * slot[j] + c);
            }
        }
    }
    return true;
}

void angles_cov(const Pose6 &p, const double C_w[9], double C_abg[9])
{
    const rp_real abg[3] = {(rp_real)p[3], (rp_real)p[4], (rp_real)p[5]};
    const double h = 1e-6;
    Eigen::Matrix3d A;
    for (int c = 0; c < 3; ++c) {
        rp_real wp[3] = {0, 0, 0}, wm[3] = {0, 0, 0}, ap[3], am[3];
        wp[c] = (rp_real)h;
        wm[c] = (rp_real)-h;
        rp_angles_plus(abg, wp, ap);
        rp_angles_plus(abg, wm, am);
        for (int r = 0; r < 3; ++r) {
            /* the difference of two angles, wrapped to [-pi, pi] */
            const double dd = std::remainder((double)ap[r] - (double)am[r], 2.0 * M_PI);
            A(r, c) = dd / (2.0 * h);
        }
    }
    Eigen::Matrix3d Cw;
    for (int e = 0; e < 9; ++e) {
        Cw(e / 3, e % 3) = C_w[e];
    }
    const Eigen::Matrix3d Ca = A * Cw * A.transpose();
    for (int e = 0; e < 9; ++e) {
        C_abg[e] = Ca(e / 3, e % 3);
    }
}

}  // namespace rpba
