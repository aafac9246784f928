// Stratified points in the unit square for pixel positions: the first two
// dimensions of the Sobol sequence (a (0,2)-sequence), Owen-scrambled by
// hashing (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)),
// as Cycles' Sobol-Burley pattern does. Every point is uniform on the square
// (so each sample stays unbiased), and the first 2^m points of a sequence
// hold one point in each of the 2^m boxes of every elementary grid
// (2^a x 2^b, a + b = m): the error of a pixel's coverage of a hard edge
// (a light's disc, a glass silhouette) falls as N^-3/4 instead of N^-1/2.
#pragma once

#include <cstdint>

#include "core/rng.h"

namespace vdbmarch {

inline uint32_t reverseBits32(uint32_t v) {
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
    v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
    return (v >> 16) | (v << 16);
}

// Burley's nested uniform scramble: a hash that flips each bit by a random
// function of the bits above it (in reversed order: the Laine-Karras
// permutation), so a scrambled net is still a net.
inline uint32_t owenScramble(uint32_t v, uint32_t seed) {
    v = reverseBits32(v);
    v += seed;
    v ^= v * 0x6c50b47cu;
    v ^= v * 0xb82f1e52u;
    v ^= v * 0xc7afe638u;
    v ^= v * 0x8d22f6e6u;
    return reverseBits32(v);
}

// Point `index` of the sequence `sequence` (any 64-bit value: a hash of the
// seed, pixel and stream), in [0, 1)^2 with 24-bit precision.
inline void sobolPoint2D(uint32_t index, uint64_t sequence, float& u, float& v) {
    // Dimension 0: van der Corput (the bit-reversed index); dimension 1: the
    // Pascal matrix mod 2, direction d_i = d_{i-1} ^ (d_{i-1} >> 1).
    uint32_t x = reverseBits32(index), y = 0, direction = 0x80000000u;
    for (uint32_t i = index; i; i >>= 1) {
        if (i & 1) y ^= direction;
        direction ^= direction >> 1;
    }
    const uint64_t seeds = mixBits(sequence);
    x = owenScramble(x, uint32_t(seeds));
    y = owenScramble(y, uint32_t(seeds >> 32));
    u = float(x >> 8) * 0x1p-24f;
    v = float(y >> 8) * 0x1p-24f;
}

}  // namespace vdbmarch
