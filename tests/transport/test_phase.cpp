// The phase mixture of overlapping media: normalisation and mean cosine by
// quadrature, its sampler against its pdf (chi-square), the f / pdf weight,
// and the Legendre weights of eq. 26 against quadrature of the mixture.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "transport/phase.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

// Two lobes with different g and colour-dependent weights, and one more
// backward lobe: what three overlapping media give at a point.
PhaseMixture threeMedia() {
    PhaseMixture m;
    m.add(Color(1.0f, 0.5f, 0.2f), 0.8f);
    m.add(Color(0.3f, 0.6f, 0.9f), -0.4f);
    m.add(Color(0.2f, 0.2f, 0.2f), 0.1f);
    return m;
}

// Composite Simpson over cos in [-1, 1] of f(cos) (times 2 pi: the azimuth).
template <typename F>
double sphereIntegral(F&& f, int n = 200000) {
    const double h = 2.0 / n;
    double s = f(-1.0) + f(1.0);
    for (int i = 1; i < n; ++i) s += (i % 2 ? 4 : 2) * f(-1.0 + i * h);
    return 2 * M_PI * s * h / 3;
}

double legendreP(int l, double x) {
    double p0 = 1, p1 = x;
    if (l == 0) return p0;
    for (int k = 2; k <= l; ++k) {
        const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    return p1;
}

TEST(PhaseMixture, EvalAndPdfIntegrateToOne) {
    const PhaseMixture m = threeMedia();
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(sphereIntegral([&](double u) { return double(m.eval(float(u))[c]); }), 1.0, 1e-4) << "channel " << c;
    EXPECT_NEAR(sphereIntegral([&](double u) { return double(m.pdf(float(u))); }), 1.0, 1e-4);
}

// The closed form of int f^2 dOmega (shadow-ray roulette's scale) against
// quadrature, in units of the isotropic 1 / (4 pi).
TEST(PhaseMixture, MeanPhaseValueIsTheIntegralOfTheSquare) {
    for (float g : {0.f, 0.3f, 0.8f, -0.9f}) {
        PhaseMixture m;
        m.add(Color(1.f), g);
        const double q = 4 * PiD * sphereIntegral([&](double u) {
            const double f = hgPhase(float(u), g);
            return f * f;
        });
        EXPECT_NEAR(m.meanPhaseValue(), q, 1e-3 * q) << "g " << g;
    }
}

TEST(PhaseMixture, SingleMediumIsItsHenyeyGreensteinLobe) {
    PhaseMixture m;
    m.add(Color(2.f), 0.6f);
    for (float u : {-0.9f, 0.f, 0.5f, 0.99f}) {
        EXPECT_FLOAT_EQ(m.eval(u).x, hgPhase(u, 0.6f));
        EXPECT_FLOAT_EQ(m.pdf(u), hgPhase(u, 0.6f));
    }
    Color w(1);
    float pdf;
    m.sample(Vec3(0, 0, 1), 0.3f, 0.7f, 0.2f, w, pdf);
    EXPECT_EQ(w, Color(1));  // f / pdf = 1
}

TEST(PhaseMixture, BlackMediaAreNotLobes) {
    PhaseMixture m;
    m.add(Color(0.f), 0.5f);
    EXPECT_TRUE(m.empty());
    m.add(Color(1.f), 0.f);
    EXPECT_TRUE(m.isotropic());
}

TEST(PhaseMixture, SamplerMatchesPdfChiSquare) {
    const PhaseMixture m = threeMedia();
    const Vec3 d = normalize(Vec3(0.3f, -0.5f, 0.8f));
    // Cells in cos (the pdf is azimuthally symmetric) and azimuth.
    const int nCos = 40, nPhi = 8, samples = 400000;
    std::vector<double> observed(nCos * nPhi, 0);
    Vec3 s, t;
    coordinateSystem(d, s, t);
    Rng rng(17);
    double weightSum = 0, weightSum2 = 0;
    for (int i = 0; i < samples; ++i) {
        Color w(1);
        float pdf;
        const Vec3 wi = m.sample(d, rng.uniform(), rng.uniform(), rng.uniform(), w, pdf);
        const float c = clamp(dot(wi, d), -1.f, 1.f);
        ASSERT_NEAR(pdf, m.pdf(c), 1e-3f * m.pdf(c));
        double phi = std::atan2(double(dot(wi, t)), double(dot(wi, s)));
        if (phi < 0) phi += 2 * M_PI;
        const int ic = std::min(nCos - 1, int((c + 1) / 2 * nCos)), ip = std::min(nPhi - 1, int(phi / (2 * M_PI) * nPhi));
        observed[size_t(ic * nPhi + ip)] += 1;
        weightSum += w.x;
        weightSum2 += double(w.x) * w.x;
    }
    // Expected counts by quadrature of the pdf over each cell; cells pooled
    // to at least 5 expected.
    std::vector<double> expected(observed.size(), 0);
    for (int ic = 0; ic < nCos; ++ic) {
        const double a = -1 + 2.0 * ic / nCos, b = a + 2.0 / nCos;
        double mass = 0;
        const int q = 200;
        for (int k = 0; k < q; ++k) mass += m.pdf(float(a + (k + 0.5) * (b - a) / q)) * (b - a) / q;
        mass *= 2 * M_PI / nPhi;
        for (int ip = 0; ip < nPhi; ++ip) expected[size_t(ic * nPhi + ip)] = mass * samples;
    }
    const test::ChiSquare chi = test::pooledChiSquare(observed, expected, 5);
    ASSERT_GT(chi.dof, 100);
    EXPECT_GT(chi.p(), 1e-3) << "chi2 " << chi.chi2 << " dof " << chi.dof;
    // The weight f / pdf has mean 1 per channel under the sampler (f integrates to 1).
    const double mean = weightSum / samples, se = std::sqrt((weightSum2 / samples - mean * mean) / (samples - 1));
    EXPECT_NEAR(mean, 1.0, 4 * se);
}

TEST(PhaseMixture, LegendreWeightsAreTheMixturesExpansion) {
    // Eq. 26: w'_l = 2 pi Int p(u) P_l(u) du, of the mixture's pdf, by
    // quadrature; HG gives g^l per lobe, so the mixture's is sum w_i g_i^l,
    // not (sum w_i g_i)^l.
    const PhaseMixture m = threeMedia();
    const int order = 6;
    float w[order + 1];
    m.legendreWeights(order, w);
    double meanG = 0;
    for (int l = 0; l <= order; ++l) {
        const double q = sphereIntegral([&](double u) { return double(m.pdf(float(u))) * legendreP(l, u); });
        EXPECT_NEAR(w[l], q, 2e-4) << "l = " << l;
        if (l == 1) meanG = q;
    }
    EXPECT_GT(std::fabs(double(w[2]) - meanG * meanG), 0.05);  // the mean g's powers would be wrong
}

}  // namespace
}  // namespace vdbmarch
