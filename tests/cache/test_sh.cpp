// Spherical harmonics of the radiance cache (cache/sh.h) against their defining
// properties: orthonormality, the trigonometric definition, projection round
// trips, and Funk-Hecke convolution with phase functions (paper eqs. 25-27).
//
// Tolerances: the sphere quadratures below are exact for the band-limited
// integrands used (Gauss-Legendre in cos theta is exact to degree 2n-1, the
// uniform azimuth rule to trigonometric degree nPhi-1), and Gauss-Legendre on
// the analytic Henyey-Greenstein lobe converges like rho^-2n (rho from the
// pole at u = (1+g^2)/(2g)), far below float precision for the node counts
// used. What remains is float rounding of the basis, bounded by kFloatTol
// relative to a bound on the magnitude of the quantity compared.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <vector>

#include "cache/sh.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "support/support.h"
#include "transport/phase.h"

namespace vdbmarch {
namespace {

using test::PiD;

// Float evaluation of an order <= 8 basis: a recurrence of <= 9 steps with a
// few roundings each, then a dot product; 64 ulps covers it with margin.
constexpr double kFloatTol = 64 * double(FLT_EPSILON);

static_assert(shCount(0) == 1 && shCount(3) == 16 && shCount(MaxShOrder) == 81, "(K+1)^2");
static_assert(shIndex(0, 0) == 0 && shIndex(1, -1) == 1 && shIndex(3, 3) == 15 && shIndex(4, -4) == 16,
              "band-major layout");

// Product rule on the sphere: Gauss-Legendre in z times uniform azimuth.
struct SphereQuadrature {
    std::vector<Vec3> dirs;
    std::vector<double> weights;
    SphereQuadrature(int nTheta, int nPhi) {
        std::vector<double> x, w;
        gaussLegendre(nTheta, x, w);
        for (int i = 0; i < nTheta; ++i) {
            double r = std::sqrt(1 - x[i] * x[i]);
            for (int j = 0; j < nPhi; ++j) {
                double phi = 2 * PiD * (j + 0.5) / nPhi;
                dirs.emplace_back(float(r * std::cos(phi)), float(r * std::sin(phi)), float(x[i]));
                weights.push_back(w[i] * 2 * PiD / nPhi);
            }
        }
    }
};

double hgPhaseD(double u, double g) {
    double denom = 1 + g * g - 2 * g * u;
    return (1 - g * g) / (4 * PiD * denom * std::sqrt(denom));
}

// Bound on |sum_lm c_lm Y_lm(w)|: |Y_lm| <= sqrt((2l+1)/(4 pi)) by the
// addition theorem (sum_m Y_lm^2 = (2l+1)/(4 pi)).
double magnitudeBound(int order, const float* c) {
    double b = 0;
    for (int l = 0; l <= order; ++l)
        for (int m = -l; m <= l; ++m) b += std::fabs(c[shIndex(l, m)]) * std::sqrt((2 * l + 1) / (4 * PiD));
    return b;
}

std::vector<Vec3> testDirections(int n, uint64_t seed) {
    Rng rng(seed);
    // Poles and axes first: the recurrence's sin^m theta factors vanish there.
    std::vector<Vec3> dirs = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}, normalize(Vec3(1, 1, 1))};
    while (int(dirs.size()) < n) dirs.push_back(sampleUniformSphere(rng.uniform(), rng.uniform()));
    return dirs;
}

std::vector<float> randomCoefficients(int order, uint64_t seed) {
    Rng rng(seed);
    std::vector<float> c(shCount(order));
    for (float& v : c) v = 2 * rng.uniform() - 1;
    return c;
}

TEST(ShBasis, OrthonormalOverSphere) {
    // Y_i Y_j has band <= 16: 64 z-nodes (degree 127) and 128 azimuths are exact.
    SphereQuadrature q(64, 128);
    for (int order : {3, MaxShOrder}) {  // expanded path and recurrence path
        const int n = shCount(order);
        std::vector<double> gram(n * n, 0.0);
        std::vector<float> Y(n);
        for (size_t k = 0; k < q.dirs.size(); ++k) {
            evalSh(order, q.dirs[k], Y.data());
            for (int i = 0; i < n; ++i)
                for (int j = 0; j <= i; ++j) gram[i * n + j] += q.weights[k] * double(Y[i]) * Y[j];
        }
        // |error| <= kFloatTol * Int |Y_i||Y_j| <= kFloatTol (Cauchy-Schwarz).
        for (int i = 0; i < n; ++i)
            for (int j = 0; j <= i; ++j)
                EXPECT_NEAR(gram[i * n + j], i == j ? 1.0 : 0.0, kFloatTol)
                    << "order " << order << " i " << i << " j " << j;
    }
}

TEST(ShBasis, MatchesTrigonometricDefinition) {
    // std::assoc_legendre omits the Condon-Shortley phase; the convention
    // documented in sh.h puts (-1)^m in, with m < 0 ~ sin and m > 0 ~ cos.
    std::vector<float> Y(shCount(MaxShOrder));
    for (const Vec3& w : testDirections(200, 11)) {
        evalSh(MaxShOrder, w, Y.data());
        double theta = std::acos(clamp(double(w.z), -1.0, 1.0)), phi = std::atan2(double(w.y), double(w.x));
        for (int l = 0; l <= MaxShOrder; ++l) {
            for (int m = -l; m <= l; ++m) {
                int am = std::abs(m);
                double k = std::sqrt((2 * l + 1) / (4 * PiD) * std::tgamma(l - am + 1) / std::tgamma(l + am + 1));
                double p = (am % 2 ? -1.0 : 1.0) * std::assoc_legendre(l, am, std::cos(theta));
                double ref = m == 0 ? k * p
                             : m > 0 ? std::sqrt(2.0) * k * p * std::cos(am * phi)
                                     : std::sqrt(2.0) * k * p * std::sin(am * phi);
                EXPECT_NEAR(Y[shIndex(l, m)], ref, kFloatTol * std::sqrt((2 * l + 1) / (4 * PiD)))
                    << "l " << l << " m " << m << " w " << w.x << " " << w.y << " " << w.z;
            }
        }
    }
    // Spot values of the convention.
    evalSh(1, Vec3(0.6f, 0, 0.8f), Y.data());
    EXPECT_NEAR(Y[shIndex(1, 1)], -0.4886025f * 0.6f, 1e-6);
    EXPECT_NEAR(Y[shIndex(1, 0)], 0.4886025f * 0.8f, 1e-6);
    // The cache file states Y_1,-1 = -0.488603 y (metadata sh_basis).
    evalSh(1, Vec3(0, 0.6f, 0.8f), Y.data());
    EXPECT_NEAR(Y[shIndex(1, -1)], -0.4886025f * 0.6f, 1e-6);
}

TEST(ShBasis, BandInvertsTheFlatIndex) {
    for (int l = 0; l <= MaxShOrder; ++l)
        for (int m = -l; m <= l; ++m) EXPECT_EQ(shBand(shIndex(l, m)), l) << "l " << l << " m " << m;
}

TEST(ShBasis, ExpandedPathMatchesRecurrence) {
    std::vector<float> a(shCount(MaxShOrder)), b(shCount(MaxShOrder));
    for (const Vec3& w : testDirections(2000, 5)) {
        for (int order = 0; order <= 3; ++order) {
            evalSh(order, w, a.data());
            evalShRecurrence(order, w, b.data());
            for (int l = 0; l <= order; ++l)
                for (int m = -l; m <= l; ++m)
                    EXPECT_NEAR(a[shIndex(l, m)], b[shIndex(l, m)], kFloatTol * std::sqrt((2 * l + 1) / (4 * PiD)))
                        << "l " << l << " m " << m;
        }
        // Higher orders start with the same 16 values.
        evalSh(MaxShOrder, w, b.data());
        evalSh(3, w, a.data());
        for (int i = 0; i < 16; ++i) EXPECT_NEAR(a[i], b[i], kFloatTol);
    }
}

TEST(ShBasis, WritesExactlyShCountValues) {
    const float sentinel = -12345.f;
    for (int order = 0; order <= MaxShOrder; ++order) {
        for (auto eval : {&evalSh, &evalShRecurrence}) {
            std::vector<float> Y(shCount(MaxShOrder) + 1, sentinel);
            eval(order, normalize(Vec3(0.3f, -0.5f, 0.7f)), Y.data());
            for (int i = 0; i < int(Y.size()); ++i)
                EXPECT_EQ(Y[i] == sentinel, i >= shCount(order)) << "order " << order << " i " << i;
        }
    }
}

TEST(ShLegendre, PolynomialsAndGaussLegendre) {
    double p[9];
    legendrePolynomials(8, 0.3, p);
    EXPECT_NEAR(p[2], 0.5 * (3 * 0.09 - 1), 1e-15);
    EXPECT_NEAR(p[3], 0.5 * (5 * 0.027 - 3 * 0.3), 1e-15);
    for (double x : {-1.0, 1.0}) {
        legendrePolynomials(8, x, p);
        for (int l = 0; l <= 8; ++l) EXPECT_NEAR(p[l], x > 0 ? 1.0 : (l % 2 ? -1.0 : 1.0), 1e-14);
    }
    // n nodes integrate x^k exactly for k <= 2n-1.
    for (int n : {1, 2, 5, 64, 256}) {
        std::vector<double> x, w;
        gaussLegendre(n, x, w);
        for (int i = 1; i < n; ++i) EXPECT_LT(x[i - 1], x[i]);
        for (int k = 0; k <= std::min(2 * n - 1, 40); ++k) {
            double sum = 0;
            for (int i = 0; i < n; ++i) sum += w[i] * std::pow(x[i], k);
            EXPECT_NEAR(sum, k % 2 ? 0.0 : 2.0 / (k + 1), 1e-13) << "n " << n << " k " << k;
        }
    }
}

TEST(ShProjection, BandLimitedRoundTrip) {
    // f has bands <= 4; projecting onto bands <= 6 multiplies to band <= 10,
    // exact on 64 x 128 nodes.
    const int fOrder = 4, pOrder = 6;
    std::vector<float> f = randomCoefficients(fOrder, 21);
    SphereQuadrature q(64, 128);
    std::vector<double> proj(shCount(pOrder), 0.0);
    std::vector<float> Y(shCount(pOrder));
    for (size_t k = 0; k < q.dirs.size(); ++k) {
        evalSh(pOrder, q.dirs[k], Y.data());
        double fk = evalShSum(shCount(fOrder), f.data(), Y.data());
        for (int i = 0; i < shCount(pOrder); ++i) proj[i] += q.weights[k] * fk * Y[i];
    }
    // |error| <= kFloatTol ||f||_2 * ||Y_i||_2 with ||f||_2^2 = sum c^2.
    double norm = 0;
    for (float c : f) norm += double(c) * c;
    norm = std::sqrt(norm);
    for (int i = 0; i < shCount(pOrder); ++i)
        EXPECT_NEAR(proj[i], i < shCount(fOrder) ? f[i] : 0.0, kFloatTol * norm) << "i " << i;

    std::vector<float> projF(proj.begin(), proj.begin() + shCount(fOrder));
    double bound = magnitudeBound(fOrder, f.data());
    for (const Vec3& w : testDirections(200, 22)) {
        evalSh(fOrder, w, Y.data());
        EXPECT_NEAR(evalShSum(shCount(fOrder), projF.data(), Y.data()),
                    evalShSum(shCount(fOrder), f.data(), Y.data()), kFloatTol * bound);
    }
}

TEST(ShFunkHecke, BandLimitedRadianceMatchesBruteForceConvolution) {
    const int order = 3;
    const int nU = 256, nPhi = 16;  // azimuth: L is band <= 3 around any axis
    std::vector<double> u, wu;
    gaussLegendre(nU, u, wu);
    std::vector<float> F = randomCoefficients(order, 31);
    std::vector<float> Y(shCount(order)), conv(shCount(order));
    float weights[order + 1];
    for (float g : {0.f, 0.5f, 0.85f, -0.6f}) {
        // Gauss-Legendre error on p(u) * poly(u) ~ rho^-2n, rho = u0 + sqrt(u0^2 - 1).
        double u0 = g == 0 ? Infinity : (1 + double(g) * g) / (2 * std::fabs(g));
        double rho = u0 + std::sqrt(u0 * u0 - 1);
        ASSERT_LT(std::pow(rho, -2.0 * nU), 1e-20);

        hgLegendreWeights(order, g, weights);
        shConvolvePhase(order, weights, F.data(), conv.data());
        // L_i is a positively weighted average of L, so L's bound applies.
        double bound = magnitudeBound(order, F.data());
        for (const Vec3& w : testDirections(12, 32)) {
            // Integrate in a frame around w so the phase depends on u only.
            double brute = 0;
            for (int i = 0; i < nU; ++i) {
                double ring = 0;
                for (int j = 0; j < nPhi; ++j) {
                    Vec3 wp = directionAround(w, float(u[i]), (j + 0.5f) / nPhi);
                    evalSh(order, wp, Y.data());
                    ring += evalShSum(shCount(order), F.data(), Y.data());
                }
                brute += wu[i] * hgPhaseD(u[i], g) * ring * (2 * PiD / nPhi);
            }
            evalSh(order, w, Y.data());
            EXPECT_NEAR(evalShSum(shCount(order), conv.data(), Y.data()), brute, kFloatTol * bound)
                << "g " << g << " w " << w.x << " " << w.y << " " << w.z;
        }
    }
}

TEST(ShFunkHecke, PhotonDeltaGivesTruncatedLegendreSeries) {
    // A photon travelling along d: L(w') = delta(w', d) projects to F_lm =
    // Y_lm(d) (eq. 27); after convolution the addition theorem (eq. 24) turns
    // sum_m Y_lm(d) Y_lm(w) into (2l+1)/(4 pi) P_l(d . w), so the cache holds
    // exactly the truncated Legendre series of the phase function.
    std::vector<float> F(shCount(MaxShOrder)), conv(shCount(MaxShOrder)), Y(shCount(MaxShOrder));
    float weights[MaxShOrder + 1];
    double P[MaxShOrder + 1];
    const Vec3 d = normalize(Vec3(0.2f, -0.7f, 0.4f));
    for (int order : {3, MaxShOrder}) {
        evalSh(order, d, F.data());
        // |error| <= kFloatTol sum_l (2l+1)/(4 pi) (Cauchy-Schwarz on eq. 24).
        double bound = shCount(order) / (4 * PiD);
        for (float g : {0.f, 0.5f, 0.85f, -0.6f, 0.95f}) {
            hgLegendreWeights(order, g, weights);
            shConvolvePhase(order, weights, F.data(), conv.data());
            for (const Vec3& w : testDirections(100, 41)) {
                legendrePolynomials(order, double(d.x) * w.x + double(d.y) * w.y + double(d.z) * w.z, P);
                double series = 0;
                for (int l = 0; l <= order; ++l) series += (2 * l + 1) / (4 * PiD) * std::pow(double(g), l) * P[l];
                evalSh(order, w, Y.data());
                EXPECT_NEAR(evalShSum(shCount(order), conv.data(), Y.data()), series, kFloatTol * bound)
                    << "order " << order << " g " << g;
            }
        }
    }
}

// Relative error of the float hgPhase(float(u), g) against the exact lobe:
// rounding u (2^-24) times |d ln p / du| <= 3|g|/(1-|g|)^2, cancellation in
// 1 + g^2 - 2gu (a few ulps of 2 against (1-|g|)^2, amplified 3/2 by the
// power), and the remaining roundings.
double hgFloatRelativeError(double g) {
    double a = 1 - std::fabs(g), eps = FLT_EPSILON;
    return 3 * std::fabs(g) / (a * a) * eps / 2 + 1.5 * 4 * eps / (a * a) + 8 * eps;
}

TEST(ShPhaseWeights, HgClosedFormMatchesQuadrature) {
    const int order = MaxShOrder;
    double quad[order + 1];
    float closed[order + 1];
    for (float g : {0.f, 0.3f, -0.6f, 0.85f, 0.9f, -0.9f, 0.95f}) {
        hgLegendreWeights(order, g, closed);
        // 256 nodes: rho^-512 < 1e-23 for |g| <= 0.9; 0.95 gets 1024.
        int nodes = std::fabs(g) > 0.9f ? 1024 : 256;
        phaseLegendreWeights(order, [g](double u) { return hgPhaseD(u, g); }, quad, nodes);
        for (int l = 0; l <= order; ++l) {
            double exact = std::pow(double(g), l);
            EXPECT_NEAR(quad[l], exact, 1e-12) << "g " << g << " l " << l;
            // l float multiplies of |values| <= 1.
            EXPECT_NEAR(closed[l], exact, (l + 1) * double(FLT_EPSILON)) << "g " << g << " l " << l;
        }
        // The renderer's float hgPhase: sum_i w_i p_i |P_l| <= 1, so the
        // absolute error is at most its relative error.
        phaseLegendreWeights(order, [g](double u) { return double(hgPhase(float(u), g)); }, quad, nodes);
        for (int l = 0; l <= order; ++l)
            EXPECT_NEAR(quad[l], std::pow(double(g), l), hgFloatRelativeError(g)) << "g " << g << " l " << l;
    }
}

TEST(ShPhaseWeights, OtherNormalisedPhases) {
    double w[MaxShOrder + 1];
    // Isotropic: only the constant band.
    phaseLegendreWeights(MaxShOrder, [](double) { return 1 / (4 * PiD); }, w);
    EXPECT_NEAR(w[0], 1.0, 1e-13);
    for (int l = 1; l <= MaxShOrder; ++l) EXPECT_NEAR(w[l], 0.0, 1e-13);
    // Rayleigh 3/(16 pi)(1+u^2) = 3/(16 pi)(4/3 P_0 + 2/3 P_2): w'_2 = 1/10.
    phaseLegendreWeights(MaxShOrder, [](double u) { return 3 / (16 * PiD) * (1 + u * u); }, w);
    for (int l = 0; l <= MaxShOrder; ++l) EXPECT_NEAR(w[l], l == 0 ? 1.0 : (l == 2 ? 0.1 : 0.0), 1e-13);
    // Two-lobe HG mixture: weights mix linearly, w'_0 = 1.
    phaseLegendreWeights(
        MaxShOrder, [](double u) { return 0.7 * hgPhaseD(u, 0.8) + 0.3 * hgPhaseD(u, -0.4); }, w);
    for (int l = 0; l <= MaxShOrder; ++l)
        EXPECT_NEAR(w[l], 0.7 * std::pow(0.8, l) + 0.3 * std::pow(-0.4, l), 1e-12) << "l " << l;
}

TEST(ShPhaseWeights, IsotropicConvolutionKeepsOnlyBandZero) {
    std::vector<float> F = randomCoefficients(MaxShOrder, 51), out(shCount(MaxShOrder));
    float weights[MaxShOrder + 1];
    hgLegendreWeights(MaxShOrder, 0.f, weights);
    shConvolvePhase(MaxShOrder, weights, F.data(), out.data());
    EXPECT_EQ(out[0], F[0]);
    for (int i = 1; i < shCount(MaxShOrder); ++i) EXPECT_EQ(out[i], 0.f) << "i " << i;
    // In place, as the cache does it.
    shConvolvePhase(MaxShOrder, weights, F.data(), F.data());
    EXPECT_EQ(F, out);
}

TEST(ShClamp, PeakedLobeRingsNegativeAndClampKeepsPositivePart) {
    // Order 3 truncation of HG g = 0.95 from one photon along d: at -d the
    // series is (1 - 3g + 5g^2 - 7g^3)/(4 pi) < 0.
    const int order = 3;
    const float g = 0.95f;
    const Vec3 d = normalize(Vec3(-0.3f, 0.5f, 0.8f));
    float F[16], Y[16], weights[order + 1];
    evalSh(order, d, F);
    hgLegendreWeights(order, g, weights);
    shConvolvePhase(order, weights, F, F);
    const double bound = shCount(order) / (4 * PiD);

    evalSh(order, -d, Y);
    double gd = g;
    double antipode = (1 - 3 * gd + 5 * gd * gd - 7 * gd * gd * gd) / (4 * PiD);
    ASSERT_LT(antipode, 0);
    EXPECT_NEAR(evalShSum(16, F, Y), antipode, kFloatTol * bound);
    EXPECT_EQ(evalShNonNegative(16, F, Y), 0.f);

    SphereQuadrature q(32, 64);
    int negative = 0;
    for (const Vec3& w : q.dirs) {
        evalSh(order, w, Y);
        float sum = evalShSum(16, F, Y), clamped = evalShNonNegative(16, F, Y);
        EXPECT_GE(clamped, 0.f);
        if (sum > 0)
            EXPECT_EQ(clamped, sum);
        else
            ++negative;
    }
    EXPECT_GT(negative, 0);
    // The forward peak itself survives unclamped.
    evalSh(order, d, Y);
    EXPECT_NEAR(evalShNonNegative(16, F, Y), (1 + 3 * gd + 5 * gd * gd + 7 * gd * gd * gd) / (4 * PiD),
                kFloatTol * bound);
}

}  // namespace
}  // namespace vdbmarch
