// Product sampling of the continuation direction (cache/product_sampler.h):
// the sampler against its own pdf (chi-square), the pdf's normalisation, the
// unbiasedness of weight = f / pdf, the variance gain over phase sampling, and
// determinism. Cases: isotropic phase with a peaked radiance lobe, a forward
// Henyey-Greenstein lobe lit from the side, a two-lobe mixture, coefficients
// with large negative regions, and no light at all (phase sampling only).
//
// Quadrature: the histogram cells and the quadrature cells below are aligned
// with the table's bins (3 x 3 cells per bin), so the table part of the pdf is
// constant on each cell and only the smooth phase part is integrated
// numerically (Gauss-Legendre in z and phi per cell, far more accurate than
// the counts' statistical error).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "cache/product_sampler.h"
#include "cache/sh.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "transport/phase.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using test::PiD;
using PS = ProductDirectionSampler;
using Coeffs = std::array<float, 16>;

Vec3 fromZPhi(double z, double phi) {
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    return Vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
}

// Integral of f(w) over the sphere: the table's grid refined `sub` x `sub`
// times per bin, n x n Gauss-Legendre nodes in (z, phi) per cell.
template <typename F>
double sphereIntegral(F&& f, int sub, int n) {
    std::vector<double> x, w;
    gaussLegendre(n, x, w);
    const int nz = PS::Nz * sub, np = PS::Nphi * sub;
    const double dz = 2.0 / nz, dp = 2 * PiD / np;
    double sum = 0;
    for (int iz = 0; iz < nz; ++iz)
        for (int ip = 0; ip < np; ++ip)
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    const double z = -1 + (iz + 0.5 + 0.5 * x[size_t(a)]) * dz;
                    const double phi = (ip + 0.5 + 0.5 * x[size_t(b)]) * dp;
                    sum += f(fromZPhi(z, phi)) * w[size_t(a)] * w[size_t(b)] * 0.25 * dz * dp;
                }
    return sum;
}

// The SH projection (order 3) of a von Mises-Fisher lobe of light travelling
// along `axis`, L(w') = scale * exp(kappa (dot(w', axis) - 1)), plus `ambient`.
Coeffs lobe(const Vec3& axis, double kappa, double scale = 1, double ambient = 0) {
    Coeffs c{};
    std::vector<double> x, w;
    gaussLegendre(96, x, w);
    const int nPhi = 192;
    for (size_t i = 0; i < x.size(); ++i)
        for (int j = 0; j < nPhi; ++j) {
            const Vec3 d = fromZPhi(x[i], 2 * PiD * (j + 0.5) / nPhi);
            const double L = scale * std::exp(kappa * (double(dot(d, axis)) - 1)) + ambient;
            float Y[16];
            evalSh(3, d, Y);
            for (int k = 0; k < 16; ++k) c[size_t(k)] += float(L * Y[k] * w[i] * 2 * PiD / nPhi);
        }
    return c;
}

float radiance(const Coeffs& c, const Vec3& travel) {
    float Y[16];
    evalSh(3, travel, Y);
    return evalShNonNegative(16, c.data(), Y);
}

PhaseMixture single(float g) {
    PhaseMixture m;
    m.add(Color(1), g);
    return m;
}

struct Case {
    const char* name;
    PhaseMixture phase;
    Vec3 rayDir;
    Coeffs coeffs;
    bool expectTable;
};

std::vector<Case> cases() {
    const Vec3 ray = normalize(Vec3(0.3f, -0.5f, 0.8f));
    Vec3 s, t;
    coordinateSystem(ray, s, t);
    PhaseMixture two;
    two.add(Color(1.0f, 0.5f, 0.2f), 0.7f);
    two.add(Color(0.3f, 0.6f, 0.9f), -0.5f);
    Coeffs negative;
    Rng rng(99);
    for (float& v : negative) v = 2 * rng.uniform() - 1;
    negative[0] = 0.2f;  // small mean: large regions where the expansion is < 0
    return {
        {"IsotropicPeakedLobe", single(0), ray, lobe(normalize(Vec3(-0.2f, 0.6f, -0.77f)), 30), true},
        {"ForwardHgSideLight", single(0.8f), ray, lobe(s, 10), true},
        {"TwoLobeMixture", two, ray, lobe(normalize(Vec3(0.5f, 0.5f, -0.7f)), 15, 1, 0.05), true},
        {"NegativeRegions", single(0.3f), ray, negative, true},
        {"NoLight", single(0.5f), ray, Coeffs{}, false},
    };
}

class ProductSamplerCase : public ::testing::TestWithParam<int> {
protected:
    void SetUp() override {
        all = cases();
        c = &all[size_t(GetParam())];
        built = sampler.build(3, c->coeffs.data(), c->phase, c->rayDir);
    }
    std::vector<Case> all;
    const Case* c = nullptr;
    PS sampler;
    bool built = false;
};

std::string caseName(const ::testing::TestParamInfo<int>& info) { return cases()[size_t(info.param)].name; }

TEST_P(ProductSamplerCase, BuildsATableOnlyWhereLightIs) {
    EXPECT_EQ(built, c->expectTable);
    EXPECT_EQ(sampler.hasTable(), c->expectTable);
}

TEST_P(ProductSamplerCase, SamplerMatchesPdfChiSquare) {
    const int sub = 3, nz = PS::Nz * sub, np = PS::Nphi * sub, samples = 1000000;
    std::vector<double> observed(size_t(nz * np), 0), expected(size_t(nz * np), 0);
    Rng rng(17);
    int pdfMismatches = 0, fromTable = 0, phaseOnly = 0;
    for (int i = 0; i < samples; ++i) {
        const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        const ProductSample s = sampler.sample(u0, u1, u2);
        ASSERT_GT(s.pdf, 0);
        ASSERT_NEAR(length(s.wi), 1.f, 1e-5f);
        if (s.pdf != sampler.pdf(s.wi)) ++pdfMismatches;
        fromTable += s.from == ProductSample::From::Table;
        phaseOnly += s.from == ProductSample::From::PhaseOnly;
        double phi = std::atan2(double(s.wi.y), double(s.wi.x));
        if (phi < 0) phi += 2 * PiD;
        const int iz = std::min(nz - 1, int((double(s.wi.z) + 1) / 2 * nz));
        const int ip = std::min(np - 1, int(phi / (2 * PiD) * np));
        observed[size_t(iz * np + ip)] += 1;
    }
    EXPECT_EQ(pdfMismatches, 0) << "sample().pdf differs from pdf(wi)";
    if (c->expectTable) {
        // About 1 - eps of the samples come from the table.
        EXPECT_NEAR(fromTable / double(samples), 1 - PS::DefaultDefensive, 0.01);
        EXPECT_EQ(phaseOnly, 0);
    } else {
        EXPECT_EQ(phaseOnly, samples);
    }
    std::vector<double> x, w;
    gaussLegendre(8, x, w);
    const double dz = 2.0 / nz, dp = 2 * PiD / np;
    for (int iz = 0; iz < nz; ++iz)
        for (int ip = 0; ip < np; ++ip) {
            double mass = 0;
            for (size_t a = 0; a < x.size(); ++a)
                for (size_t b = 0; b < x.size(); ++b) {
                    const Vec3 d = fromZPhi(-1 + (iz + 0.5 + 0.5 * x[a]) * dz, (ip + 0.5 + 0.5 * x[b]) * dp);
                    mass += double(sampler.pdf(d)) * w[a] * w[b] * 0.25 * dz * dp;
                }
            expected[size_t(iz * np + ip)] = mass * samples;
        }
    const test::ChiSquare chi = test::pooledChiSquare(observed, expected, 5);
    std::printf("[ chi2     ] %-20s chi2 %.1f dof %d p %.3f\n", c->name, chi.chi2, chi.dof, chi.p());
    ASSERT_GT(chi.dof, 500);
    EXPECT_GT(chi.p(), 1e-3) << "chi2 " << chi.chi2 << " dof " << chi.dof;
}

TEST_P(ProductSamplerCase, PdfIntegratesToOne) {
    auto f = [&](const Vec3& d) { return double(sampler.pdf(d)); };
    const double coarse = sphereIntegral(f, 2, 6), fine = sphereIntegral(f, 4, 8);
    // The table part is exact on these aligned cells; the phase part's error
    // is estimated by the difference of the two rules (plus float rounding).
    EXPECT_NEAR(fine, 1.0, 1e-5 + 10 * std::fabs(fine - coarse)) << "coarse " << coarse;
    EXPECT_LT(std::fabs(fine - coarse), 1e-4);
    if (c->expectTable) {
        EXPECT_NEAR(sphereIntegral([&](const Vec3& d) { return double(sampler.tablePdf(d)); }, 1, 1), 1.0, 1e-5);
    }
}

// Smooth, sign-changing test function of the direction.
double testFunction(const Vec3& w) { return 1 + 0.5 * w.x - 0.7 * w.y * w.z + 0.4 * std::exp(2.0 * w.z); }

TEST_P(ProductSamplerCase, WeightIsUnbiased) {
    // Reference: Int f(dot(rayDir, w)) g(w) dw per channel, in the frame of
    // rayDir (Gauss-Legendre in the cosine, where the lobe lives, x uniform
    // azimuth, spectrally accurate for the periodic integrand).
    Vec3 s, t;
    coordinateSystem(c->rayDir, s, t);
    std::vector<double> x, w;
    gaussLegendre(512, x, w);
    const int nPhi = 256;
    double ref[3] = {0, 0, 0};
    for (size_t i = 0; i < x.size(); ++i) {
        const Color f = c->phase.eval(float(x[i]));
        const double r = std::sqrt(1 - x[i] * x[i]);
        for (int j = 0; j < nPhi; ++j) {
            const double phi = 2 * PiD * (j + 0.5) / nPhi;
            const Vec3 d = s * float(r * std::cos(phi)) + t * float(r * std::sin(phi)) + c->rayDir * float(x[i]);
            const double g = testFunction(d) * w[i] * 2 * PiD / nPhi;
            for (int ch = 0; ch < 3; ++ch) ref[ch] += f[ch] * g;
        }
    }
    test::SampleStats stats[3];
    Rng rng(23);
    for (int i = 0; i < 1000000; ++i) {
        const ProductSample smp = sampler.sample(rng.uniform(), rng.uniform(), rng.uniform());
        const double g = testFunction(smp.wi);
        for (int ch = 0; ch < 3; ++ch) stats[ch].add(smp.weight[ch] * g);
    }
    for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(stats[ch].mean(), ref[ch], 4 * stats[ch].stdError()) << "channel " << ch;
}

INSTANTIATE_TEST_SUITE_P(Cases, ProductSamplerCase, ::testing::Range(0, 5), caseName);

TEST(ProductSampler, NoLightFallsBackToPhaseSampling) {
    const PhaseMixture phase = single(0.5f);
    const Vec3 ray = normalize(Vec3(1, 2, 3));
    const Coeffs zero{};
    Coeffs darkEverywhere{};
    darkEverywhere[0] = -1;  // negative everywhere: clamped to zero
    Coeffs nan{};
    nan[0] = std::nanf("");
    for (const Coeffs* cs : {&zero, static_cast<const Coeffs*>(&darkEverywhere), static_cast<const Coeffs*>(&nan)}) {
        PS sampler;
        EXPECT_FALSE(sampler.build(3, cs->data(), phase, ray));
        Rng rng(3);
        for (int i = 0; i < 100; ++i) {
            const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
            const ProductSample s = sampler.sample(u0, u1, u2);
            Color w(1);
            float pdf;
            const Vec3 wi = phase.sample(ray, u0, u1, u2, w, pdf);
            EXPECT_EQ(s.from, ProductSample::From::PhaseOnly);
            EXPECT_EQ(s.wi, wi);  // exactly phase sampling
            EXPECT_EQ(s.pdf, phase.pdf(dot(ray, wi)));
            EXPECT_FLOAT_EQ(s.weight.x, 1.f);
        }
    }
}

TEST(ProductSampler, EmptyPhaseSamplesNothing) {
    PhaseMixture none;
    const Coeffs c = lobe(Vec3(0, 0, 1), 5);
    PS sampler;
    EXPECT_FALSE(sampler.build(3, c.data(), none, Vec3(0, 0, 1)));
    const ProductSample s = sampler.sample(0.5f, 0.5f, 0.5f);
    EXPECT_EQ(s.pdf, 0.f);
    EXPECT_TRUE(isBlack(s.weight));
    EXPECT_EQ(sampler.pdf(Vec3(0, 0, 1)), 0.f);
}

TEST(ProductSampler, DefensiveComponentBoundsTheWeight) {
    // One lobe: weight = f / (eps f + (1 - eps) t) <= 1 / eps.
    const PhaseMixture phase = single(0.9f);
    const Vec3 ray = normalize(Vec3(0.3f, -0.5f, 0.8f));
    const Coeffs c = lobe(normalize(Vec3(1, 1, 0)), 40);
    PS sampler;
    ASSERT_TRUE(sampler.build(3, c.data(), phase, ray));
    Rng rng(5);
    float maxWeight = 0;
    for (int i = 0; i < 200000; ++i)
        maxWeight = std::max(maxWeight, sampler.sample(rng.uniform(), rng.uniform(), rng.uniform()).weight.x);
    EXPECT_LE(maxWeight, 1 / PS::DefaultDefensive * (1 + 1e-5f));
    EXPECT_GT(maxWeight, 1.f);
}

TEST(ProductSampler, BinsRoundTrip) {
    for (int b = 0; b < PS::Bins; ++b) {
        float z0, z1, p0, p1;
        PS::binBounds(b, z0, z1, p0, p1);
        EXPECT_EQ(PS::binOf(fromZPhi(0.5 * (z0 + z1), 0.5 * (p0 + p1))), b);
    }
    EXPECT_EQ(PS::binOf(Vec3(0, 0, 1)) / PS::Nphi, PS::Nz - 1);
    EXPECT_EQ(PS::binOf(Vec3(0, 0, -1)) / PS::Nphi, 0);
}

TEST(ProductSampler, SameUniformsGiveTheSameSample) {
    const Case c = cases()[2];
    PS a, b;
    ASSERT_TRUE(a.build(3, c.coeffs.data(), c.phase, c.rayDir));
    ASSERT_TRUE(b.build(3, c.coeffs.data(), c.phase, c.rayDir));
    Rng rng(11);
    for (int i = 0; i < 1000; ++i) {
        const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        const ProductSample s1 = a.sample(u0, u1, u2), s2 = a.sample(u0, u1, u2), s3 = b.sample(u0, u1, u2);
        EXPECT_EQ(s1.wi, s2.wi);
        EXPECT_EQ(s1.wi, s3.wi);
        EXPECT_EQ(s1.pdf, s3.pdf);
        EXPECT_EQ(s1.weight, s3.weight);
        EXPECT_EQ(s1.from, s3.from);
    }
}

// Variance of the in-scattering estimate weight * L(-wi), L the clamped SH
// radiance itself, with product sampling against plain phase sampling, at the
// same sample count. Also prints the variance over eps (the choice of
// DefaultDefensive).
struct VarianceResult {
    double mean, variance;
};

VarianceResult productVariance(const Case& c, float eps, int n) {
    PS sampler(eps);
    sampler.build(3, c.coeffs.data(), c.phase, c.rayDir);
    test::SampleStats st;
    Rng rng(31);
    for (int i = 0; i < n; ++i) {
        const ProductSample s = sampler.sample(rng.uniform(), rng.uniform(), rng.uniform());
        st.add(average(s.weight) * radiance(c.coeffs, -s.wi));
    }
    return {st.mean(), st.variance()};
}

VarianceResult phaseVariance(const Case& c, int n) {
    test::SampleStats st;
    Rng rng(31);
    for (int i = 0; i < n; ++i) {
        Color w(1);
        float pdf;
        const Vec3 wi = c.phase.sample(c.rayDir, rng.uniform(), rng.uniform(), rng.uniform(), w, pdf);
        st.add(average(w) * radiance(c.coeffs, -wi));
    }
    return {st.mean(), st.variance()};
}

TEST(ProductSampler, VarianceAgainstPhaseSampling) {
    const int n = 400000;
    const std::vector<Case> all = cases();
    for (int k : {0, 1, 2, 3}) {
        const Case& c = all[size_t(k)];
        const VarianceResult ph = phaseVariance(c, n), pr = productVariance(c, PS::DefaultDefensive, n);
        std::printf("[ variance ] %-20s mean %.5f / %.5f  var phase %.3e  product %.3e  ratio %.3f   eps:", c.name,
                    ph.mean, pr.mean, ph.variance, pr.variance, pr.variance / ph.variance);
        for (float eps : {0.1f, 0.2f, 0.3f, 0.4f, 0.5f}) std::printf(" %.1f:%.3f", double(eps),
                                                                    productVariance(c, eps, n / 4).variance / ph.variance);
        std::printf("\n");
        // Both estimate the same integral.
        EXPECT_NEAR(pr.mean, ph.mean, 4 * std::sqrt((ph.variance + pr.variance) / n)) << c.name;
        // Peaked radiance under a broad or side-lit phase: a clear gain.
        if (k == 0 || k == 1) {
            EXPECT_LT(pr.variance, 0.5 * ph.variance) << c.name;
        }
    }
}

}  // namespace
}  // namespace vdbmarch
