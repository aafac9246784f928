// The power-series transmittance (core/power_series.h) against its closed
// form: the order's distribution against its stated P(K >= k) by chi-square;
// agreeing estimates give exp(-k D) exactly; noisy unbiased estimates of D
// give exp(-k D) on average (within 4 standard errors) where exp(-mean) of the
// same estimates is measurably biased (the test has power).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/power_series.h"
#include "core/rng.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

TEST(PowerSeries, OrderFollowsItsDistribution) {
    for (double pZero : {0.0, 0.75, 0.9}) {
        const SeriesOrder dist(pZero);
        EXPECT_EQ(dist.atLeast(0), 1.0);
        EXPECT_NEAR(dist.atLeast(1), 1 - pZero, 1e-15);
        EXPECT_EQ(dist.atLeast(SeriesOrder::MinOrder), dist.atLeast(1));
        EXPECT_LT(dist.atLeast(SeriesOrder::MaxOrder), 1e-30);
        const int bins = 12, n = 400000;
        std::vector<double> observed(bins, 0), expected(bins, 0);
        Rng rng(3, uint64_t(pZero * 100));
        for (int i = 0; i < n; ++i) observed[size_t(std::min(bins - 1, dist.sample(rng.uniformDouble())))] += 1;
        for (int k = 0; k < bins; ++k)
            expected[size_t(k)] = n * (dist.atLeast(k) - (k + 1 < bins ? dist.atLeast(k + 1) : 0.0));
        const ChiSquare c = pooledChiSquare(observed, expected, 5);
        EXPECT_GT(c.p(), 1e-3) << "pZero " << pZero << " chi2 " << c.chi2 << " dof " << c.dof;
    }
}

TEST(PowerSeries, AgreeingEstimatesGiveTheExponential) {
    const SeriesOrder dist(0.75);
    std::vector<double> d(SeriesOrder::MaxOrder + 1, 2.5), scratch(d.size());
    const Color k(0.3f, 1.f, 0.f);
    for (int order : {0, 1, 2, 5, 12}) {
        const Color T = powerSeriesTransmittance(d.data(), order, k, dist, scratch.data());
        // Every series term past order 0 vanishes; the weights of the
        // zero-th term are 1.
        EXPECT_NEAR(T.x, std::exp(-0.75), 1e-6) << order;
        EXPECT_NEAR(T.y, std::exp(-2.5), 1e-6) << order;
        EXPECT_EQ(T.z, 1.f) << order;
    }
}

TEST(PowerSeries, UnbiasedForNoisyDepths) {
    struct Case {
        double depth, noise, pZero;
    };
    // Optical depth D, estimates D + uniform noise of half-width `noise`
    // (standard deviation noise / sqrt 3), at the renderer's pZero and others.
    for (const Case& cs : {Case{0.5, 0.4, 0.75}, Case{2.0, 1.0, 0.75}, Case{4.0, 1.5, 0.9}, Case{1.0, 0.8, 0.0}}) {
        const SeriesOrder dist(cs.pZero);
        const Color k(1.f, 0.5f, 0.f);
        std::vector<double> d(SeriesOrder::MaxOrder + 1), scratch(d.size());
        SampleStats series[2], naive;
        Rng rng(11, uint64_t(cs.depth * 10));
        for (int i = 0; i < 400000; ++i) {
            const int order = dist.sample(rng.uniformDouble());
            for (int j = 0; j <= order; ++j) d[size_t(j)] = cs.depth + cs.noise * (2 * rng.uniformDouble() - 1);
            const Color T = powerSeriesTransmittance(d.data(), order, k, dist, scratch.data());
            series[0].add(T.x);
            series[1].add(T.y);
            EXPECT_EQ(T.z, 1.f);
            naive.add(std::exp(-d[0]));
        }
        for (int c = 0; c < 2; ++c) {
            const double expected = std::exp(-double(k[c]) * cs.depth);
            EXPECT_NEAR(series[c].mean(), expected, 4 * series[c].stdError())
                << "depth " << cs.depth << " noise " << cs.noise << " channel " << c;
        }
        // exp of an unbiased depth is biased upwards (Jensen); the series is not.
        const double truth = std::exp(-cs.depth);
        EXPECT_GT(naive.mean() - truth, 8 * naive.stdError()) << "depth " << cs.depth;
    }
}

}  // namespace
}  // namespace vdbmarch
