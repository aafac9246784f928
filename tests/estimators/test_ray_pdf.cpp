// The per-ray pdf of the transmittance and guided marchers (eqs. 9, 16-18):
// normalisation, chi-square of its samples, and the guided estimator's
// expectation against quadrature of the same integrand along a ray, for a
// good histogram, a negative-ringing (clamped) one and an empty one; and the
// mixture with equiangular densities towards lights (the guided marcher's
// share towards lights near the ray): chi-square and expectation.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "estimators/ray_pdf.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using test::pooledChiSquare;
using test::SampleStats;

// A synthetic ray: 60 steps of 0.05 with varying extinction, some of them
// not scattering (sigma_s = 0), through a medium of optical depth ~ 3.
struct SyntheticRay {
    std::vector<PdfStep> steps;
    std::vector<double> sigmaS, kappa, T0;
    SyntheticRay() {
        double T = 1, t = 0;
        for (int k = 0; k < 60; ++k) {
            double len = 0.05, kap = 0.5 + 1.5 * (1 + std::sin(0.37 * k)), ss = (k >= 20 && k < 26) ? 0.0 : 0.8 * kap;
            double S = -std::expm1(-kap * len) / kap;
            steps.push_back({float(t), float(len), float(kap), float(ss * T * S)});
            sigmaS.push_back(ss);
            kappa.push_back(kap);
            T0.push_back(T);
            T *= std::exp(-kap * len);
            t += len;
        }
    }
    // T(t) sigma_s on step k at offset x.
    double weight(int k, double x) const { return T0[size_t(k)] * std::exp(-kappa[size_t(k)] * x) * sigmaS[size_t(k)]; }
};

// L_i along the ray: two sharp peaks (widths 0.01 and 0.03) on a dim floor,
// and a dark region [2.2, 2.5).
double syntheticLi(double t) {
    if (t >= 2.2 && t < 2.5) return 0;
    return 0.05 + 40 * std::exp(-0.5 * std::pow((t - 0.63) / 0.01, 2)) + 5 * std::exp(-0.5 * std::pow((t - 1.71) / 0.03, 2));
}

// Quadrature of sum_k int_step T sigma_s L_i (Simpson, 2000 panels per step).
double quadrature(const SyntheticRay& r) {
    double sum = 0;
    for (size_t k = 0; k < r.steps.size(); ++k) {
        const int n = 2000;
        const double h = r.steps[k].len / n;
        for (int i = 0; i <= n; ++i) {
            double x = i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
            sum += w * r.weight(int(k), x) * syntheticLi(r.steps[k].t0 + x) * h / 3;
        }
    }
    return sum;
}

TEST(RayPdf, IntegratesToOneAndMatchesItsSamples) {
    SyntheticRay r;
    std::vector<float> h;
    for (const auto& s : r.steps) h.push_back(float(syntheticLi(s.t0 + 0.5 * s.len)));
    for (bool guided : {false, true}) {
        RayPdf pdf;
        pdf.build(r.steps, guided ? h.data() : nullptr);
        ASSERT_TRUE(pdf.valid());
        // Normalisation by Simpson quadrature of pdf(step, x).
        double integral = 0;
        for (int k = 0; k < int(r.steps.size()); ++k) {
            const int n = 200;
            const double dx = r.steps[size_t(k)].len / n;
            for (int i = 0; i <= n; ++i)
                integral += ((i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2)) * pdf.pdf(k, float(i * dx)) * dx / 3;
        }
        EXPECT_NEAR(integral, 1.0, 1e-5);
        // Chi-square over 4 sub-bins per step, expected counts from the pdf
        // integrated by quadrature; non-scattering steps must get no sample.
        const int sub = 4, samples = 400000;
        std::vector<double> observed(r.steps.size() * sub, 0), expected(r.steps.size() * sub, 0);
        Rng rng(guided ? 7 : 8);
        for (int i = 0; i < samples; ++i) {
            int k;
            float x;
            double p;
            pdf.sample(rng.uniform(), k, x, p);
            ASSERT_GE(x, 0.f);
            ASSERT_LT(x, r.steps[size_t(k)].len);
            ASSERT_NEAR(p, pdf.pdf(k, x), 1e-9 * p);
            ASSERT_GT(r.sigmaS[size_t(k)], 0) << "sampled a step that cannot scatter";
            observed[size_t(k) * sub + size_t(std::min(sub - 1, int(x / r.steps[size_t(k)].len * sub)))] += 1;
        }
        for (size_t b = 0; b < expected.size(); ++b) {
            const PdfStep& s = r.steps[b / sub];
            const double a = s.len * double(b % sub) / sub, c = s.len * double(b % sub + 1) / sub;
            const int n = 100;
            for (int i = 0; i <= n; ++i)
                expected[b] += ((i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2)) *
                               pdf.pdf(int(b / sub), float(a + i * (c - a) / n)) * (c - a) / n / 3 * samples;
        }
        // Pool bins with small expectations, as the chi-square test needs.
        test::ChiSquare c = pooledChiSquare(observed, expected, 20);
        EXPECT_GT(c.p(), 1e-4) << "chi2 " << c.chi2 << " dof " << c.dof << (guided ? " guided" : "");
    }
}

struct EstimatorStats {
    double mean = 0, stdError = 0, variance = 0;
};

// Eq. 18 with N stratified samples, repeated: mean, its standard error and
// the per-estimate variance.
EstimatorStats estimate(const SyntheticRay& r, const float* h, int n, int repeats, uint64_t seed) {
    RayPdf pdf;
    pdf.build(r.steps, h);
    Rng rng(seed);
    SampleStats estimates;
    for (int rep = 0; rep < repeats; ++rep) {
        double e = 0;
        for (int j = 0; j < n; ++j) {
            int k;
            float x;
            double p;
            pdf.sample((j + rng.uniform()) / n, k, x, p);
            e += r.weight(k, x) * syntheticLi(r.steps[size_t(k)].t0 + x) / (n * p);
        }
        estimates.add(e);
    }
    return {estimates.mean(), estimates.stdError(), estimates.variance()};
}

TEST(RayPdf, GuidedEstimatorIsUnbiasedForAnyHistogram) {
    SyntheticRay r;
    const double truth = quadrature(r);
    // A good histogram: L_i at the step centres (sharper than the cache's cells).
    std::vector<float> good, ringing, empty(r.steps.size(), 0.f), wrong;
    for (size_t k = 0; k < r.steps.size(); ++k) {
        const double t = r.steps[k].t0 + 0.5 * r.steps[k].len;
        good.push_back(float(syntheticLi(t)));
        // Ringing: an SH-like overshoot that goes negative next to the peak
        // and is clamped to 0 there, where L_i is not 0.
        double ring = syntheticLi(t) + 8 * std::sin(9 * t);
        ringing.push_back(float(std::max(0.0, ring)));
        // Wrong: light only where L_i is dark.
        wrong.push_back(t >= 2.2 && t < 2.5 ? 10.f : 0.f);
    }
    const int n = 4, repeats = 20000;
    EstimatorStats transmittance = estimate(r, nullptr, n, repeats, 1);
    struct Case {
        const char* name;
        const float* h;
    } cases[] = {{"good", good.data()}, {"ringing", ringing.data()}, {"empty", empty.data()}, {"wrong", wrong.data()}};
    EXPECT_NEAR(transmittance.mean, truth, 4 * transmittance.stdError) << "transmittance";
    for (const auto& c : cases) {
        EstimatorStats s = estimate(r, c.h, n, repeats, 2);
        EXPECT_NEAR(s.mean, truth, 4 * s.stdError) << c.name;
        // Defensive mixing bounds the loss to 1/eps of transmittance's variance.
        EXPECT_LT(s.variance, transmittance.variance / RayPdf::DefaultDefensive) << c.name;
        if (c.h == good.data()) {
            EXPECT_LT(s.variance, 0.1 * transmittance.variance) << "a good histogram must pay off";
        }
    }
}

// Simpson's rule on 200 intervals of [lo, hi].
template <typename F>
double simpson(double lo, double hi, F&& f) {
    const int n = 200;
    double sum = 0;
    for (int i = 0; i <= n; ++i) sum += ((i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2)) * f(lo + i * (hi - lo) / n);
    return sum * (hi - lo) / n / 3;
}

// Two lights near the synthetic ray: one 0.02 from it at t = 0.63 (L_i's
// sharp peak), one 0.3 from it at t = 2.9 whose equiangular interval runs
// past the ray's last step (3.0) to 3.5, so a share of its draws lands in no
// step; odds 0.7 and 0.3.
RayPdf::Lights syntheticLights() {
    RayPdf::Lights lights(2);
    lights[0].light = 0;
    lights[0].sampler = EquiangularSampler(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.63f, 0.02f, 0), 0.f, 3.f, 1e-6f);
    lights[0].choice = 0.7f;
    lights[1].light = 1;
    lights[1].sampler = EquiangularSampler(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2.9f, 0, 0.3f), 0.f, 3.5f, 1e-6f);
    lights[1].choice = 0.3f;
    return lights;
}

TEST(RayPdf, MixtureWithLightsMatchesItsSamples) {
    SyntheticRay r;
    const RayPdf::Lights lights = syntheticLights();
    const double a = 0.25;
    std::vector<float> wrong;  // the cache's light only where L_i is dark
    for (const auto& s : r.steps) wrong.push_back(s.t0 >= 2.2f && s.t0 < 2.5f ? 10.f : 0.f);
    RayPdf pdf;
    pdf.build(r.steps, wrong.data());
    // Expected counts: 8 sub-bins per step by Simpson quadrature of the
    // mixture density, and one bin for the light draws that land past the
    // last step (the second light's density over [3, 3.5), times a c_2).
    const int sub = 8, samples = 400000;
    std::vector<double> observed(r.steps.size() * sub + 1, 0), expected(r.steps.size() * sub + 1, 0);
    double total = 0;
    for (size_t b = 0; b + 1 < expected.size(); ++b) {
        const PdfStep& s = r.steps[b / sub];
        const double lo = s.len * double(b % sub) / sub, hi = s.len * double(b % sub + 1) / sub;
        expected[b] = simpson(lo, hi, [&](double x) { return pdf.pdfWithLights(int(b / sub), float(x), a, lights); });
        total += expected[b];
    }
    expected.back() = a * lights[1].choice * simpson(3.0, 3.5, [&](double t) { return lights[1].sampler.pdf(float(t)); });
    total += expected.back();
    EXPECT_NEAR(total, 1.0, 1e-4) << "the mixture's mass over the steps and past them";
    for (double& e : expected) e *= samples;
    Rng rng(11);
    for (int i = 0; i < samples; ++i) {
        int k;
        float x;
        double p;
        if (!pdf.sampleWithLights(rng.uniformDouble(), a, lights, k, x, p)) {
            observed.back() += 1;
            continue;
        }
        ASSERT_GE(x, 0.f);
        ASSERT_LT(x, r.steps[size_t(k)].len);
        ASSERT_NEAR(p, pdf.pdfWithLights(k, x, a, lights), 1e-9 * p);
        observed[size_t(k) * sub + size_t(std::min(sub - 1, int(x / r.steps[size_t(k)].len * sub)))] += 1;
    }
    test::ChiSquare c = pooledChiSquare(observed, expected, 20);
    EXPECT_GT(c.p(), 1e-4) << "chi2 " << c.chi2 << " dof " << c.dof;
}

// The mixture with the folds of caustics behind glass spheres too
// (caustic_folds.h): a crossing at t = 1.4 (half-width 0.1) and one at 2.95
// (half-width 0.2, so part of its draws lands past the last step). The
// folds' density is singular at a crossing, so its share of each bin comes
// from its closed-form CDF, the rest by Simpson quadrature.
TEST(RayPdf, MixtureWithLightsAndFoldsMatchesItsSamples) {
    SyntheticRay r;
    const RayPdf::Lights lights = syntheticLights();
    FoldSampler folds;
    const double tf[2] = {1.4, 2.95}, w[2] = {0.1, 0.2};
    for (int i = 0; i < 2; ++i) folds.add(float(tf[i]), float(w[i]));
    const RayPdf::Mixture mix{0.25, &lights, 0.15, &folds};
    RayPdf pdf;
    std::vector<float> h;
    for (const auto& s : r.steps) h.push_back(1.f + s.t0);
    pdf.build(r.steps, h.data());
    auto foldMass = [&](double lo, double hi) {  // a window's CDF on a side: sqrt(d / w) / 2
        double m = 0;
        for (int i = 0; i < 2; ++i) {
            auto cdf = [&](double t) {
                const double x = std::clamp((t - tf[i]) / w[i], -1.0, 1.0);
                return 0.5 + std::copysign(0.5 * std::sqrt(std::fabs(x)), x);
            };
            m += 0.5 * (cdf(hi) - cdf(lo));
        }
        return m;
    };
    const int sub = 8, samples = 400000;
    std::vector<double> observed(r.steps.size() * sub + 1, 0), expected(r.steps.size() * sub + 1, 0);
    double total = 0;
    for (size_t b = 0; b + 1 < expected.size(); ++b) {
        const int k = int(b / sub);
        const PdfStep& s = r.steps[size_t(k)];
        const double lo = s.len * double(b % sub) / sub, hi = s.len * double(b % sub + 1) / sub;
        expected[b] = simpson(lo, hi, [&](double x) {
                          return (1 - 0.25 - 0.15) * pdf.pdf(k, float(x)) + 0.25 * pdf.pdfWithLights(k, float(x), 1.0, lights);
                      }) +
                      0.15 * foldMass(s.t0 + lo, s.t0 + hi);
        total += expected[b];
    }
    expected.back() = 0.25 * lights[1].choice * simpson(3.0, 3.5, [&](double t) { return lights[1].sampler.pdf(float(t)); }) +
                      0.15 * foldMass(3.0, 3.5);
    total += expected.back();
    EXPECT_NEAR(total, 1.0, 1e-4) << "the mixture's mass over the steps and past them";
    for (double& e : expected) e *= samples;
    Rng rng(13);
    for (int i = 0; i < samples; ++i) {
        int k;
        float x, t;
        double p;
        if (!pdf.sampleMixture(rng.uniformDouble(), mix, k, x, p, t)) {
            observed.back() += 1;
            continue;
        }
        ASSERT_NEAR(t, r.steps[size_t(k)].t0 + x, 1e-6f);
        ASSERT_NEAR(p, pdf.mixturePdf(k, x, mix, t), 1e-9 * p);
        observed[size_t(k) * sub + size_t(std::min(sub - 1, int(x / r.steps[size_t(k)].len * sub)))] += 1;
    }
    test::ChiSquare c = pooledChiSquare(observed, expected, 20);
    EXPECT_GT(c.p(), 1e-4) << "chi2 " << c.chi2 << " dof " << c.dof;
}

// Eq. 18 over the mixture, N stratified positions: the expectation of the
// integral for the wrong histogram, and a variance far below that of the
// wrong histogram alone (the light at t = 0.63 is L_i's sharp peak).
TEST(RayPdf, MixtureWithLightsIsUnbiasedAndRescuesAWrongHistogram) {
    SyntheticRay r;
    const double truth = quadrature(r);
    const RayPdf::Lights lights = syntheticLights();
    std::vector<float> wrong;
    for (const auto& s : r.steps) wrong.push_back(s.t0 >= 2.2f && s.t0 < 2.5f ? 10.f : 0.f);
    RayPdf pdf;
    pdf.build(r.steps, wrong.data());
    const int n = 4, repeats = 20000;
    SampleStats with, without;
    Rng rng(12);
    for (int rep = 0; rep < repeats; ++rep) {
        double e[2] = {0, 0};
        for (int m = 0; m < 2; ++m)
            for (int j = 0; j < n; ++j) {
                int k;
                float x;
                double p;
                if (!pdf.sampleWithLights((j + rng.uniformDouble()) / n, m == 0 ? 0.25 : 0.0, lights, k, x, p)) continue;
                e[m] += r.weight(k, x) * syntheticLi(r.steps[size_t(k)].t0 + x) / (n * p);
            }
        with.add(e[0]);
        without.add(e[1]);
    }
    EXPECT_NEAR(with.mean(), truth, 4 * with.stdError());
    EXPECT_NEAR(without.mean(), truth, 4 * without.stdError());
    EXPECT_LT(with.variance(), 0.25 * without.variance());
}

}  // namespace
}  // namespace vdbmarch
