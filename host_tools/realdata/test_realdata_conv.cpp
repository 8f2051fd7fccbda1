/*
 * test_realdata_conv.cpp - rp_realdata's conversions and scoring, and (when the data is there)
 * its loaders: pose vector round trip in the paper's angles, transform algebra, the ATE / RPE
 * of a known error, the KITTI and EuRoC rigs and first frames. Run by `make test`; prints one
 * line per check and a cmocka-style summary.
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <sys/stat.h>

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
        rprd::Sequence bad;
        err.clear();
        const bool refused = !rprd::load_kitti(data + "/euroc_mh01_000-149", 0, 0, &bad, &err);
        check(refused && !err.empty(), ("a wrong folder is refused: " + err).c_str(), 0.0);
    } else {
        std::printf("test_realdata_conv: loaders not checked: no data in %s (RIGPOSE_DATA)\n",
                    data.c_str());
    }
    std::printf("[  PASSED  ] %d test(s).\n", n_pass);
    if (n_fail) {
        std::printf("[  FAILED  ] %d test(s).\n", n_fail);
        return 1;
    }
    return 0;
}
