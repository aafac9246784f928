// Russian roulette and the guided weight window (transport/roulette.h):
// every decision keeps the path's expected weight, E[paths x weight] = 1,
// for any ratio r, so guided roulette and splitting are unbiased whatever
// the cache says; the window leaves paths near the pixel's estimate alone
// and splitting respects its limit.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "transport/roulette.h"

namespace vdbmarch {
namespace {

// E[paths x weight] over u uniform on [0, 1), by the midpoint rule on n
// points: exact up to 1/n for the step function of u.
double expectedWeight(float r, int splitLimit, int n = 100000) {
    double sum = 0;
    for (int i = 0; i < n; ++i) {
        const WindowDecision d = weightWindow(r, float((i + 0.5) / n), splitLimit);
        sum += double(d.paths) * double(d.weight);
    }
    return sum / n;
}

TEST(WeightWindow, KeepsThePathsExpectedWeightForAnyRatio) {
    const float inf = std::numeric_limits<float>::infinity();
    for (float r : {0.f, 1e-6f, 0.05f, 0.1f, 0.2f, 0.33f, 0.5f, 1.f, 1.6f, 1.7f, 2.4f, 2.6f, 5.f, 7.9f, 100.f, inf})
        for (int limit : {1, 2, 3, 8})
            EXPECT_NEAR(expectedWeight(r, limit), 1.0, 2e-5) << "r " << r << " limit " << limit;
}

TEST(WeightWindow, LeavesPathsInsideTheWindowAlone) {
    for (float r : {WindowLow, 0.5f, 1.f, 1.5f, std::nextafter(WindowHigh, 0.f)})
        for (float u : {0.f, 0.5f, 0.999f}) {
            const WindowDecision d = weightWindow(r, u, MaxSplitPaths);
            EXPECT_EQ(d.paths, 1) << r;
            EXPECT_EQ(d.weight, 1.f) << r;
        }
    // NaN (a broken estimate) changes nothing either.
    const WindowDecision d = weightWindow(std::numeric_limits<float>::quiet_NaN(), 0.5f, MaxSplitPaths);
    EXPECT_EQ(d.paths, 1);
    EXPECT_EQ(d.weight, 1.f);
}

TEST(WeightWindow, RoulettesBelowWithAFloorAndSplitsAboveWithinTheLimit) {
    // Below the window: survival max(r, WindowMinSurvival), weight its inverse.
    EXPECT_EQ(weightWindow(0.25f, 0.24f, 8).paths, 1);
    EXPECT_FLOAT_EQ(weightWindow(0.25f, 0.24f, 8).weight, 4.f);
    EXPECT_EQ(weightWindow(0.25f, 0.26f, 8).paths, 0);
    EXPECT_EQ(weightWindow(0.f, 0.5f * WindowMinSurvival, 8).paths, 1);
    EXPECT_FLOAT_EQ(weightWindow(0.f, 0.f, 8).weight, 1.f / WindowMinSurvival);
    // Above: round(r) paths of weight 1/n, at most the limit and MaxSplitPaths.
    EXPECT_EQ(weightWindow(3.4f, 0.5f, 8).paths, 3);
    EXPECT_FLOAT_EQ(weightWindow(3.4f, 0.5f, 8).weight, 1.f / 3.f);
    EXPECT_EQ(weightWindow(1.7f, 0.5f, 8).paths, 2);
    EXPECT_EQ(weightWindow(6.f, 0.5f, 2).paths, 2);
    EXPECT_EQ(weightWindow(6.f, 0.5f, 1).paths, 1);
    EXPECT_EQ(weightWindow(std::numeric_limits<float>::infinity(), 0.5f, 100).paths, MaxSplitPaths);
}

}  // namespace
}  // namespace vdbmarch
