/*
 * test_realdata_conv.cpp - rp_realdata's conversions and scoring, and (when the data is there)
 * its loaders: pose vector round trip in the paper's angles, transform algebra, the ATE / RPE
 * of a known error, the KITTI and EuRoC rigs and first frames, and the dense direct yardstick
 * (rp_direct.hpp) on a few KITTI frames. Run by `make test`; prints one line per check and a
 * cmocka-style summary.
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <sys/stat.h>

#include "rp_direct.hpp"
#include "rp_realdata.hpp"

namespace {

int n_pass = 0, n_fail = 0;

void check(bool ok, const char *what, double value)
{
    std::printf("[%s] %s (%.9g)\n", ok ? "       OK " : "  FAILED  ", what, value);
    (ok ? n_pass : n_fail)++;
}

double pose_diff(const rprd::Pose &a, const rprd::Pose &b)
{
    double d = 0.0;
    for (int i = 0; i < 9; ++i) {
        d = std::fmax(d, std::fabs(a.R[i] - b.R[i]));
    }
    for (int i = 0; i < 3; ++i) {
        d = std::fmax(d, std::fabs(a.t[i] - b.t[i]));
    }
    return d;
}

double length(const rprd::Pose &T)
{
    return std::sqrt(T.t[0] * T.t[0] + T.t[1] * T.t[1] + T.t[2] * T.t[2]);
}

/* Rotation angle of a pose, degrees. */
double angle_deg(const rprd::Pose &T)
{
    const double c = (T.R[0] + T.R[4] + T.R[8] - 1.0) / 2.0;
    return std::acos(std::fmin(1.0, std::fmax(-1.0, c))) * 180.0 / M_PI;
}

/* The dense direct yardstick on KITTI: 3 steps of frames 20-23 (where the truth is a real
 * measurement) agree with the truth, whatever the start; 3 steps of frames 0-3 do not (the
 * truth's extrapolated start, README.md); a distorted pair is refused. */
void check_direct(const std::string &kitti, const rprd::Sequence &euroc)
{
    rprd::Sequence k;
    std::string err;
    if (!rprd::load_kitti(kitti, 20, 4, &k, &err)) {
        check(false, ("direct: KITTI frames 20-23: " + err).c_str(), 0.0);
        return;
    }
    rprd::DirectOpts o;
    std::vector<rprd::Pose> traj, steps, traj2, steps2;
    const bool ok = rprd::direct_reference(k, o, &traj, &steps, &err);
    o.start_step_m = 0.3;
    const bool ok2 = rprd::direct_reference(k, o, &traj2, &steps2, &err);
    check(ok && ok2 && steps.size() == 3 && traj.size() == 4, "direct: 3 steps, 4 poses", 0.0);
    if (!ok || !ok2 || steps.size() != 3) {
        return;
    }
    double worst_len = 0.0, worst_rot = 0.0, worst_start = 0.0;
    for (size_t j = 1; j < 4; ++j) {
        const rprd::Pose truth = rprd::pose_mul(rprd::pose_inv(k.truth[j - 1]), k.truth[j]);
        const rprd::Pose est = rprd::pose_inv(steps[j - 1]);
        worst_len = std::fmax(worst_len, std::fabs(length(est) / length(truth) - 1.0));
        worst_rot = std::fmax(worst_rot, angle_deg(rprd::pose_mul(rprd::pose_inv(est), truth)));
        worst_start = std::fmax(worst_start, pose_diff(steps[j - 1], steps2[j - 1]));
    }
    check(worst_len < 0.02, "direct: KITTI steps 20-23 within 2 % of the truth's length",
          worst_len);
    check(worst_rot < 0.05, "direct: ... and within 0.05 deg of its rotation", worst_rot);
    check(worst_start < 1e-4, "direct: same steps from a 0.3 m start as from 0.75 m",
          worst_start);
    rprd::Sequence s0;
    if (rprd::load_kitti(kitti, 0, 4, &s0, &err) &&
        rprd::direct_reference(s0, rprd::DirectOpts(), &traj, &steps, &err)) {
        double longest = 0.0, truth_shortest = 1e9;
        for (size_t j = 1; j < 4; ++j) {
            longest = std::fmax(longest, length(steps[j - 1]));
            truth_shortest = std::fmin(
                truth_shortest, length(rprd::pose_mul(rprd::pose_inv(s0.truth[j - 1]), s0.truth[j])));
        }
        check(longest < 0.75 && truth_shortest > 0.85,
              "direct: KITTI frames 0-3: images under 0.75 m a step, truth over 0.85 m", longest);
    } else {
        check(false, ("direct: KITTI frames 0-3: " + err).c_str(), 0.0);
    }
    err.clear();
    const bool refused = !rprd::direct_reference(euroc, rprd::DirectOpts(), &traj, nullptr, &err);
    check(refused && !err.empty(), ("direct: a distorted pair is refused: " + err).c_str(), 0.0);
}

bool is_dir(const std::string &p)
{
    struct stat st;
    return stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

}  // namespace

int main()
{
    /* pose vector round trip, seeded */
    std::srand(7);
    double worst = 0.0, worst_inv = 0.0;
    for (int k = 0; k < 1000; ++k) {
        double p[6], q[6];
        for (int i = 0; i < 6; ++i) {
            p[i] = (2.0 * std::rand() / RAND_MAX - 1.0) * (i == 4 ? 1.5 : 3.0);
        }
        const rprd::Pose T = rprd::pose_from_vec(p);
        rprd::pose_to_vec(T, q);
        worst = std::fmax(worst, pose_diff(T, rprd::pose_from_vec(q)));
        worst_inv = std::fmax(worst_inv, pose_diff(rprd::pose_mul(rprd::pose_inv(T), T),
                                                   rprd::Pose()));
    }
    check(worst < 1e-12, "pose vector -> pose -> vector -> pose round trip", worst);
    check(worst_inv < 1e-12, "pose_inv(T) * T is the identity", worst_inv);

    /* a known error: 10 frames 1 m apart along z, the estimate 0.1 m off in x from frame 1 on */
    std::vector<rprd::Pose> truth(10), est(10);
    for (int j = 0; j < 10; ++j) {
        truth[(size_t)j].t[2] = j;
        est[(size_t)j].t[2] = j;
        est[(size_t)j].t[0] = j ? 0.1 : 0.0;
    }
    const rprd::Summary s = rprd::summarise(est, truth);
    check(std::fabs(s.path_m - 9.0) < 1e-12, "path length 9 m", s.path_m);
    check(std::fabs(s.ate_m - 0.1 * std::sqrt(0.9)) < 1e-12, "ATE = 0.1 sqrt(9/10) m", s.ate_m);
    check(std::fabs(s.rpe_percent - 100.0 * 0.1 / 9.0) < 1e-9, "RPE: one 0.1 m step error",
          s.rpe_percent);

    /* the loaders, on the real data if present */
    const char *env = std::getenv("RIGPOSE_DATA");
    const std::string data = env ? env : "../shared/data";
    if (is_dir(data + "/kitti00_000-099") && is_dir(data + "/euroc_mh01_000-149")) {
        rprd::Sequence k, e;
        std::string err;
        const bool ok_k = rprd::load_kitti(data + "/kitti00_000-099", 0, 0, &k, &err);
        check(ok_k && k.utime.size() == 100, "KITTI: 100 frames loaded", (double)k.utime.size());
        if (ok_k) {
            check(rp_rig_check(&k.rig) == RP_OK, "KITTI: rig usable", 0.0);
            check(std::fabs((double)k.rig.cam[1].D[0] - 386.1448 / 718.856) < 1e-9,
                  "KITTI: baseline 386.1448 / 718.856 m", (double)k.rig.cam[1].D[0]);
            check(pose_diff(k.truth[0], rprd::Pose()) < 1e-6, "KITTI: frame 0 is the world",
                  pose_diff(k.truth[0], rprd::Pose()));
            check(std::fabs(k.truth[99].t[2] - 83.8853) < 1e-3, "KITTI: frame 99 at z 83.885 m",
                  k.truth[99].t[2]);
        }
        const bool ok_e = rprd::load_euroc(data + "/euroc_mh01_000-149", 0, 0, &e, &err);
        check(ok_e && e.utime.size() == 150, "EuRoC: 150 frames loaded", (double)e.utime.size());
        if (ok_e) {
            const double b = std::sqrt((double)(e.rig.cam[1].D[0] * e.rig.cam[1].D[0] +
                                                e.rig.cam[1].D[1] * e.rig.cam[1].D[1] +
                                                e.rig.cam[1].D[2] * e.rig.cam[1].D[2]));
            check(rp_rig_check(&e.rig) == RP_OK, "EuRoC: rig usable", 0.0);
            check(std::fabs(b - 0.110) < 0.001, "EuRoC: baseline about 0.110 m", b);
            check(pose_diff(e.truth[0], rprd::Pose()) < 1e-9, "EuRoC: frame 0 is the world",
                  pose_diff(e.truth[0], rprd::Pose()));
            check(e.utime[1] - e.utime[0] == 50000, "EuRoC: 20 Hz",
                  (double)(e.utime[1] - e.utime[0]));
        }
        if (ok_e) {
            check_direct(data + "/kitti00_000-099", e);
        }
        rprd::Sequence bad;
        err.clear();
        const bool refused = !rprd::load_kitti(data + "/euroc_mh01_000-149", 0, 0, &bad, &err);
        check(refused && !err.empty(), ("a wrong folder is refused: " + err).c_str(), 0.0);
    } else {
        std::printf("[  SKIPPED ] 1 test(s): the loaders on real data: no kitti00_000-099/ and "
                    "euroc_mh01_000-149/ in %s (set RIGPOSE_DATA)\n",
                    data.c_str());
    }
    std::printf("[  PASSED  ] %d test(s).\n", n_pass);
    if (n_fail) {
        std::printf("[  FAILED  ] %d test(s).\n", n_fail);
        return 1;
    }
    return 0;
}
