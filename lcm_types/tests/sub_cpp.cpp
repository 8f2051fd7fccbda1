// sub_cpp - a C++ subscriber of the daemon's poses through the lcm-gen C++ types (lcm-gen -x).
// usage: sub_cpp URL CHANNEL EXPECT READYFILE
// Subscribes, touches READYFILE, then receives until EXPECT poses arrived (or 60 s passed) and
// checks seq 0..EXPECT-1 in order and a unit quaternion. Prints "sub_cpp: ok" or "sub_cpp: FAIL".
#include <lcm/lcm-cpp.hpp>
#include <rigpose/pose_t.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

struct Poses {
    int n = 0;
    int bad = 0;
    void on_pose(const lcm::ReceiveBuffer *, const std::string &, const rigpose::pose_t *m) {
        if (m->seq != n) {
            if (bad++ < 5) std::printf("pose %d has seq %d\n", n, m->seq);
        }
        double q = 0;
        for (double x : m->quaternion) q += x * x;
        if (std::fabs(std::sqrt(q) - 1) > 1e-9 && bad++ < 5)
            std::printf("seq %d: |q| = %.12f\n", m->seq, std::sqrt(q));
        n++;
    }
};

}  // namespace

int main(int argc, char **argv) {
    if (argc != 5) {
        std::fprintf(stderr, "usage: sub_cpp URL CHANNEL EXPECT READYFILE\n");
        return 2;
    }
    const int expect = std::atoi(argv[3]);
    lcm::LCM lc(argv[1]);
    if (!lc.good()) {
        std::printf("sub_cpp: FAIL: cannot open %s\n", argv[1]);
        return 1;
    }
    Poses p;
    lc.subscribe(argv[2], &Poses::on_pose, &p);
    std::FILE *f = std::fopen(argv[4], "w");
    if (f) std::fclose(f);
    auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (p.n < expect && std::chrono::steady_clock::now() < end) lc.handleTimeout(100);
    std::printf("C++ subscriber (rigpose::pose_t): %d poses (expected %d), %d problems\n", p.n,
                expect, p.bad);
    const bool ok = p.n == expect && p.bad == 0;
    std::printf(ok ? "sub_cpp: ok\n" : "sub_cpp: FAIL\n");
    return ok ? 0 : 1;
}
