// The low-frequency error of image/metrics.h: bias shows, pixel noise does
// not; the paired agreement of two noisy renders: z by construction.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/rng.h"
#include "image/metrics.h"

namespace vdbmarch {
namespace {

Image constantImage(int w, int h, float v) {
    Image img(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) img.set(x, y, Color(v), 1.f);
    return img;
}

TEST(LowFrequencyError, AConstantBiasIsItsFractionOfTheMean) {
    const Image ref = constantImage(32, 24, 2.f), test = constantImage(32, 24, 2.2f);
    EXPECT_NEAR(lowFrequencyError(test, ref), 0.1, 1e-6);
}

TEST(LowFrequencyError, ZeroMeanPixelNoiseWithinBlocksAveragesOut) {
    const Image ref = constantImage(32, 24, 1.f);
    Image test = ref;
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 32; ++x) test.set(x, y, Color((x + y) % 2 ? 1.5f : 0.5f), 1.f);  // checkerboard
    EXPECT_NEAR(lowFrequencyError(test, ref), 0.0, 1e-7);
    EXPECT_GT(compareImages(test, ref).rmse, 0.4);
}

TEST(LowFrequencyError, ABlotchShowsAtItsBlockShare) {
    const Image ref = constantImage(16, 16, 1.f);
    Image test = ref;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) test.set(x, y, Color(1.4f), 1.f);  // one of four 8x8 blocks 40% bright
    EXPECT_NEAR(lowFrequencyError(test, ref), std::sqrt(0.4 * 0.4 / 4), 1e-6);
}

TEST(LowFrequencyError, SizesMustMatch) {
    EXPECT_THROW(lowFrequencyError(constantImage(8, 8, 1.f), constantImage(8, 9, 1.f)), InputError);
}

// Two images of unit-variance noise about the same value: |z| <= 4 in every
// region and channel; a bias of b in one quadrant's red, n pixels there,
// shows as z = b sqrt(n) / sqrt(2) (the differences' variance is 2).
TEST(PairedAgreement, NoiseAgreesAndAQuadrantBiasShowsAtItsZ) {
    const int W = 64, H = 48;
    Image a(W, H), b(W, H);
    Rng rng(11, 0);
    auto gauss = [&] {
        const double u1 = 1 - double(rng.uniform()), u2 = double(rng.uniform());
        return float(std::sqrt(-2 * std::log(u1)) * std::cos(6.283185307179586 * u2));
    };
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            a.set(x, y, Color(5 + gauss(), 5 + gauss(), 5 + gauss()), 1.f);
            b.set(x, y, Color(5 + gauss(), 5 + gauss(), 5 + gauss()), 1.f);
        }
    const PairedAgreement same = pairedAgreement(a, b);
    EXPECT_LE(same.maxAbsZ, 4.0);
    EXPECT_EQ(same.z[0][3], 0.0);  // alpha identical
    const double bias = 0.5, n = double(W / 2 * H / 2);
    Image c = b;
    for (int y = H / 2; y < H; ++y)
        for (int x = W / 2; x < W; ++x) c.rgba[4 * (size_t(y) * W + size_t(x))] += float(bias);
    const PairedAgreement biased = pairedAgreement(c, a);
    const double expected = bias * std::sqrt(n) / std::sqrt(2.0);  // 12.2
    EXPECT_EQ(biased.region, 4);
    EXPECT_EQ(biased.channel, 0);
    // Less the noise's own z, the bias over the sample standard error, whose
    // relative error is 1 / sqrt(2 n) (4 sigma: 10 %).
    EXPECT_NEAR(biased.z[4][0] + same.z[4][0], expected, 0.1 * expected) << biased.z[4][0];
    EXPECT_THROW(pairedAgreement(a, Image(W, H + 1)), InputError);
}

}  // namespace
}  // namespace vdbmarch
