// Directions towards spot and collimated beams (strategies/beam_directions.h): the mixture
// of f's own sampling and the beams draws directions with the density it
// reports (chi-square on a fine grid of the sphere, the expected counts from
// pdf() by Gauss-Legendre quadrature per cell), at medium vertices inside
// and outside the beams and at a diffuse surface vertex; the beams' own
// density integrates to one; and the weight is f / pdf.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "cache/sh.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "scene/scene.h"
#include "support/sphere_quadrature.h"
#include "support/support.h"
#include "strategies/beam_directions.h"
#include "strategies/light_distances.h"
#include "transport/media_point.h"

namespace vdbmarch {
namespace {

// Two spots of different power and cone and a collimated quad, tilted
// against its beam, into a haze box of g = 0.5; wide beams so they cover
// many cells of the test's grid.
const char* const kBeamScene = R"({
  "camera": {"position": [0, 0, 6], "look_at": [0, 0, 0], "resolution": [8, 8]},
  "lights": [
    {"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "intensity": [20, 20, 20],
     "cone_deg": 20, "falloff_deg": 5},
    {"type": "spot", "position": [-3, 0.5, 0.5], "direction": [1, -0.2, 0], "intensity": [10, 12, 14],
     "cone_deg": 12, "falloff_deg": 3},
    {"type": "collimated_quad", "center": [-0.8, 1.5, -0.5], "u": [0.8, 0, 0.1], "v": [0, 0.3, 0.6],
     "direction": [0.2, -1, -0.1], "irradiance": [3, 3, 3]}],
  "media": [{"name": "haze", "type": "homogeneous", "sigma_a": 0.02, "sigma_s": 0.3, "g": 0.5,
             "bounds": {"min": [-1.5, -1, -1], "max": [1.5, 1, 1]}}],
  "render": {"method": "reference"}, "experiments": {"beam_directions": true}
})";

using test::fromZPhi;
using test::sphereIntegral;

struct BeamCase {
    const char* name;
    Vec3 x, d;
    bool surface;
};

class BeamMixtureSampling : public ::testing::TestWithParam<BeamCase> {};

TEST_P(BeamMixtureSampling, SamplerMatchesItsPdf) {
    const BeamCase& c = GetParam();
    auto scene = test::sceneFromJson(kBeamScene);
    ThreadContext ctx(*scene);
    const int region = Scene::WorldRegion;  // the haze is in the open
    MediumPoint mp;
    evalMedia(ctx, region, c.x, mp);
    ASSERT_TRUE(mp.scatters());
    const LightDistances distances(*scene, 1);
    const BeamDirections beams(*scene, distances, 2);
    ASSERT_TRUE(beams.hasBeams(region, false));
    ASSERT_EQ(beams.region(region).beams.size(), 3u);
    ASSERT_TRUE(beams.region(region).beams[2].prism);
    const ScatterVertex v = c.surface ? ScatterVertex::onSurface(c.x, c.d, Vec3(0, 1, 0), Color(0.5f))
                                      : ScatterVertex::inMedium(c.x, c.d, mp.phase);
    const BeamMixture mix(&ctx, &beams, region, &v);

    // The beams' own density is a density.
    const double beamMass =
        sphereIntegral([&](const Vec3& w) { return double(beams.beamDirectionPdf(ctx, region, c.x, w)); }, 96, 6);
    EXPECT_NEAR(beamMass, 1.0, 0.01) << c.name;

    const int nz = 48, np = 96, samples = 2000000;
    std::vector<double> observed(size_t(nz * np), 0), expected(size_t(nz * np), 0);
    Rng rng(23);
    int mismatches = 0, badWeights = 0, zero = 0;
    for (int i = 0; i < samples; ++i) {
        Color weight(1);
        float pdf;
        const Vec3 wi = mix.sample(rng, weight, pdf);
        if (!(pdf > 0)) {  // a surface's beam direction below the floor
            ++zero;
            EXPECT_TRUE(isBlack(weight));
            continue;
        }
        ASSERT_NEAR(length(wi), 1.f, 1e-5f);
        if (std::fabs(pdf - mix.pdf(wi)) > 1e-5f * pdf) ++mismatches;
        const Color expectW = v.f(wi) / pdf;
        if (std::fabs(weight.x - expectW.x) > 1e-4f * expectW.x) ++badWeights;
        double phi = std::atan2(double(wi.y), double(wi.x));
        if (phi < 0) phi += 2 * PiD;
        const int iz = std::min(nz - 1, int((double(wi.z) + 1) / 2 * nz));
        const int ip = std::min(np - 1, int(phi / (2 * PiD) * np));
        observed[size_t(iz * np + ip)] += 1;
    }
    EXPECT_EQ(mismatches, 0);
    EXPECT_EQ(badWeights, 0);
    if (!c.surface) {
        EXPECT_EQ(zero, 0);
    }
    std::vector<double> x, w;
    gaussLegendre(6, x, w);
    const double dz = 2.0 / nz, dp = 2 * PiD / np;
    // Where the sampler goes: the mixture, except that a surface keeps
    // only directions above it (the rest come back with pdf 0).
    auto density = [&](const Vec3& d) {
        return c.surface && !(d.y > 0) ? 0.0 : double(mix.pdf(d));
    };
    double total = 0;
    for (int iz = 0; iz < nz; ++iz)
        for (int ip = 0; ip < np; ++ip) {
            double mass = 0;
            for (size_t a = 0; a < x.size(); ++a)
                for (size_t b = 0; b < x.size(); ++b)
                    mass += density(fromZPhi(-1 + (iz + 0.5 + 0.5 * x[a]) * dz, (ip + 0.5 + 0.5 * x[b]) * dp)) * w[a] *
                            w[b] * 0.25 * dz * dp;
            expected[size_t(iz * np + ip)] = mass * samples;
            total += mass;
        }
    // The share of samples below a surface is what the density leaves there.
    if (c.surface) {
        EXPECT_NEAR(zero / double(samples), 1 - total, 4 * std::sqrt((1 - total) * total / samples) + 2e-3);
    }
    const test::ChiSquare chi = test::pooledChiSquare(observed, expected, 5);
    std::printf("[ chi2     ] %-24s chi2 %.1f dof %d p %.3f\n", c.name, chi.chi2, chi.dof, chi.p());
    ASSERT_GT(chi.dof, 1000);
    EXPECT_GT(chi.p(), 1e-3) << "chi2 " << chi.chi2 << " dof " << chi.dof;
}

INSTANTIATE_TEST_SUITE_P(Vertices, BeamMixtureSampling,
                         ::testing::Values(BeamCase{"outside the beams", Vec3(1.1f, -0.4f, 0.6f),
                                                    normalize(Vec3(0.3f, -1, 0.2f)), false},
                                           BeamCase{"inside a beam", Vec3(0.2f, 0.3f, -0.1f),
                                                    normalize(Vec3(1, 0.2f, -0.5f)), false},
                                           BeamCase{"inside the prism", Vec3(-0.5f, 0.f, -0.65f),
                                                    normalize(Vec3(0.2f, -1, -0.1f)), false},
                                           BeamCase{"on a floor", Vec3(0.7f, -0.99f, 0.4f),
                                                    normalize(Vec3(0.2f, -1, 0.1f)), true}),
                         [](const ::testing::TestParamInfo<BeamCase>& i) {
                             std::string n = i.param.name;
                             for (char& ch : n)
                                 if (ch == ' ') ch = '_';
                             return n;
                         });

}  // namespace
}  // namespace vdbmarch
