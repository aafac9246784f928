// Distance sampling towards lights (strategies/light_distances.h) in the path
// tracer: every experiments.volume_sampling mode against numerical quadrature of
// single scattering from a point and a spot light inside a homogeneous box,
// and the three modes against one another on a heterogeneous VDB cloud with
// multiple scattering, glass, a sphere light and an environment map; and the
// guided marcher's equiangular share against quadrature, and with caches
// that know nothing of the light.
#include <gtest/gtest.h>

#include <cmath>

#include "cache/radiance_cache.h"
#include "core/sampling.h"
#include "illumination/illumination.h"
#include "support/support.h"
#include "transport/phase.h"

namespace vdbmarch {
namespace {

using namespace test;

const char* const VolumeSamplingModes[] = {"distance", "equiangular", "mis"};

// Single scattering (max_depth 1) from a point light beside the view and a
// spot whose beam crosses it, both inside a homogeneous box (sigma_t 1,
// sigma_s 0.8, g 0.5), seen by an orthographic camera looking down -z. With
// pixel jitter the image mean is the mean of L over the view square:
//   L(x, y) = int_{z in box} exp(-sigma_t (0.5 - z)) sigma_s
//             sum_l p(wi . d) I_l falloff_l / r_l^2 exp(-sigma_t r_l) dz
// (a light inside the convex box: its shadow ray stays inside), integrated
// by the midpoint rule on 160 x 160 x 800 points (its error, measured by
// halving the grid, is below 1e-4 of the mean). The render's mean over the
// image and over its left and right halves must match within 4 standard
// errors of the pixel mean plus that quadrature bound.
TEST(LightDistance, SingleScatteringFromPointAndSpotMatchesQuadrature) {
    const double sigmaT = 1.0, sigmaS = 0.8;
    const float g = 0.5f;
    const std::string lights = R"("lights": [
        {"type": "point", "position": [0.85, 0.475, 0.1], "intensity": 0.5},
        {"type": "spot", "position": [0.475, -0.3, -0.2], "direction": [0, 1, 0.15], "cone_deg": 10,
         "falloff_deg": 3, "intensity": 2}])";
    const std::string media = str(R"("media": [{"type": "homogeneous", "sigma_a": 0.2, "sigma_s": 0.8, "g": )", g,
                                  R"(, "bounds": {"min": [-2, -2, -0.5], "max": [3, 3, 0.5]}}])");
    const std::string camera = R"("camera": {"type": "orthographic", "position": [0.475, 0.475, 5],
        "look_at": [0.475, 0.475, 0], "up": [0, 1, 0], "width_world": 0.5, "resolution": [32, 32]})";

    // Quadrature of the view-square mean, whole and by halves in x.
    const auto point = makeLight(pointLight(Vec3(0.85f, 0.475f, 0.1f), Color(0.5f)));
    const auto spot = makeLight(spotLight(Vec3(0.475f, -0.3f, -0.2f), normalize(Vec3(0, 1, 0.15f)), 10, 3, Color(2)));
    const Vec3 d(0, 0, -1);
    const int nxy = 160, nz = 800;
    double half[2] = {0, 0};
    for (int iy = 0; iy < nxy; ++iy)
        for (int ix = 0; ix < nxy; ++ix) {
            const double x = 0.225 + 0.5 * (ix + 0.5) / nxy, y = 0.225 + 0.5 * (iy + 0.5) / nxy;
            double L = 0;
            for (int iz = 0; iz < nz; ++iz) {
                const double z = 0.5 - (iz + 0.5) / nz;
                const Vec3 p{float(x), float(y), float(z)};
                double s = 0;
                for (const Light* l : {point.get(), spot.get()}) {
                    LightSample ls;
                    if (!l->sample(p, 0, 0, ls)) continue;
                    s += double(hgPhase(dot(ls.wi, d), g)) * ls.L.x * std::exp(-sigmaT * ls.dist);
                }
                L += std::exp(-sigmaT * (0.5 - z)) * sigmaS * s / nz;
            }
            half[ix * 2 / nxy] += L / (nxy * nxy / 2);
        }
    const double expected[3] = {0.5 * (half[0] + half[1]), half[0], half[1]};

    // The path tracer, and the guided marcher, whose L_i positions mix the
    // equiangular density into its per-ray pdf unless the mode is "distance".
    for (const char* method : {"reference", "guided"})
        for (const char* mode : VolumeSamplingModes) {
            auto scene = sceneFromJson("{" + camera + "," + lights + "," + media + str(R"(,
                "photons": {"count": 20000}, "render": {"method": ")", method,
                                                                      R"(", "max_depth": 1, "spp": 64, "seed": 5},
                "experiments": {"volume_sampling": ")", mode, "\"}}"));
            const Image img = renderImage(*scene).image;
            for (int part = 0; part < 3; ++part) {
                SampleStats st;
                for (int y = 0; y < 32; ++y)
                    for (int x = 0; x < 32; ++x)
                        if (part == 0 || (x < 16) == (part == 1)) st.add(img.rgb(x, y).x);
                EXPECT_NEAR(st.mean(), expected[part], 4 * st.stdError() + 1e-4 * expected[0])
                    << method << " " << mode << " part " << part;
            }
        }
}

// The modes estimate the same image: a VDB cloud (multiple scattering,
// max_depth 6) holding a point light, lit by a spot and a sphere light, under
// the sky map, with a glass ball in front. Paired per-pixel differences of
// each mode against "distance" (plain delta tracking) have zero mean over the
// image and each quadrant within 4 standard errors.
TEST(LightDistance, ModesAgreeOnAHeterogeneousCloudWithGlassAndSky) {
    std::vector<std::string> common = cloudSkyWithLightsAndGlass();
    common.insert(common.end(), {"render.method=\"reference\"", "render.spp=256"});
    auto render = [&](const std::string& mode) {
        std::vector<std::string> o = common;
        o.push_back("experiments.volume_sampling=\"" + mode + "\"");
        return renderImage(*buildScene(loadSceneFile(samplePath("cloud_sky.json"), o))).image;
    };
    const Image base = render("distance");
    for (const char* mode : {"equiangular", "mis"}) expectPairedAgreement(base, render(mode), mode);
}

// Per pixel, the squared difference of two renders (channels averaged).
SampleStats squaredDifferences(const Image& a, const Image& b) {
    SampleStats st;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const Color d = a.rgb(x, y) - b.rgb(x, y);
            st.add(double(average(d * d)));
        }
    return st;
}

// The guided marcher (the default where media sit in glass or delta lights
// shine through it) with a cache that knows nothing of the light: a cache
// baked before the light moved, read with --force. A spot's beam crosses a
// thin haze in view, its apex outside the view; single scattering. The
// cache is written to a file and read as `render --cache` reads it, zeroed
// and moved (cell i given cell n - 1 - i's coefficients). Every render
// agrees with the path tracer's (paired, 4 standard errors). Per sample, the
// pair MSE of a wrong cache is at most 2x the path tracer's (the issue's
// bound; measured 0.95-1.01x, standard error 0.13-0.15), three standard
// errors included, because a quarter of the positions follow the
// equiangular density over the beam. The paper's pdf alone
// (experiments.volume_sampling = "distance") measured 2.9-4.0x, and must stay
// above 1x: the scene shows what the share is for.
TEST(LightDistance, GuidedMarcherWithAWrongCacheKeepsItsNoise) {
    const std::string json = R"({"camera": {"type": "perspective", "position": [0, 0, 3], "look_at": [0, 0, 0],
        "fov_deg": 40, "resolution": [96, 72]},
        "lights": [{"type": "spot", "position": [-2.4, 0.1, 0.3], "direction": [1, -0.1, -0.15], "cone_deg": 10,
                    "falloff_deg": 3, "intensity": 20}],
        "media": [{"type": "homogeneous", "sigma_a": 0.05, "sigma_s": 0.3, "g": 0.3,
                   "bounds": {"min": [-3, -1.2, -1], "max": [3, 1.2, 1]}}],
        "photons": {"count": 40000}, "render": {"method": "@METHOD@", "max_depth": 1, "spp": 32, "seed": @SEED@},
        "experiments": {"volume_sampling": "@MODE@"}})";
    auto scene = [&](const std::string& method, const std::string& mode, int seed) {
        return sceneFromJson(subst(json, {{"METHOD", method}, {"MODE", mode}, {"SEED", str(seed)}}));
    };
    TempDir dir("wrongcache");
    Illumination il = prepareIllumination(*scene("guided", "mis", 1), Method::Guided);
    ASSERT_TRUE(il.cache);
    RadianceCache& c = *il.cache;
    const std::string zeroed = dir.path() + "/zeroed.vdb", moved = dir.path() + "/moved.vdb";
    const size_t n = c.cells.size(), k = size_t(c.coefficientCount());
    for (size_t i = 0; i < n / 2; ++i)
        std::swap_ranges(c.coefficients.begin() + long(i * k), c.coefficients.begin() + long((i + 1) * k),
                         c.coefficients.begin() + long((n - 1 - i) * k));
    c.save(moved);
    std::fill(c.coefficients.begin(), c.coefficients.end(), 0.f);
    c.save(zeroed);

    auto render = [&](const std::string& cache, const std::string& mode, int seed) {
        RenderOptions o;
        o.illumination.cacheFile = cache;
        return renderImage(*scene("guided", mode, seed), o).image;
    };
    const Image truth = renderImage(*scene("reference", "mis", 3)).image;
    const SampleStats pt =
        squaredDifferences(renderImage(*scene("reference", "mis", 1)).image, renderImage(*scene("reference", "mis", 2)).image);
    for (const char* mode : {"mis", "distance"})
        for (const std::string& cache : {zeroed, moved}) {
            const Image a = render(cache, mode, 1), b = render(cache, mode, 2);
            expectPairedAgreement(truth, a, str(mode, " ", cache));
            const SampleStats st = squaredDifferences(a, b);
            const double ratio = st.mean() / pt.mean();
            const double se = ratio * std::hypot(st.stdError() / st.mean(), pt.stdError() / pt.mean());
            if (std::string(mode) == "mis")
                EXPECT_LT(ratio + 3 * se, 2.0) << cache;
            else
                EXPECT_GT(ratio - 3 * se, 1.0) << cache << ": the scene no longer shows what the share is for";
        }
}

}  // namespace
}  // namespace vdbmarch
