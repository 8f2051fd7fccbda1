/*
 * priv/rp_rng.h - the core's deterministic generator for its randomised solvers (the rig RANSAC,
 * 1-point RANSAC): splitmix64 turns a seed into a state, xorshift64* draws from it. The state is
 * one uint64_t in the caller's struct, never 0, so the same seed gives the same draws on every
 * build and board.
 */
#ifndef RP_PRIV_RNG_H
#define RP_PRIV_RNG_H

#include <stdint.h>

/* A state from seed (splitmix64's finaliser; a state of 0 would stay 0, so it is replaced). */
static inline uint64_t rp_rng_state(uint64_t seed)
{
    uint64_t z = seed + 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return z != 0 ? z : 0x2545F4914F6CDD1Dull;
}

/* The next 32 bits (xorshift64*, high half). */
static inline uint32_t rp_rng_next32(uint64_t *s)
{
    uint64_t x = *s;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    *s = x;
    return (uint32_t)((x * 0x2545F4914F6CDD1Dull) >> 32);
}

/* Uniform in [0, m), m >= 1 (multiply-shift; bias below 2^-32 * m). */
static inline uint32_t rp_rng_below(uint64_t *s, uint32_t m)
{
    return (uint32_t)(((uint64_t)rp_rng_next32(s) * (uint64_t)m) >> 32);
}

#endif /* RP_PRIV_RNG_H */
