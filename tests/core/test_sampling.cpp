// Samplers against their pdfs: normalisation, moments, chi-square; Fresnel
// limits; light estimators against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "scene/lights.h"
#include "chi_square.h"

namespace vdbmarch {
namespace {

using testing::chiSquareQ;

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
    double chi2 = 0, accO = 0, accE = 0;
    int dof = -1;
    for (int b = 0; b < bins; ++b) {
        accO += observed[size_t(b)];
        accE += expected[size_t(b)];
        if (accE >= 5 || b == bins - 1) {
            chi2 += (accO - accE) * (accO - accE) / accE;
            accO = accE = 0;
            ++dof;
        }
    }
    double p = chiSquareQ(chi2, dof);
    EXPECT_GT(p, 1e-4) << "chi2 " << chi2 << " dof " << dof << " g " << g;
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

// A sphere light of radiance L seen from distance d gives irradiance
// E = pi L (r/d)^2 on a surface facing it; the cone sampler's L/pdf averaged
// with the cosine must match, within 4 standard errors.
TEST(SphereLight, ConeSamplingEstimatesTheIrradianceOfASphere) {
    LightDesc d;
    d.type = LightDesc::Type::Sphere;
    d.position = Vec3(0, 0, 3);
    d.radius = 1;
    d.power = Vec3(10);
    Light light(d);
    const double L = light.emittedRadiance().x, r = 1, dist = 3;
    const double expected = M_PI * L * (r / dist) * (r / dist);
    Rng rng(9);
    const int n = 200000;
    double s = 0, s2 = 0;
    for (int i = 0; i < n; ++i) {
        LightSample ls;
        ASSERT_TRUE(light.sample(Vec3(0), rng.uniform(), rng.uniform(), ls));
        double v = ls.L.x * std::max(0.f, ls.wi.z);
        s += v;
        s2 += v * v;
        EXPECT_NEAR(length(ls.wi * ls.dist - d.position), r, 1e-4);  // lands on the sphere
    }
    double mean = s / n, se = std::sqrt((s2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, expected, 4 * se + 1e-9);
}

TEST(SpotLight, SmoothFalloffBetweenConeAndFalloffStart) {
    LightDesc d;
    d.type = LightDesc::Type::Spot;
    d.position = Vec3(0, 0, 0);
    d.direction = Vec3(0, 0, -1);
    d.intensity = Vec3(4);
    d.coneDeg = 30;
    d.falloffDeg = 10;
    Light light(d);
    auto at = [&](float deg) {
        LightSample ls;
        Vec3 x(std::sin(radians(deg)) * 2, 0, -std::cos(radians(deg)) * 2);
        return light.sample(x, 0, 0, ls) ? ls.L.x : 0.f;
    };
    EXPECT_NEAR(at(0), 1.0, 1e-6);    // I / d^2 = 4 / 4
    EXPECT_NEAR(at(19), 1.0, 1e-6);   // inside the full-intensity core
    EXPECT_GT(at(25), 0.0);
    EXPECT_LT(at(25), 1.0);
    EXPECT_EQ(at(31), 0.0);           // outside the cone
}

TEST(CollimatedQuad, LightsOnlyItsBeam) {
    LightDesc d;
    d.type = LightDesc::Type::CollimatedQuad;
    d.center = Vec3(0, 5, 0);
    d.u = Vec3(2, 0, 0);
    d.v = Vec3(0, 0, 1);
    d.direction = Vec3(0, -1, 0);
    d.irradiance = Vec3(3);
    Light light(d);
    LightSample ls;
    ASSERT_TRUE(light.sample(Vec3(0.9f, 0, 0.4f), 0, 0, ls));
    EXPECT_NEAR(ls.dist, 5, 1e-5);
    EXPECT_EQ(ls.L.x, 3);
    EXPECT_FALSE(light.sample(Vec3(1.1f, 0, 0), 0, 0, ls));  // beside the quad
    EXPECT_FALSE(light.sample(Vec3(0, 6, 0), 0, 0, ls));     // above the emitter
}

}  // namespace
}  // namespace vdbmarch
