// Guided path tracing (render.method = "guided_path"): the radiance cache as
// the path loop's guide (marchers/cache_path_guide.h).
//  - The guided free flight along fixed rays through the heterogeneous VDB
//    cloud: its samples follow the density it reports (chi-square; the
//    weights of distance sampling towards lights use that density), and its
//    weighted collisions integrate T sigma_s over every part of the ray, and
//    its passes T(tEnd), against quadrature of the grid's own density:
//    unbiased, with the cache as baked and with a wrong one (every cell's
//    coefficients moved to another cell, or zeroed).
//  - Whole images against the plain path tracer on the cloud with glass, a
//    spot, a point and a sphere light and the sky map, with guided
//    directions off and on (render.product_sampling), and with guided
//    roulette and splitting (render.guided_roulette), which stay
//    deterministic for any thread count and crop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>

#include "illumination/illumination.h"
#include "estimators/cache_path_guide.h"
#include "support/support.h"
#include "transport/media_point.h"
#include "transport/thread_context.h"

namespace vdbmarch {
namespace {

using namespace test;

enum class CacheState { AsBaked, Moved, Zeroed };

void spoil(RadianceCache& cache, CacheState state) {
    const size_t n = cache.cells.size(), k = size_t(cache.coefficientCount());
    if (state == CacheState::Zeroed) std::fill(cache.coefficients.begin(), cache.coefficients.end(), 0.f);
    if (state == CacheState::Moved)  // cell i takes cell n - 1 - i's coefficients
        for (size_t i = 0; i < n / 2; ++i)
            std::swap_ranges(cache.coefficients.begin() + long(i * k), cache.coefficients.begin() + long((i + 1) * k),
                             cache.coefficients.begin() + long((n - 1 - i) * k));
}

class GuidedFlight : public ::testing::TestWithParam<CacheState> {};

TEST_P(GuidedFlight, FollowsItsDensityAndIntegratesTransmittanceTimesScattering) {
    const std::string scene = str(R"({"camera": {"type": "perspective", "position": [0, 0.2, 3], "look_at": [0, 0.2, 0],
        "fov_deg": 30, "resolution": [8, 8]},
        "lights": [{"type": "directional", "direction": [0.6, -0.7, -0.45], "irradiance": 3},
                   {"type": "sphere", "position": [-0.6, 0.9, 0.4], "radius": 0.1, "power": 20}],
        "media": [{"name": "cloud", "type": "vdb", "file": ")", samplePath("cloud.vdb"),
                                  R"(", "sigma_a": 0.3, "sigma_s": 6, "g": 0.5}],
        "photons": {"count": 50000}, "render": {"method": "guided_path", "max_depth": 4, "seed": 3}})");
    auto s = sceneFromJson(scene);
    Illumination il = prepareIllumination(*s, Method::GuidedPath);
    ASSERT_TRUE(il.cache);
    spoil(*il.cache, GetParam());
    auto guide = makeCachePathGuide(*s, *il.cache);
    ThreadContext ctx(*s);
    const Medium& medium = *s->media[0];
    const BBox b = medium.worldBounds();
    const Vec3 centre = (b.lo + b.hi) * 0.5f;
    const float sigmaT = medium.sigma_a.x + medium.sigma_s.x, sigmaS = medium.sigma_s.x;
    // Two rays: through the middle of the cloud, and grazing its top.
    const Vec3 targets[2] = {centre, Vec3(centre.x, centre.y + 0.3f * (b.hi.y - centre.y), centre.z)};
    for (int r = 0; r < 2; ++r) {
        const Vec3 o = targets[r] + normalize(Vec3(-1, 0.2f, 0.7f)) * length(b.hi - b.lo);
        const Ray ray{o, normalize(targets[r] - o)};
        const float tEnd = 2 * length(targets[r] - o);
        ASSERT_TRUE(guide->prepareFlight(ctx, Scene::WorldRegion, ray, tEnd, -1)) << "ray " << r;

        // Quadrature along the ray: the reported density and T sigma_s, T
        // from the grid's density by the midpoint rule on a fine grid.
        const int bins = 60, sub = 400;
        std::vector<double> expected(bins + 1, 0.0), integral(bins, 0.0);
        double tau = 0;
        MediumQuery& q = *ctx.queries[0];
        const double dt = double(tEnd) / (bins * sub);
        for (int i = 0; i < bins; ++i)
            for (int j = 0; j < sub; ++j) {
                const double t = (i * sub + j + 0.5) * dt;
                expected[size_t(i)] += double(guide->flightDensity(ctx, float(t))) * dt;
                const double rho = q.density(ray.at(float(t)));
                integral[size_t(i)] += std::exp(-tau - 0.5 * sigmaT * rho * dt) * sigmaS * rho * dt;
                tau += sigmaT * rho * dt;
            }
        double scatter = 0;
        for (int i = 0; i < bins; ++i) scatter += expected[size_t(i)];
        expected[bins] = 1 - scatter;  // passes
        ASSERT_GT(scatter, 0.05);
        ASSERT_LT(scatter, 1.0 + 1e-3);
        const double Tend = std::exp(-tau);

        const int n = 200000;
        std::vector<double> observed(bins + 1, 0.0);
        std::vector<SampleStats> weighted(bins + 1);
        SampleStats all;  // the whole segment: int T sigma_s + T(tEnd)
        Rng rng(hashValues(0x666c69676874, uint64_t(r), uint64_t(GetParam())));
        MediumPoint mp;
        for (int k = 0; k < n; ++k) {
            const vdbmarch::GuidedFlight f = guide->sampleFlight(ctx, rng, mp);
            const int bin = f.scattered ? std::min(bins - 1, int(double(f.t) / double(tEnd) * bins)) : bins;
            observed[size_t(bin)] += 1;
            for (int i = 0; i <= bins; ++i) weighted[size_t(i)].add(i == bin ? double(f.weight.x) : 0.0);
            all.add(double(f.weight.x));
        }
        for (double& e : expected) e *= n;
        const ChiSquare c = pooledChiSquare(observed, expected, 5);
        EXPECT_GT(c.p(), 1e-4) << "ray " << r << " chi2 " << c.chi2 << " dof " << c.dof;
        // The quadrature's own error (midpoint rule on 24000 points, the
        // trilinear grid's kinks inside steps) is below 1e-3 of the whole.
        double total = Tend;
        for (double v : integral) total += v;
        EXPECT_NEAR(all.mean(), total, 4 * all.stdError() + 1e-3 * total) << "ray " << r;
        for (int i = 0; i <= bins; ++i) {
            const double want = i < bins ? integral[size_t(i)] : Tend;
            EXPECT_NEAR(weighted[size_t(i)].mean(), want, 4 * weighted[size_t(i)].stdError() + 1e-3 * total)
                << "ray " << r << " bin " << i;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Caches, GuidedFlight,
                         ::testing::Values(CacheState::AsBaked, CacheState::Moved, CacheState::Zeroed),
                         [](const ::testing::TestParamInfo<CacheState>& i) {
                             return i.param == CacheState::AsBaked ? std::string("AsBaked")
                                    : i.param == CacheState::Moved ? std::string("Moved")
                                                                   : std::string("Zeroed");
                         });

// The cloud under the sky map (max_depth 6) holding a point light, lit by a
// spot and a sphere light, with a glass ball in front (as the light-distance
// test): paired per-pixel differences of guided path tracing (directions
// from the phase, then from phase x cached radiance) against the plain path
// tracer have zero mean over the image and each quadrant within 4 standard
// errors.
TEST(GuidedPath, AgreesWithThePathTracerOnAHeterogeneousCloudWithGlassAndSky) {
    std::vector<std::string> common = cloudSkyWithLightsAndGlass();
    common.insert(common.end(), {"render.spp=128", "photons.count=20000"});
    auto render = [&](const std::string& method, bool product, bool roulette = false) {
        std::vector<std::string> o = common;
        o.push_back("render.method=\"" + method + "\"");
        o.push_back(str("render.product_sampling=", product ? "true" : "false"));
        o.push_back(str("render.guided_roulette=", roulette ? "true" : "false"));
        return renderImage(*buildScene(loadSceneFile(samplePath("cloud_sky.json"), o))).image;
    };
    const Image base = render("reference", false);
    for (bool product : {false, true})
        expectPairedAgreement(base, render("guided_path", product), str("product sampling ", product));
    expectPairedAgreement(base, render("guided_path", false, true), "guided roulette and splitting");
}

// With guided roulette and splitting (copies traced depth first from the
// vertex, their random numbers from the path's own stream) the image is the
// same for any thread count and any crop of the frame.
TEST(GuidedPath, RouletteAndSplittingAreDeterministicForAnyThreadCountAndCrop) {
    auto render = [](int threads, bool roulette, std::optional<PixelRect> crop) {
        RenderOptions options;
        options.crop = crop;
        return renderImage(*buildScene(loadSceneFile(
                               samplePath("cloud.json"),
                               {"camera.resolution=[32,24]", "render.spp=4", "render.max_depth=8",
                                "photons.count=20000", "render.method=\"guided_path\"",
                                str("render.guided_roulette=", roulette ? "true" : "false"),
                                str("render.threads=", threads)})),
                           options)
            .image;
    };
    const Image whole = render(1, true, std::nullopt);
    const Image other = render(3, true, std::nullopt);
    ASSERT_EQ(whole.rgba.size(), other.rgba.size());
    EXPECT_EQ(0, std::memcmp(whole.rgba.data(), other.rgba.data(), whole.rgba.size() * sizeof(float)));
    const PixelRect crop{7, 5, 29, 19};
    const Image part = render(2, true, crop);
    for (int y = crop.y0; y < crop.y1; ++y)
        EXPECT_EQ(0, std::memcmp(&part.rgba[size_t((y - crop.y0) * crop.width()) * 4],
                                 &whole.rgba[size_t(y * 32 + crop.x0) * 4], size_t(crop.width()) * 4 * sizeof(float)))
            << "row " << y;
    // The window did act: without it the pixels differ.
    const Image plain = render(1, false, std::nullopt);
    EXPECT_NE(0, std::memcmp(whole.rgba.data(), plain.rgba.data(), whole.rgba.size() * sizeof(float)));
}

}  // namespace
}  // namespace vdbmarch
