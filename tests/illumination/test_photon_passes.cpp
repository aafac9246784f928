// Progressive photon passes (Knaus & Zwicker 2011) in a closed-form case:
// photons drawn from the density f(x) = f0 (1 - |x|^2) in the unit ball,
// f0 = 15 / (8 pi), and the estimate of f(0) from the k nearest photons
// (PhotonMap::estimateLi with an isotropic phase of 1), pass after pass.
//
// Given the k-th distance r, the k - 1 nearer photons are i.i.d. with density
// f / M(r) in the ball (M(r) = 2.5 r^3 - 1.5 r^5 its mass), so the estimate
// gathered within rho r has the expectation
//   (k - 1) f0 (1 - 0.6 rho^2 r^2) / (N M(r)),
// and M(r) ~ Beta(k, N - k + 1), so E[(k - 1) / (N M)] = 1 and
//   E[pass estimate] = f0 - 0.6 f0 rho^2 C,  C = E[r^2 (k - 1) / (N M(r))],
// with C a one-dimensional integral over the Beta density (quadrature here).
// The bias of the mean of M passes is then -0.6 f0 C mean_j(rho_j^2): the
// fixed-radius estimate keeps its bias forever, the progressive one loses it
// at the rate the radius rule predicts.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "illumination/illumination.h"
#include "photons/photon_map.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

constexpr int N = 1000, K = 50;
const double F0 = 15.0 / (8.0 * M_PI);

std::vector<Photon> drawPhotons(Rng& rng) {
    std::vector<Photon> photons;
    photons.reserve(N);
    while (int(photons.size()) < N) {
        Vec3 u(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
        float r2 = lengthSquared(u);
        if (r2 > 1 || rng.uniform() > 1 - r2) continue;  // rejection: density (1 - |x|^2)
        Photon p;
        p.position = u;
        p.direction = encodeDirection(Vec3(0, 0, 1));
        p.weight = Color(1.f / N);
        p.flags = 0;
        photons.push_back(p);
    }
    return photons;
}

// r with M(r) = m.
double radiusOfMass(double m) {
    double lo = 0, hi = 1;
    for (int i = 0; i < 80; ++i) {
        double mid = 0.5 * (lo + hi);
        (2.5 * mid * mid * mid - 1.5 * std::pow(mid, 5) < m ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// C = E[r^2 (k - 1) / (N m)], m ~ Beta(k, N - k + 1), by the midpoint rule
// over the Beta density (its mass is checked to 1e-9).
double constantC(double* mass) {
    const double a = K, b = N - K + 1;
    const double logB = std::lgamma(a) + std::lgamma(b) - std::lgamma(a + b);
    const int n = 200000;
    double c = 0, total = 0;
    for (int i = 0; i < n; ++i) {
        double m = (i + 0.5) / n;
        double pdf = std::exp((a - 1) * std::log(m) + (b - 1) * std::log1p(-m) - logB) / n;
        double r = radiusOfMass(m);
        total += pdf;
        c += pdf * r * r * (K - 1) / (double(N) * m);
    }
    *mass = total;
    return c;
}

TEST(PhotonPasses, RadiusRuleIsKnausZwickers) {
    // r_{j+1}^3 = r_j^3 (j + alpha) / (j + 1), from r_0 = 1.
    for (double alpha : {4.0 / 7, 2.0 / 3, 0.9}) {
        double r3 = 1;
        for (int j = 0; j < 2000; ++j) {
            EXPECT_NEAR(progressiveRadiusScale(j, alpha), std::cbrt(r3), 1e-9 * std::cbrt(r3)) << j;
            r3 *= (j + 1 + alpha) / (j + 2);
        }
    }
    EXPECT_EQ(progressiveRadiusScale(0, 0.5), 1.0);
}

TEST(PhotonPasses, ProgressiveEstimateLosesItsBiasAtThePredictedRate) {
    const double alpha = 4.0 / 7;
    double mass = 0;
    const double C = constantC(&mass);
    ASSERT_NEAR(mass, 1.0, 1e-9);
    const double fixedBias = -0.6 * F0 * C;  // every pass of the fixed radius

    const int replications = 256, passes = 64;
    const int checkpoints[] = {1, 4, 16, 64};
    test::SampleStats progressive[4], fixedRadius;
    auto isotropic = [](float) { return Color(1.f); };
    for (int rep = 0; rep < replications; ++rep) {
        double sumProgressive = 0, sumFixed = 0;
        int next = 0;
        for (int j = 0; j < passes; ++j) {
            Rng rng(hashValues(0x5050, uint64_t(rep)), uint64_t(j));  // an independent batch per pass
            PhotonMap map(drawPhotons(rng));
            const float rho = float(progressiveRadiusScale(j, alpha));
            sumProgressive += average(map.estimateLi(Vec3(0.f), Vec3(0, 0, 1), K, isotropic, nullptr, rho));
            sumFixed += average(map.estimateLi(Vec3(0.f), Vec3(0, 0, 1), K, isotropic));
            if (j + 1 == checkpoints[next]) progressive[next++].add(sumProgressive / (j + 1));
        }
        fixedRadius.add(sumFixed / passes);
    }
    // The fixed radius: its mean sits at the predicted bias, many standard
    // errors from the truth (a plateau).
    EXPECT_NEAR(fixedRadius.mean(), F0 + fixedBias, 4 * fixedRadius.stdError());
    EXPECT_GT(std::fabs(fixedBias), 8 * fixedRadius.stdError());
    double lastBias = 0;
    for (int c = 0; c < 4; ++c) {
        double meanRho2 = 0;
        for (int j = 0; j < checkpoints[c]; ++j) meanRho2 += std::pow(progressiveRadiusScale(j, alpha), 2);
        meanRho2 /= checkpoints[c];
        const double predicted = F0 + fixedBias * meanRho2;
        EXPECT_NEAR(progressive[c].mean(), predicted, 4 * progressive[c].stdError())
            << checkpoints[c] << " passes: predicted bias " << fixedBias * meanRho2;
        lastBias = fixedBias * meanRho2;
        std::printf("passes %d: measured bias %.5f +- %.5f, predicted %.5f (fixed radius %.5f +- %.5f)\n", checkpoints[c], progressive[c].mean() - F0, progressive[c].stdError(), lastBias, fixedRadius.mean() - F0, fixedRadius.stdError());
    }
    // After 64 passes the bias is under 45% of the fixed radius's, and the
    // measured one is too.
    EXPECT_LT(std::fabs(lastBias), 0.45 * std::fabs(fixedBias));
    EXPECT_LT(std::fabs(progressive[3].mean() - F0) - 4 * progressive[3].stdError(), 0.45 * std::fabs(fixedBias));
}

}  // namespace
}  // namespace vdbmarch
