// Russian roulette (transport/roulette.h): every decision keeps the path's
// expected throughput, E[beta'] = beta, for any throughput and any judged
// scale, and leaves paths at or above the threshold untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "transport/roulette.h"

namespace vdbmarch {
namespace {

// E[beta'] over n draws of a fixed-seed Rng, and its standard error.
void expectedThroughput(const Color& beta, float threshold, float scale, double& mean, double& se) {
    Rng rng(7, 11);
    const int n = 400000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        Color b = beta;
        const double v = russianRoulette(b, rng, threshold, scale) ? double(b.x) : 0.0;
        sum += v;
        sum2 += v * v;
    }
    mean = sum / n;
    se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
}

TEST(RussianRoulette, KeepsTheExpectedThroughput) {
    for (float b : {1e-4f, 0.01f, 0.3f, 0.9f})
        for (float scale : {1.f, 0.25f, 40.f}) {
            double mean, se;
            expectedThroughput(Color(b), ScatterRouletteThreshold, scale, mean, se);
            EXPECT_NEAR(mean, double(b), 4 * se + 1e-12) << "beta " << b << " scale " << scale;
        }
}

TEST(RussianRoulette, LeavesBrightPathsAlone) {
    Rng rng(1, 2);
    Color b(2.f, 0.5f, 1.f);
    EXPECT_TRUE(russianRoulette(b, rng, ScatterRouletteThreshold));
    EXPECT_EQ(b.x, 2.f);
    EXPECT_EQ(b.y, 0.5f);
}

TEST(RussianRoulette, EndsBlackAndNonFinitePaths) {
    Rng rng(1, 2);
    Color black(0.f), nan(std::numeric_limits<float>::quiet_NaN());
    EXPECT_FALSE(russianRoulette(black, rng));
    EXPECT_FALSE(russianRoulette(nan, rng));
    EXPECT_EQ(rouletteSurvival(Color(0.f)), 0.f);
}

}  // namespace
}  // namespace vdbmarch
