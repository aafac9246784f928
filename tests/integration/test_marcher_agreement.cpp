// Method agreement: uniform (small step), transmittance and guided converge
// to the reference path tracer's image, on a heterogeneous VDB cloud under a
// spotlight and on a glass sphere holding smoke, in fog, over a diffuse
// floor, lit by a sphere light, with multiple scattering (max_depth 4). The marchers' L_i is exact for direct
// light (shadow rays) and takes the rest from the photon map, whose kNN
// estimate is consistent but biased at a finite photon count: the tolerance
// is the paired test's 4 standard errors plus that bias, bounded by the
// fraction `photonBias` of the image mean (justified below; 0 where no photon
// enters the estimate).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/error.h"
#include "estimators/estimator.h"
#include "render/render.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

struct Agreement {
    double meanDiff = 0, stdError = 0, mean = 0, relMse = 0;
};

// Paired per-pixel differences over the image (all channels): their mean is
// zero when two estimators agree, and their spread is the two noises.
Agreement compare(const Image& test, const Image& ref) {
    double s = 0, s2 = 0, m = 0, r2 = 0;
    size_t n = 0;
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x)
            for (int c = 0; c < 3; ++c) {
                double d = double(test.rgb(x, y)[c]) - double(ref.rgb(x, y)[c]);
                s += d;
                s2 += d * d;
                m += double(ref.rgb(x, y)[c]);
                r2 += double(ref.rgb(x, y)[c]) * double(ref.rgb(x, y)[c]);
                ++n;
            }
    Agreement a;
    a.meanDiff = s / double(n);
    a.stdError = std::sqrt(std::max(0.0, s2 / double(n) - a.meanDiff * a.meanDiff) / double(n - 1));
    a.mean = m / double(n);
    a.relMse = s2 / std::max(r2, 1e-30);
    return a;
}

RenderResult render(const std::string& sceneFile, const std::vector<std::string>& common, Method method, int spp) {
    std::vector<std::string> o = common;
    o.push_back(methodOverride(method));
    o.push_back(str("render.spp=", spp));
    return renderImage(*buildScene(loadSceneFile(sceneFile, o)));
}

// Every marcher against the reference: the uniform marcher at a small step
// (its bias is O((kappa dx)^2)) and 4 spp, the ray-pdf marchers (and any new
// method) at 32 spp.
struct Run {
    Method method;
    int spp;
    std::vector<std::string> extra;
};

std::vector<Run> marcherRuns() {
    std::vector<Run> runs;
    for (Method m : estimatorMethods()) {
        if (m == Method::Reference) continue;
        if (m == Method::Uniform) runs.push_back({m, 4, {"render.step=0.01"}});
        else runs.push_back({m, 32, {}});
    }
    return runs;
}

void checkAgreement(const std::string& name, const std::string& sceneFile, const std::vector<std::string>& common,
                    int referenceSpp, double photonBias) {
    const Image ref = render(sceneFile, common, Method::Reference, referenceSpp).image;
    const std::vector<Run> runs = marcherRuns();
    ASSERT_GE(runs.size(), 3u);
    for (const auto& run : runs) {
        std::vector<std::string> o = common;
        o.insert(o.end(), run.extra.begin(), run.extra.end());
        const RenderResult r = render(sceneFile, o, run.method, run.spp);
        // No allowance where no photon enters the estimate: the methods
        // without a cache trace none (guided builds its cache from photons,
        // which shapes only its pdf).
        if (photonBias == 0 && (run.method == Method::Uniform || run.method == Method::Transmittance)) {
            EXPECT_EQ(r.photons, 0u) << methodName(run.method);
        }
        Agreement a = compare(r.image, ref);
        EXPECT_NEAR(a.meanDiff, 0.0, 4 * a.stdError + photonBias * a.mean) << name << ": " << methodName(run.method);
        if (std::getenv("VDBMARCH_VERBOSE"))
            std::printf("%s %s: mean diff %.4g (%.2f%% of mean %.4g), SE %.3g, relMSE %.4g\n", name.c_str(), methodName(run.method),
                        a.meanDiff, 100 * a.meanDiff / a.mean, a.mean, a.stdError, a.relMse);
    }
}

// The photon map's share: with render.li = "path" (the default) photons carry
// only what paths cannot find, here the multiply scattered light of the spot
// (next-event estimation near a point or spot light has unbounded variance),
// and their kNN estimate is within a few percent where the photon density is
// smooth (PhotonMapAccuracy tests, 4 SE at k = 100). Measured
// (VDBMARCH_VERBOSE=1, 2026-12-03) on the cloud under the spot: -1.4%, -0.7%,
// -0.8% of the image mean for uniform, transmittance and guided (2.0, 1.2
// and 1.4 SE); 3% bounds that bias with margin.
// The sphere light traces no photons (no delta light, no caustic): every
// marcher is unbiased there but for the uniform marcher's step (O((kappa
// dx)^2) at step 0.01), so that scene gets no allowance beyond 4 SE.
constexpr double PhotonBias = 0.03;

TEST(MarcherAgreement, VdbCloudUnderASpotlight) {
    const std::string scene = samplePath("cloud.json");
    checkAgreement("cloud+spot", scene,
                   {"camera.resolution=[32,24]", "render.max_depth=4", "render.seed=3",
                    R"(media=[{"name": "cloud", "type": "vdb", "file": "cloud.vdb", "sigma_a": 0.3, "sigma_s": 6, "g": 0.6}])",
                    R"(lights=[{"type": "spot", "position": [-1.2, 1.6, 1.0], "direction": [0.6, -0.7, -0.45],
                               "intensity": [8, 8, 8], "cone_deg": 14, "falloff_deg": 4}])",
                    "background=0"},
                   512, PhotonBias);
}

TEST(MarcherAgreement, GlassSphereWithSmokeUnderASphereLight) {
    const std::string scene = samplePath("glass.json");
    checkAgreement("glass+sphere light", scene,
                   {"camera.resolution=[32,24]", "render.max_depth=4", "render.seed=3",
                    R"(lights=[{"type": "sphere", "position": [-1.0, 1.6, 0.8], "radius": 0.25, "power": [60, 55, 50]}])"
                    // glass.json's diffuse floor stays: light scattered by the fog onto it
                    // reaches the marchers through their diffuse bounce.
                    },
                   512, 0.0);
}

}  // namespace
}  // namespace vdbmarch
