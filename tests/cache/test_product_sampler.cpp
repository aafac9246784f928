// Product sampling of the continuation direction (cache/product_sampler.h)
// and the direction lobes it reads (cache/direction_lobes.h): the sampler
// against its own pdf (chi-square), the pdf's normalisation, the
// unbiasedness of weight = f / pdf, the variance gain over phase sampling,
// and determinism; the lobe fit against the distribution its photons came
// from. Cases: isotropic phase with a peaked light, a forward
// Henyey-Greenstein lobe lit from the side, a two-lobe phase mixture with two
// lights and ambient light, a backward lobe, and no light at all (phase
// sampling only).
//
// Quadrature: Gauss-Legendre in z and phi per cell of a fine grid, far more
// accurate than the counts' statistical error for lobes this wide.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "cache/direction_lobes.h"
#include "cache/product_sampler.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "transport/phase.h"
#include "support/sphere_quadrature.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using test::PiD;
using PS = ProductDirectionSampler;
using Lobes = std::array<float, DirectionLobes::Floats>;

using test::fromZPhi;
using test::sphereIntegral;

// Photons whose light a path meets in direction wi: `count` around `axis`
// (vMF, concentration kappa) with total weight `power`.
struct Photons {
    std::vector<Vec3> wi;
    std::vector<float> w;
    void add(const Vec3& axis, float kappa, float power, int count, uint64_t seed) {
        const VmfLobe l = VmfLobe::make(axis, kappa, 1);
        Rng rng(seed);
        for (int i = 0; i < count; ++i) {
            wi.push_back(l.sample(rng.uniform(), rng.uniform()));
            w.push_back(power / float(count) * (0.5f + rng.uniform()));
        }
    }
    Lobes fit() const {
        Lobes out{};
        DirectionLobes::fit(wi.data(), w.data(), int(wi.size()), out.data());
        return out;
    }
};

PhaseMixture single(float g) {
    PhaseMixture m;
    m.add(Color(1), g);
    return m;
}

struct Case {
    const char* name;
    PhaseMixture phase;
    Vec3 rayDir;
    Lobes lobes;
    bool expectLobes;
};

std::vector<Case> cases() {
    const Vec3 ray = normalize(Vec3(0.3f, -0.5f, 0.8f));
    Vec3 s, t;
    coordinateSystem(ray, s, t);
    PhaseMixture two;
    two.add(Color(1.0f, 0.5f, 0.2f), 0.7f);
    two.add(Color(0.3f, 0.6f, 0.9f), -0.5f);
    Photons peaked, side, twoLights, ring;
    peaked.add(normalize(Vec3(-0.2f, 0.6f, -0.77f)), 30, 1, 40, 1);
    side.add(s, 10, 1, 60, 2);
    twoLights.add(normalize(Vec3(0.5f, 0.5f, -0.7f)), 15, 1, 30, 3);
    twoLights.add(t, 40, 0.5f, 20, 4);
    twoLights.add(Vec3(0, 0, 1), 0, 0.3f, 20, 5);  // ambient
    ring.add(normalize(t - ray), 5, 1, 50, 6);
    return {
        {"IsotropicPeakedLight", single(0), ray, peaked.fit(), true},
        {"ForwardHgSideLight", single(0.8f), ray, side.fit(), true},
        {"TwoLobeMixtureTwoLights", two, ray, twoLights.fit(), true},
        {"BackwardHg", single(-0.5f), ray, ring.fit(), true},
        {"NoLight", single(0.5f), ray, Lobes{}, false},
    };
}

class ProductSamplerCase : public ::testing::TestWithParam<int> {
protected:
    void SetUp() override {
        all = cases();
        c = &all[size_t(GetParam())];
        built = sampler.build(DirectionLobes::prepare(c->lobes.data()), c->phase, c->rayDir);
    }
    std::vector<Case> all;
    const Case* c = nullptr;
    PS sampler;
    bool built = false;
};

std::string caseName(const ::testing::TestParamInfo<int>& info) { return cases()[size_t(info.param)].name; }

TEST_P(ProductSamplerCase, BuildsLobesOnlyWhereLightIs) {
    EXPECT_EQ(built, c->expectLobes);
    EXPECT_EQ(sampler.hasLobes(), c->expectLobes);
}

TEST_P(ProductSamplerCase, SamplerMatchesPdfChiSquare) {
    const int nz = 24, np = 48, samples = 1000000;
    std::vector<double> observed(size_t(nz * np), 0), expected(size_t(nz * np), 0);
    Rng rng(17);
    int pdfMismatches = 0, fromLobes = 0, phaseOnly = 0;
    for (int i = 0; i < samples; ++i) {
        const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        const ProductSample s = sampler.sample(u0, u1, u2);
        ASSERT_GT(s.pdf, 0);
        ASSERT_NEAR(length(s.wi), 1.f, 1e-5f);
        if (s.pdf != sampler.pdf(s.wi)) ++pdfMismatches;
        fromLobes += s.from == ProductSample::From::Lobes;
        phaseOnly += s.from == ProductSample::From::PhaseOnly;
        double phi = std::atan2(double(s.wi.y), double(s.wi.x));
        if (phi < 0) phi += 2 * PiD;
        const int iz = std::min(nz - 1, int((double(s.wi.z) + 1) / 2 * nz));
        const int ip = std::min(np - 1, int(phi / (2 * PiD) * np));
        observed[size_t(iz * np + ip)] += 1;
    }
    EXPECT_EQ(pdfMismatches, 0) << "sample().pdf differs from pdf(wi)";
    if (c->expectLobes) {
        // 1 - eps of the samples come from the lobes: binomial, 4 sigma.
        const double p = 1 - PS::DefaultDefensive;
        EXPECT_NEAR(fromLobes / double(samples), p, 4 * std::sqrt(p * (1 - p) / samples));
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
    std::printf("[ chi2     ] %-24s chi2 %.1f dof %d p %.3f\n", c->name, chi.chi2, chi.dof, chi.p());
    ASSERT_GT(chi.dof, 500);
    EXPECT_GT(chi.p(), 1e-3) << "chi2 " << chi.chi2 << " dof " << chi.dof;
}

TEST_P(ProductSamplerCase, PdfIntegratesToOne) {
    auto f = [&](const Vec3& d) { return double(sampler.pdf(d)); };
    const double coarse = sphereIntegral(f, 48, 6), fine = sphereIntegral(f, 96, 8);
    // The quadrature's error is estimated by the difference of the two rules
    // (plus float rounding).
    EXPECT_NEAR(fine, 1.0, 1e-5 + 10 * std::fabs(fine - coarse)) << "coarse " << coarse;
    EXPECT_LT(std::fabs(fine - coarse), 1e-4);
    if (c->expectLobes) {
        EXPECT_NEAR(sphereIntegral([&](const Vec3& d) { return double(sampler.lobesPdf(d)); }, 96, 8), 1.0, 1e-4);
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
    const Lobes zero{};
    Lobes nan{};
    nan[0] = std::nanf("");
    nan[1] = 1;
    Lobes infinite{};
    infinite[0] = INFINITY;
    for (const Lobes* ls : {&zero, static_cast<const Lobes*>(&nan), static_cast<const Lobes*>(&infinite)}) {
        PS sampler;
        EXPECT_FALSE(sampler.build(DirectionLobes::prepare(ls->data()), phase, ray));
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
    Photons ph;
    ph.add(Vec3(0, 0, 1), 5, 1, 30, 7);
    const Lobes l = ph.fit();
    PS sampler;
    EXPECT_FALSE(sampler.build(DirectionLobes::prepare(l.data()), none, Vec3(0, 0, 1)));
    const ProductSample s = sampler.sample(0.5f, 0.5f, 0.5f);
    EXPECT_EQ(s.pdf, 0.f);
    EXPECT_TRUE(isBlack(s.weight));
    EXPECT_EQ(sampler.pdf(Vec3(0, 0, 1)), 0.f);
}

TEST(ProductSampler, DefensiveComponentBoundsTheWeight) {
    // One lobe: weight = f / (eps f + (1 - eps) t) <= 1 / eps.
    const PhaseMixture phase = single(0.9f);
    const Vec3 ray = normalize(Vec3(0.3f, -0.5f, 0.8f));
    Photons ph;
    ph.add(normalize(Vec3(1, 1, 0)), 40, 1, 50, 8);
    const Lobes l = ph.fit();
    PS sampler;
    ASSERT_TRUE(sampler.build(DirectionLobes::prepare(l.data()), phase, ray));
    Rng rng(5);
    float maxWeight = 0;
    for (int i = 0; i < 200000; ++i)
        maxWeight = std::max(maxWeight, sampler.sample(rng.uniform(), rng.uniform(), rng.uniform()).weight.x);
    EXPECT_LE(maxWeight, 1 / PS::DefaultDefensive * (1 + 1e-5f));
    EXPECT_GT(maxWeight, 1.f);
}

TEST(ProductSampler, SameUniformsGiveTheSameSample) {
    const Case c = cases()[2];
    PS a, b;
    ASSERT_TRUE(a.build(DirectionLobes::prepare(c.lobes.data()), c.phase, c.rayDir));
    ASSERT_TRUE(b.build(DirectionLobes::prepare(c.lobes.data()), c.phase, c.rayDir));
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

// The radiance the lobes describe, as a function of the direction a path
// takes: sum_j W_j vMF_j(wi).
double lobeRadiance(const Lobes& l, const Vec3& wi) {
    double L = 0;
    for (int j = 0; j < DirectionLobes::MaxLobes; ++j) {
        VmfLobe v;
        if (DirectionLobes::lobe(l.data(), j, v)) L += double(v.weight) * double(v.pdf(wi));
    }
    return L;
}

// Variance of the in-scattering estimate weight * L(wi), L the radiance
// the lobes describe, with product sampling against plain phase sampling,
// at the same sample count. Also prints the variance over eps (the choice
// of DefaultDefensive).
struct VarianceResult {
    double mean, variance;
};

VarianceResult productVariance(const Case& c, float eps, int n) {
    PS sampler(eps);
    sampler.build(DirectionLobes::prepare(c.lobes.data()), c.phase, c.rayDir);
    test::SampleStats st;
    Rng rng(31);
    for (int i = 0; i < n; ++i) {
        const ProductSample s = sampler.sample(rng.uniform(), rng.uniform(), rng.uniform());
        st.add(average(s.weight) * lobeRadiance(c.lobes, s.wi));
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
        st.add(average(w) * lobeRadiance(c.lobes, wi));
    }
    return {st.mean(), st.variance()};
}

TEST(ProductSampler, VarianceAgainstPhaseSampling) {
    const int n = 400000;
    const std::vector<Case> all = cases();
    for (int k : {0, 1, 2, 3}) {
        const Case& c = all[size_t(k)];
        const VarianceResult ph = phaseVariance(c, n), pr = productVariance(c, PS::DefaultDefensive, n);
        std::printf("[ variance ] %-24s mean %.5f / %.5f  var phase %.3e  product %.3e  ratio %.3f   eps:", c.name,
                    ph.mean, pr.mean, ph.variance, pr.variance, pr.variance / ph.variance);
        for (float eps : {0.1f, 0.2f, 0.3f, 0.4f, 0.5f}) std::printf(" %.1f:%.3f", double(eps),
                                                                    productVariance(c, eps, n / 4).variance / ph.variance);
        std::printf("\n");
        // Both estimate the same integral.
        EXPECT_NEAR(pr.mean, ph.mean, 4 * std::sqrt((ph.variance + pr.variance) / n)) << c.name;
        // Peaked light under a broad or side-lit phase: a clear gain.
        if (k == 0 || k == 1) {
            EXPECT_LT(pr.variance, 0.5 * ph.variance) << c.name;
        }
    }
}

// Concentration of a vMF lobe from its mean resultant length A(kappa) =
// coth(kappa) - 1 / kappa, by bisection (the exact inverse, against which
// Banerjee's approximation is checked).
double exactKappa(double r) {
    double lo = 1e-6, hi = 1e4;
    for (int i = 0; i < 200; ++i) {
        const double m = 0.5 * (lo + hi);
        (1 / std::tanh(m) - 1 / m < r ? lo : hi) = m;
    }
    return 0.5 * (lo + hi);
}

TEST(DirectionLobes, FitRecoversOneLobe) {
    const Vec3 axis = normalize(Vec3(0.2f, -0.9f, 0.4f));
    for (float kappa : {2.f, 20.f, 200.f}) {
        Photons ph;
        ph.add(axis, kappa, 1, 20000, 41);
        const Lobes l = ph.fit();
        VmfLobe v;
        ASSERT_TRUE(DirectionLobes::lobe(l.data(), 0, v));
        int others = 0;
        for (int j = 1; j < DirectionLobes::MaxLobes; ++j) others += l[size_t(j * DirectionLobes::LobeFloats)] > 0;
        // A single lobe may be split by k-means only where it is broad.
        if (kappa >= 20) {
            EXPECT_EQ(others, 0) << kappa;
        }
        if (others > 0) continue;
        // Mean direction: the standard error of the sample mean direction is
        // about 1 / sqrt(N kappa) radians; 4 of those.
        EXPECT_GT(dot(v.mu, axis), std::cos(4 / std::sqrt(20000.0 * kappa))) << kappa;
        // Concentration: the sample's mean resultant length has a standard
        // error of about sqrt(A'(kappa) / N) and Banerjee's approximation
        // differs from the exact inverse by under 3 % here.
        const double A = 1 / std::tanh(double(kappa)) - 1 / double(kappa);
        const double dA = 1 / (double(kappa) * kappa) - 1 / (std::sinh(double(kappa)) * std::sinh(double(kappa)));
        const double rLo = A - 4 * std::sqrt(dA / 20000), rHi = A + 4 * std::sqrt(dA / 20000);
        EXPECT_GT(v.kappa, 0.97 * exactKappa(rLo)) << kappa;
        EXPECT_LT(v.kappa, 1.03 * exactKappa(std::min(rHi, 0.9999))) << kappa;
    }
}

TEST(DirectionLobes, FitSeparatesTwoLights) {
    Photons ph;
    const Vec3 a = normalize(Vec3(1, 0, 0.2f)), b = normalize(Vec3(-0.3f, 1, -0.5f));
    ph.add(a, 50, 3, 300, 51);
    ph.add(b, 80, 1, 200, 52);
    const Lobes l = ph.fit();
    double wa = 0, wb = 0, total = 0;
    for (size_t i = 0; i < ph.w.size(); ++i) (i < 300 ? wa : wb) += ph.w[i];
    int found = 0;
    for (int j = 0; j < DirectionLobes::MaxLobes; ++j) {
        VmfLobe v;
        if (!DirectionLobes::lobe(l.data(), j, v)) continue;
        total += v.weight;
        if (dot(v.mu, a) > 0.99f) {
            EXPECT_NEAR(v.weight, wa, 1e-3 * wa);
            ++found;
        }
        if (dot(v.mu, b) > 0.99f) {
            EXPECT_NEAR(v.weight, wb, 1e-3 * wb);
            ++found;
        }
    }
    EXPECT_EQ(found, 2);
    EXPECT_NEAR(total, wa + wb, 1e-3 * (wa + wb));
}

TEST(DirectionLobes, UniformLightGivesBroadLobes) {
    // Directions from everywhere: the small-sample correction keeps the
    // concentrations low instead of reading 1 / sqrt(N) as a lobe.
    Photons ph;
    ph.add(Vec3(0, 0, 1), 0, 1, 40, 61);
    const Lobes l = ph.fit();
    for (int j = 0; j < DirectionLobes::MaxLobes; ++j) {
        VmfLobe v;
        if (DirectionLobes::lobe(l.data(), j, v)) {
            EXPECT_LT(v.kappa, 6.f) << j;
        }
    }
}

TEST(DirectionLobes, BatchesAverageLikeTheirPhotons) {
    // Two batches: the second assigned to the first's lobes, averaged with
    // weights 1/2, give the statistics of all photons at half weight.
    const Vec3 a = normalize(Vec3(1, 0, 0.2f)), b = normalize(Vec3(-0.3f, 1, -0.5f));
    Photons first, second;
    first.add(a, 50, 2, 100, 71);
    first.add(b, 80, 1, 100, 72);
    second.add(a, 50, 2, 100, 73);
    second.add(b, 80, 1, 100, 74);
    Lobes stats = first.fit(), fresh{};
    DirectionLobes::assign(stats.data(), second.wi.data(), second.w.data(), int(second.wi.size()), fresh.data());
    DirectionLobes::average(stats.data(), fresh.data(), 0.5f, 0.5f);
    double W = 0, N = 0;
    for (int j = 0; j < DirectionLobes::MaxLobes; ++j) {
        W += stats[size_t(j * DirectionLobes::LobeFloats)];
        N += stats[size_t(j * DirectionLobes::LobeFloats + 4)];
    }
    double expectW = 0;
    for (float w : first.w) expectW += 0.5 * w;
    for (float w : second.w) expectW += 0.5 * w;
    EXPECT_NEAR(W, expectW, 1e-5 * expectW);
    EXPECT_EQ(N, 400);
}

TEST(VmfLobe, SamplerMatchesPdfAndNormalisation) {
    for (float kappa : {0.f, 0.5f, 8.f, 120.f}) {
        const VmfLobe v = VmfLobe::make(normalize(Vec3(0.3f, 0.4f, -0.5f)), kappa, 1);
        // Normalisation, in the lobe's frame (all the mass near cos = 1).
        std::vector<double> x, w;
        gaussLegendre(256, x, w);
        double mass = 0;
        Vec3 s, t;
        coordinateSystem(v.mu, s, t);
        const double h = kappa > 10 ? 0.05 : 1.0;  // cosines over [1 - 2h, 1]
        for (size_t i = 0; i < x.size(); ++i) {
            const double c = 1 - (1 - x[i]) * h;
            const Vec3 d = v.mu * float(c) + s * float(std::sqrt(std::max(0.0, 1 - c * c)));
            mass += double(v.pdf(d)) * w[i] * h * 2 * PiD;
        }
        EXPECT_NEAR(mass, 1.0, 1e-4) << kappa;  // kappa 120: e^{-12} of the mass lies below 0.9
        // The sampled cosine's distribution against the pdf's (chi-square on
        // the cosine, where all the structure of a vMF lobe lies).
        const int bins = 100, n = 200000;
        std::vector<double> observed(bins, 0), expected(bins, 0);
        Rng rng(81);
        const double lo = kappa > 10 ? 0.9 : -1.0;
        for (int i = 0; i < n; ++i) {
            const double c = dot(v.sample(rng.uniform(), rng.uniform()), v.mu);
            observed[size_t(std::min(bins - 1, std::max(0, int((c - lo) / (1 - lo) * bins))))] += 1;
        }
        for (int b = 0; b < bins; ++b) {
            // Mass of [c0, c1): 2 pi int C e^{kappa c} dc, closed form.
            const double c0 = lo + (1 - lo) * b / bins, c1 = lo + (1 - lo) * (b + 1) / bins;
            double m;
            if (kappa == 0) m = (c1 - c0) / 2;
            else m = (std::exp(kappa * (c1 - 1)) - std::exp(kappa * (c0 - 1))) / -std::expm1(-2.0 * kappa);
            if (b == 0 && kappa > 10) m += (std::exp(kappa * (c0 - 1)) - std::exp(-2.0 * kappa)) / -std::expm1(-2.0 * kappa);
            expected[size_t(b)] = m * n;
        }
        const test::ChiSquare chi = test::pooledChiSquare(observed, expected, 5);
        EXPECT_GT(chi.p(), 1e-3) << kappa << " chi2 " << chi.chi2 << " dof " << chi.dof;
    }
}

}  // namespace
}  // namespace vdbmarch
