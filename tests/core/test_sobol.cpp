// The scrambled Sobol points of the pixel positions (core/sobol.h): every
// prefix of 2^m points of a sequence is a (0,m,2)-net, and a point of a given
// index is uniform over the square across sequences (each sample unbiased).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/sobol.h"

namespace vdbmarch {
namespace {

TEST(Sobol, EveryPowerOfTwoPrefixIsANet) {
    for (uint64_t sequence : {uint64_t(0), uint64_t(1), uint64_t(0x9e3779b97f4a7c15ULL), uint64_t(12345)})
        for (int m = 0; m <= 10; ++m) {
            const uint32_t n = 1u << m;
            std::vector<float> u(n), v(n);
            for (uint32_t i = 0; i < n; ++i) sobolPoint2D(i, sequence, u[i], v[i]);
            // Every elementary grid of 2^a x 2^b boxes, a + b = m: one point in each.
            for (int a = 0; a <= m; ++a) {
                const int b = m - a;
                std::vector<int> count(size_t(n), 0);
                for (uint32_t i = 0; i < n; ++i) {
                    ASSERT_GE(u[i], 0.f);
                    ASSERT_LT(u[i], 1.f);
                    ASSERT_GE(v[i], 0.f);
                    ASSERT_LT(v[i], 1.f);
                    const uint32_t bx = uint32_t(u[i] * float(1u << a)), by = uint32_t(v[i] * float(1u << b));
                    ++count[(size_t(by) << a) | bx];
                }
                for (int c : count) ASSERT_EQ(c, 1) << "sequence " << sequence << ", 2^" << a << " x 2^" << b;
            }
        }
}

// Point 5 (and 0, the first) over 64,000 sequences, binned 16 x 16: Pearson's
// chi-square against the uniform density, 255 degrees of freedom. The 0.1 %
// critical value is 330.5.
TEST(Sobol, APointIsUniformAcrossSequences) {
    for (uint32_t index : {0u, 5u, 1000u}) {
        const int bins = 16, samples = 64000;
        std::vector<int> count(bins * bins, 0);
        for (int s = 0; s < samples; ++s) {
            float u, v;
            sobolPoint2D(index, hashValues(7, uint64_t(s)), u, v);
            ++count[size_t(int(v * bins) * bins + int(u * bins))];
        }
        const double expected = double(samples) / (bins * bins);
        double chi2 = 0;
        for (int c : count) chi2 += (c - expected) * (c - expected) / expected;
        EXPECT_LT(chi2, 330.5) << "index " << index;
    }
}

// Two sequences (two pixels, or the two half renders of one pixel) are not
// the same points.
TEST(Sobol, SequencesDiffer) {
    int same = 0;
    for (uint32_t i = 0; i < 64; ++i) {
        float u0, v0, u1, v1;
        sobolPoint2D(i, 1, u0, v0);
        sobolPoint2D(i, 2, u1, v1);
        same += u0 == u1 && v0 == v1;
    }
    EXPECT_EQ(same, 0);
}

}  // namespace
}  // namespace vdbmarch
