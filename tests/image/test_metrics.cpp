// The low-frequency error of image/metrics.h: bias shows, pixel noise does not.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
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

}  // namespace
}  // namespace vdbmarch
