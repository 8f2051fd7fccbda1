/*
 * rp_noise.hpp - seeded 3-D gradient noise for the rendered scenes' textures (host only).
 */
#ifndef RP_NOISE_HPP
#define RP_NOISE_HPP

#include <cmath>
#include <cstdint>
#include <utility>

namespace rpr {

/* splitmix64's finaliser. */
inline uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform [0, 1) from a counter-style stream. */
struct Stream {
    uint64_t s;
    double next()
    {
        s += 0x9E3779B97F4A7C15ull;
        return (double)(mix64(s) >> 11) * (1.0 / 9007199254740992.0);
    }
};

/* 3-D gradient noise on the integer lattice: at each lattice point a pseudo-random gradient
 * (one of the 12 cube edge directions, picked by a seeded permutation), blended with the quintic
 * fade 6t^5 - 15t^4 + 10t^3. Zero at lattice points, roughly in [-1, 1]. */
class GradNoise {
public:
    explicit GradNoise(uint64_t seed)
    {
        for (int i = 0; i < 256; ++i) {
            perm_[i] = (uint8_t)i;
        }
        Stream st{seed};
        for (int i = 255; i > 0; --i) {
            const int j = (int)(st.next() * (i + 1));
            std::swap(perm_[i], perm_[j]);
        }
        for (int i = 0; i < 256; ++i) {
            perm_[256 + i] = perm_[i];
        }
    }

    double operator()(double x, double y, double z) const
    {
        const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
        const int X = (int)fx & 255, Y = (int)fy & 255, Z = (int)fz & 255;
        x -= fx;
        y -= fy;
        z -= fz;
        const double u = fade(x), v = fade(y), w = fade(z);
        double c[8];
        for (int k = 0; k < 8; ++k) {
            const int dx = k & 1, dy = (k >> 1) & 1, dz = (k >> 2) & 1;
            const int h = perm_[perm_[perm_[X + dx] + Y + dy] + Z + dz];
            c[k] = dot(h, x - dx, y - dy, z - dz);
        }
        const double x00 = c[0] + u * (c[1] - c[0]), x10 = c[2] + u * (c[3] - c[2]);
        const double x01 = c[4] + u * (c[5] - c[4]), x11 = c[6] + u * (c[7] - c[6]);
        const double y0 = x00 + v * (x10 - x00), y1 = x01 + v * (x11 - x01);
        return y0 + w * (y1 - y0);
    }

private:
    static double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
    static double dot(int h, double x, double y, double z)
    {
        switch (h % 12) { /* the 12 edge midpoints of the cube */
        case 0: return x + y;
        case 1: return -x + y;
        case 2: return x - y;
        case 3: return -x - y;
        case 4: return x + z;
        case 5: return -x + z;
        case 6: return x - z;
        case 7: return -x - z;
        case 8: return y + z;
        case 9: return -y + z;
        case 10: return y - z;
        default: return -y - z;
        }
    }
    uint8_t perm_[512];
};

} /* namespace rpr */

#endif /* RP_NOISE_HPP */
