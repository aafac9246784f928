// Samplers against their pdfs: normalisation, moments, chi-square; Fresnel
// limits.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "support/support.h"
#include "transport/phase.h"

namespace vdbmarch {
namespace {

class HenyeyGreenstein : public ::testing::TestWithParam<float> {};

// Stratified quadrature over cos in [-1, 1] (the azimuth integrates to 2 pi).
TEST_P(HenyeyGreenstein, IntegratesToOneWithMeanCosineG) {
    const float g = GetParam();
    const int n = 200000;
    double integral = 0, mean = 0;
    for (int i = 0; i < n; ++i) {
        double c = -1 + 2 * (i + 0.5) / n;
        double p = hgPhase(float(c), g) * 2 * M_PI * (2.0 / n);
        integral += p;
        mean += p * c;
    }
    EXPECT_NEAR(integral, 1.0, 2e-3);
    EXPECT_NEAR(mean, g, 2e-3);
}

// Chi-square of sampled cosines against the pdf integrated over each bin;
// bins pooled to an expected count >= 5. Fixed seed; the test fails only if
// the p-value is below 1e-4 (a false alarm once in 10^4 seeds).
TEST_P(HenyeyGreenstein, SamplerPassesChiSquareAgainstItsPdf) {
    const float g = GetParam();
    const int bins = 200, samples = 400000;
    std::vector<double> observed(bins, 0), expected(bins, 0);
    Rng rng(42, uint64_t(g * 1000 + 5000));
    for (int i = 0; i < samples; ++i) {
        float c = sampleHgCosTheta(rng.uniform(), g);
        int b = std::min(bins - 1, int((c + 1) / 2 * bins));
        observed[size_t(b)] += 1;
    }
    // Expected counts from the closed-form CDF of the cosine,
    // F(c) = (1 - g^2) / (2g) [(1 + g^2 - 2gc)^(-1/2) - 1/(1 + g)],
    // which the normalisation test above checks against the pdf by quadrature.
    auto cdf = [&](double c) {
        if (g == 0) return (c + 1) / 2;
        double gg = g;
        return (1 - gg * gg) / (2 * gg) * (1 / std::sqrt(1 + gg * gg - 2 * gg * c) - 1 / (1 + gg));
    };
    for (int b = 0; b < bins; ++b)
        expected[size_t(b)] = (cdf(-1 + 2.0 * (b + 1) / bins) - cdf(-1 + 2.0 * b / bins)) * samples;
    test::ChiSquare c = test::pooledChiSquare(observed, expected, 5);
    EXPECT_GT(c.p(), 1e-4) << "chi2 " << c.chi2 << " dof " << c.dof << " g " << g;
}

INSTANTIATE_TEST_SUITE_P(Anisotropy, HenyeyGreenstein, ::testing::Values(-0.9f, -0.3f, 0.f, 0.5f, 0.9f, 0.99f));

TEST(Fresnel, NormalIncidenceAndTotalInternalReflection) {
    const float n = 1.5f;
    EXPECT_NEAR(fresnelDielectric(1.f, n), ((n - 1) / (n + 1)) * ((n - 1) / (n + 1)), 1e-6);
    // Leaving glass beyond the critical angle reflects everything.
    float critical = std::asin(1 / n);
    EXPECT_EQ(fresnelDielectric(std::cos(critical + 0.01f), 1 / n), 1.f);
    EXPECT_LT(fresnelDielectric(std::cos(critical - 0.01f), 1 / n), 1.f);
    EXPECT_NEAR(fresnelDielectric(1e-6f, n), 1.f, 1e-3);  // grazing
}

// Equiangular distance sampling: the pdf integrates to 1 over [a, b]
// (midpoint quadrature), and samples pass a chi-square test against the pdf
// integrated over each bin, for a point beside the interval, one near its
// middle (a sharp peak) and one far from it, and a half-infinite interval.
struct EquiangularCase {
    Vec3 light;
    float a, b;
};

class Equiangular : public ::testing::TestWithParam<EquiangularCase> {};

TEST_P(Equiangular, PdfIntegratesToOneAndSamplerPassesChiSquare) {
    const EquiangularCase c = GetParam();
    const Vec3 o(0.1f, -0.2f, 0.3f), d = normalize(Vec3(1, 0.5f, -0.25f));
    EquiangularSampler s(o, d, c.light, c.a, c.b, 1e-6f);
    ASSERT_TRUE(s.valid());
    // Bins over [a, B]: B = b, or for b = inf a far point whose tail mass is
    // in the last pooled bin.
    const double B = std::isinf(c.b) ? c.a + 200.0 : c.b;
    const int bins = 400, samples = 400000;
    auto binMass = [&](int k) {  // fine midpoint quadrature of the pdf over bin k
        const int sub = 400;
        const double t0 = c.a + (B - c.a) * k / bins, h = (B - c.a) / bins / sub;
        double m = 0;
        for (int i = 0; i < sub; ++i) m += double(s.pdf(float(t0 + (i + 0.5) * h))) * h;
        return m;
    };
    std::vector<double> observed(bins + 1, 0), expected(bins + 1, 0);
    double total = 0;
    for (int k = 0; k < bins; ++k) total += expected[size_t(k)] = binMass(k);
    if (std::isinf(c.b)) {
        expected[bins] = std::max(0.0, 1 - total);
    } else {
        EXPECT_NEAR(total, 1.0, 2e-3);
    }
    for (double& e : expected) e *= samples;
    Rng rng(7, 11);
    for (int i = 0; i < samples; ++i) {
        const float t = s.sample(rng.uniform());
        ASSERT_GE(t, c.a);
        ASSERT_LE(t, c.b);
        const int k = t >= B ? bins : std::min(bins - 1, int((t - c.a) / (B - c.a) * bins));
        observed[size_t(k)] += 1;
    }
    test::ChiSquare chi = test::pooledChiSquare(observed, expected, 5);
    EXPECT_GT(chi.p(), 1e-4) << "chi2 " << chi.chi2 << " dof " << chi.dof;
    EXPECT_EQ(s.pdf(c.a - 0.01f), 0.f);
}

INSTANTIATE_TEST_SUITE_P(
    Lights, Equiangular,
    ::testing::Values(EquiangularCase{Vec3(3, 2, 1), 0.5f, 6.f},           // beside the interval
                      EquiangularCase{Vec3(1.8f, 0.7f, -0.1f), 0.f, 4.f},  // 0.1 from the ray: a sharp peak
                      EquiangularCase{Vec3(-40, 3, 0), 1.f, 5.f},           // far behind: nearly uniform
                      EquiangularCase{Vec3(2, 1.5f, 0), 0.f, Infinity}));  // half-infinite

}  // namespace
}  // namespace vdbmarch
