// PCG32 (O'Neill 2014, pcg-basic) and a hash to seed one independent stream
// per (seed, pixel, sample): pixels never share random numbers across threads,
// so images are bit-identical for any thread count.
#pragma once

#include <cstdint>

namespace vdbmarch {

inline uint64_t mixBits(uint64_t v) {
    // splitmix64 finaliser
    v ^= v >> 30; v *= 0xbf58476d1ce4e5b9ULL;
    v ^= v >> 27; v *= 0x94d049bb133111ebULL;
    v ^= v >> 31;
    return v;
}

inline uint64_t hashValues(uint64_t a, uint64_t b = 0, uint64_t c = 0) {
    return mixBits(a ^ mixBits((b + 0x9e3779b97f4a7c15ULL) ^ mixBits(c + 0x632be59bd9b4e019ULL)));
}

class Rng {
public:
    Rng() { seed(0, 0); }
    Rng(uint64_t seq, uint64_t offset = 0) { seed(seq, offset); }
    void seed(uint64_t seq, uint64_t offset) {
        mState = 0u;
        mInc = (seq << 1u) | 1u;
        next();
        mState += mixBits(offset);
        next();
    }
    uint32_t next() {
        uint64_t old = mState;
        mState = old * 0x5851f42d4c957f2dULL + mInc;
        uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }
    // Uniform in [0, 1): 24 random mantissa bits, never returns 1.
    float uniform() { return float(next() >> 8) * 0x1p-24f; }
    double uniformDouble() { return (double(next()) * 0x1p-32 + double(next())) * 0x1p-32; }

private:
    uint64_t mState, mInc;
};

}  // namespace vdbmarch
