// Environment maps: the documented orientation, rotation, the sampler's pdf
// (integrates to one, chi-square of sampled directions against it), and the
// light-sampling estimator of the map's integral and of irradiance against
// quadrature over the texels.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "scene/environment.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;


// A smooth sky brighter towards +Y, with a small bright "sun" block of texels.
std::vector<Color> skyTexels(int w, int h, int sunX, int sunY, int sunSize, float sun) {
    std::vector<Color> t(size_t(w * h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float v = (y + 0.5f) / h;
            Color c(0.2f + 0.8f * (1 - v), 0.3f + 0.7f * (1 - v), 1.f);
            if (x >= sunX && x < sunX + sunSize && y >= sunY && y < sunY + sunSize) c = Color(sun, sun * 0.9f, sun * 0.7f);
            t[size_t(y * w + x)] = c * (0.5f + 0.5f * float((x * 13 + y * 7) % 4) / 3.f);
        }
    return t;
}

TEST(Environment, OrientationIsTheDocumentedLatLongConvention) {
    // Directions of the texel centres that the convention names.
    EXPECT_NEAR(Environment::uvToDirection(0.5f, 0.f).y, 1, 1e-6f);           // top row: +Y
    const Vec3 centre = Environment::uvToDirection(0.5f, 0.5f);             // image centre: +Z
    EXPECT_NEAR(centre.z, 1, 1e-6f);
    const Vec3 quarter = Environment::uvToDirection(0.25f, 0.5f);           // u = 1/4: +X
    EXPECT_NEAR(quarter.x, 1, 1e-6f);
    const Vec3 left = Environment::uvToDirection(0.f, 0.5f);                // left edge: -Z
    EXPECT_NEAR(left.z, -1, 1e-6f);
    // Round trip away from the poles and the seam.
    Rng rng(1);
    for (int i = 0; i < 1000; ++i) {
        const float u = 0.001f + 0.998f * rng.uniform(), v = 0.001f + 0.998f * rng.uniform();
        float u2, v2;
        Environment::directionToUv(Environment::uvToDirection(u, v), u2, v2);
        EXPECT_NEAR(u2, u, 2e-5f);
        EXPECT_NEAR(v2, v, 2e-5f);
    }
}

TEST(Environment, RadianceReadsTheTexelAndRotationTurnsAboutY) {
    const int w = 64, h = 32;
    std::vector<Color> t(size_t(w * h), Color(0));
    t[size_t((h / 2) * w + w / 2)] = Color(5, 6, 7);  // the texel just below the horizon at +Z
    // Column w/2 starts at +Z and runs towards -X (u grows from -Z through +X, +Z, -X).
    const Vec3 justBelowPlusZ = normalize(Vec3(-0.01f, -0.02f, 1));
    EXPECT_EQ(Environment(t, w, h, 2, 0).radiance(justBelowPlusZ), Color(10, 12, 14));  // times the scale
    // Turned by 90 degrees about +Y (right-handed): what looked along +Z now looks along +X.
    const Environment turned(t, w, h, 1, 90);
    EXPECT_EQ(turned.radiance(normalize(Vec3(1, -0.02f, 0.01f))), Color(5, 6, 7));
    EXPECT_EQ(turned.radiance(justBelowPlusZ), Color(0));
}

// The backdrop lookup: texel values at texel centres, the mean of two
// neighbours half-way between them, across the azimuth seam too; a flat
// map stays flat.
TEST(Environment, BackdropIsBilinearBetweenTexelCentres) {
    const int w = 8, h = 4;
    std::vector<Color> t(size_t(w * h), Color(0));
    t[size_t(1 * w + 2)] = Color(4, 0, 0);
    t[size_t(1 * w + 3)] = Color(0, 4, 0);
    t[size_t(1 * w + 7)] = Color(0, 0, 8);
    t[size_t(1 * w + 0)] = Color(8, 0, 0);
    const Environment env(t, w, h, 1, 0);
    auto dir = [&](float x, float y) { return Environment::uvToDirection(x / w, y / h); };
    const Color centre = env.radianceSeen(dir(2.5f, 1.5f));
    EXPECT_NEAR(centre.x, 4, 1e-4f);
    EXPECT_NEAR(centre.y, 0, 1e-4f);
    const Color between = env.radianceSeen(dir(3.f, 1.5f));
    EXPECT_NEAR(between.x, 2, 1e-4f);
    EXPECT_NEAR(between.y, 2, 1e-4f);
    const Color seam = env.radianceSeen(dir(8.f - 1e-4f, 1.5f));  // between column 7 and column 0
    EXPECT_NEAR(seam.z, 4, 1e-3f);
    EXPECT_NEAR(seam.x, 4, 1e-3f);
    const Environment flat(std::vector<Color>(size_t(w * h), Color(0.5f)), w, h, 1, 0);
    for (float y : {0.1f, 1.5f, 3.9f})
        for (float x : {0.f, 3.3f, 7.99f}) EXPECT_NEAR(flat.radianceSeen(dir(x, y)).x, 0.5f, 1e-6f);
}

TEST(Environment, PdfIntegratesToOneAndMatchesSampling) {
    const int w = 32, h = 16;
    const Environment env(skyTexels(w, h, 20, 5, 2, 40), w, h, 1, 30);
    // Bins in (theta, phi), 2 x 2 a texel, so that the quadrature below
    // never straddles a bin edge (bins at the poles are small: pooled).
    const int bz = 32, bphi = 64;
    auto binOf = [&](const Vec3& d) {
        const double theta = std::atan2(std::hypot(double(d.x), double(d.z)), double(d.y));
        const int iz = std::min(bz - 1, int(theta / PiD * bz));
        double phi = std::atan2(double(d.x), double(-d.z));
        if (phi < 0) phi += 2 * PiD;
        const int ip = std::min(bphi - 1, int(phi / (2 * PiD) * bphi));
        return size_t(iz * bphi + ip);
    };
    // Expected counts: the pdf integrated over each bin by a fine midpoint
    // rule in (theta, phi), where pdf x sin(theta) is bounded (in z the
    // pdf's 1/sin(theta) at the poles would defeat the rule).
    const long n = 500000;
    std::vector<double> expected(size_t(bz * bphi), 0), observed(expected.size(), 0);
    const int nt = 16 * 64, np = 32 * 64;  // 64 points per texel edge
    double total = 0;
    for (int it = 0; it < nt; ++it)
        for (int ip = 0; ip < np; ++ip) {
            const double theta = PiD * (it + 0.5) / nt, phi = 2 * PiD * (ip + 0.5) / np;
            const double s = std::sin(theta);
            const Vec3 d(float(s * std::sin(phi)), float(std::cos(theta)), float(-s * std::cos(phi)));
            const double p = env.pdf(d) * s * (PiD / nt) * (2 * PiD / np);
            expected[binOf(d)] += n * p;
            total += p;
        }
    EXPECT_NEAR(total, 1, 1e-3);  // the rule's error where texel and bin edges cut its cells
    Rng rng(11);
    long mismatch = 0;
    for (long i = 0; i < n; ++i) {
        Vec3 d;
        float pdf;
        Color lop;
        ASSERT_TRUE(env.sample(rng.uniform(), rng.uniform(), d, pdf, lop));
        mismatch += env.pdf(d) != pdf;
        observed[binOf(d)] += 1;
    }
    EXPECT_EQ(mismatch, 0);
    const ChiSquare c = pooledChiSquare(observed, expected, 20);
    EXPECT_GT(c.p(), 1e-4) << "chi2 " << c.chi2 << " dof " << c.dof;
}

// Irradiance on a surface with normal n by light sampling, against the sum
// over texels of L x (cosine integrated over the texel by quadrature); and
// the mean of L / pdf is the map's integral.
TEST(Environment, LightSamplingEstimatesIrradianceAndIntegral) {
    const int w = 64, h = 32;
    const Environment env(skyTexels(w, h, 40, 9, 3, 60), w, h, 1.5f, -50);
    const std::vector<Vec3> normals = {{0, 1, 0}, normalize(Vec3(1, 0.2f, -0.4f)), normalize(Vec3(-0.3f, -1, 0.5f))};
    for (const Vec3& n : normals) {
        const double truth = environmentIrradianceByQuadrature(env, n, -50);
        SampleStats e, integral;
        Rng rng(21);
        for (int i = 0; i < 400000; ++i) {
            Vec3 d;
            float pdf;
            Color lop;
            if (!env.sample(rng.uniform(), rng.uniform(), d, pdf, lop)) {
                e.add(0);
                integral.add(0);
                continue;
            }
            e.add(double(lop.x) * std::max(0.f, dot(d, n)));
            integral.add(lop.x);
        }
        // The quadrature's own error: cosine across 1/8 texel, ~1e-3 relative.
        EXPECT_NEAR(e.mean(), truth, 4 * e.stdError() + 2e-3 * truth) << "n = " << n.x << "," << n.y << "," << n.z;
        EXPECT_NEAR(integral.mean(), env.integral().x, 4 * integral.stdError());
    }
}

TEST(Environment, BlackMapHasNoLightAndConstantIsUniform) {
    const Environment black(std::vector<Color>(8 * 4, Color(0)), 8, 4, 1, 0);
    EXPECT_TRUE(black.isBlack());
    Vec3 d;
    float pdf;
    Color lop;
    EXPECT_FALSE(black.sample(0.3f, 0.6f, d, pdf, lop));
    EXPECT_EQ(black.pdf(Vec3(0, 1, 0)), 0);
    const Environment constant(Color(0.5f, 1, 2));
    EXPECT_FALSE(constant.hasMap());
    EXPECT_EQ(constant.radiance(Vec3(0, 0, 1)), Color(0.5f, 1, 2));
    EXPECT_NEAR(constant.integral().z, 8 * PiD, 1e-5);
    // A constant map: integral 4 pi L up to float rounding of the rows' solid angles.
    const Environment flat(std::vector<Color>(64 * 32, Color(2)), 64, 32, 1, 0);
    EXPECT_NEAR(flat.integral().x, 8 * PiD, 1e-4);
}

}  // namespace
}  // namespace vdbmarch
