// Full light transport against answers that do not share the methods'
// approximations: an emissive furnace (every pixel exactly 1) for every
// method and L_i source, and the continuation-path L_i of the marchers
// against the reference path tracer on a heterogeneous VDB cloud.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <tuple>

#include "core/blackbody.h"
#include "core/error.h"
#include "estimators/estimator.h"
#include "illumination/illumination.h"
#include "render/render.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

// An emissive VDB box of density 1, 41 units on a side (voxel 1), with
// sigma_a = sigma_s = 1 (albedo 0.5), g = 0.7 and L_e = 1, seen from its
// centre. In equilibrium L = L_e solves the transfer equation everywhere
// (-sigma_t L + sigma_a L_e + sigma_s integral p L = 0), so every pixel is 1
// up to the light from beyond the box, attenuated by e^-40 at least.
// max_depth 64 leaves 0.5^64 of the multiple scattering out.
class EmissiveFurnace : public ::testing::TestWithParam<std::tuple<Method, LiSource>> {};

// Per channel (and, last, the channels' average): the mean pixel of each of 8
// independent renders (pixel and photon seeds). The pixels of one render
// share its photon map, whose error is common to all of them, so the
// standard error comes from the spread of whole renders.
std::array<SampleStats, 4> furnaceRenders(Method method, LiSource li, const std::string& emission) {
    TempDir dir("furnace");
    const std::string vdb = writeEmissiveBox(dir / "furnace.vdb", -20, 20, 4, 1.0);
    std::array<SampleStats, 4> renders;
    for (int run = 0; run < 8; ++run) {
        auto scene = sceneFromJson(str(R"({
            "camera": {"position": [0.3, 0.2, 0.1], "look_at": [1, 0.5, -2], "fov_deg": 90, "resolution": [12, 9]},
            "media": [{"type": "vdb", "file": ")", vdb, R"(", "sigma_a": 1, "sigma_s": 1, "g": 0.7,
                       "emission": )", emission, R"(}],
            "photons": {"count": 100000, "k": 100},
            "render": {"max_depth": 64, "seed": )", 100 + run, R"(, "spp": )", isPathTracer(method) ? 16 : 4,
                                       R"(, "li": ")", liSourceName(li), R"("}})"));
        scene->desc.render.method = method;
        RenderResult r = renderImage(*scene);
        std::array<SampleStats, 4> pixels;
        for (int y = 0; y < r.image.height; ++y)
            for (int x = 0; x < r.image.width; ++x) {
                const Color c = r.image.rgb(x, y);
                for (int ch = 0; ch < 3; ++ch) pixels[size_t(ch)].add(c[ch]);
                pixels[3].add(average(c));
            }
        for (size_t ch = 0; ch < 4; ++ch) renders[ch].add(pixels[ch].mean());
    }
    return renders;
}

TEST_P(EmissiveFurnace, EveryPixelIsOne) {
    const auto [method, li] = GetParam();
    const SampleStats renders = furnaceRenders(method, li, R"({"grid": "temperature", "scale": 1})")[3];
    if (std::getenv("VDBMARCH_VERBOSE"))
        std::printf("furnace %s li=%s: mean %.5f, SE %.2g\n", methodName(method), liSourceName(li), renders.mean(),
                    renders.stdError());
    EXPECT_NEAR(renders.mean(), 1.0, 4 * renders.stdError()) << methodName(method) << " li=" << liSourceName(li);
}

// The same furnace glowing as a 3000 K blackbody: every pixel is
// L_e = blackbodyRadiance(3000 K) (luminance 1.46) in each channel. With li = photons the
// emitted photons carry that colour (the sampler weights voxels by the
// blackbody luminance, the power per channel by the radiance).
class BlackbodyFurnace : public EmissiveFurnace {};

TEST_P(BlackbodyFurnace, PixelsAreTheBlackbodyRadiance) {
    const auto [method, li] = GetParam();
    const auto renders =
        furnaceRenders(method, li, R"({"grid": "temperature", "blackbody": true, "temperature_scale": 3000})");
    const Color expected = blackbodyRadiance(3000);
    for (int ch = 0; ch < 3; ++ch) {
        const SampleStats& s = renders[size_t(ch)];
        if (std::getenv("VDBMARCH_VERBOSE"))
            std::printf("blackbody furnace %s li=%s channel %d: mean %.5f (expected %.5f), SE %.2g\n",
                        methodName(method), liSourceName(li), ch, s.mean(), expected[ch], s.stdError());
        EXPECT_NEAR(s.mean(), expected[ch], 4 * s.stdError()) << methodName(method) << " li=" << liSourceName(li)
                                                               << " channel " << ch;
    }
}

std::string furnaceName(const ::testing::TestParamInfo<std::tuple<Method, LiSource>>& info) {
    return str(methodName(std::get<0>(info.param)), "_", liSourceName(std::get<1>(info.param)));
}

std::vector<std::tuple<Method, LiSource>> furnaceCases() {
    std::vector<std::tuple<Method, LiSource>> cases;
    for (Method m : estimatorMethods())
        for (LiSource li : {LiSource::Path, LiSource::Photons})
            if (!isPathTracer(m) || li == LiSource::Path) cases.push_back({m, li});  // path tracers have no L_i source
    return cases;
}

INSTANTIATE_TEST_SUITE_P(Methods, EmissiveFurnace, ::testing::ValuesIn(furnaceCases()), furnaceName);

// The photon cases, where the blackbody colour travels as photon power, and
// the reference path tracer.
std::vector<std::tuple<Method, LiSource>> blackbodyFurnaceCases() {
    std::vector<std::tuple<Method, LiSource>> cases;
    for (const auto& c : furnaceCases())
        if (isPathTracer(std::get<0>(c)) || std::get<1>(c) == LiSource::Photons) cases.push_back(c);
    return cases;
}

INSTANTIATE_TEST_SUITE_P(Methods, BlackbodyFurnace, ::testing::ValuesIn(blackbodyFurnaceCases()), furnaceName);

// The continuation estimate of L_i is unbiased: every marcher with
// render.li = "path" agrees with the reference path tracer on the VDB cloud
// under a sun and a sphere light with multiple scattering (max_depth 8; no
// point light and no glass, so no photon is traced), within 4 standard
// errors of the paired pixel differences plus the marchers' own step bias
// along the camera ray (uniform: eq. 5's O(dx^2); sampled: one density
// sample per step in the transmittance), bounded by 1% of the mean at step
// 0.01.
TEST(ContinuationPaths, AgreeWithTheReferenceOnAVdbCloud) {
    const std::string file = samplePath("cloud.json");
    const std::vector<std::string> common = {
        "camera.resolution=[32,24]", "render.max_depth=8", "render.step=0.01", "render.li=\"path\"",
        R"(media=[{"name": "cloud", "type": "vdb", "file": "cloud.vdb", "sigma_a": 0.3, "sigma_s": 6, "g": 0.6}])",
        R"(lights=[{"type": "directional", "direction": [0.6, -0.7, -0.45], "irradiance": [2, 2, 2]},
                   {"type": "sphere", "position": [-1.2, 1.6, 1.0], "radius": 0.3, "power": [30, 30, 30]}])",
        "background=0.05"};
    auto render = [&](Method m, int spp, int seed) {
        std::vector<std::string> o = common;
        o.push_back(str("render.spp=", spp));
        o.push_back(str("render.seed=", seed));
        SceneDesc d = loadSceneFile(file, o);
        d.render.method = m;
        return renderImage(*buildScene(d)).image;
    };
    const Image ref = render(Method::Reference, 256, 1);
    for (Method m : estimatorMethods()) {
        if (m == Method::Reference) continue;
        const Image img = render(m, m == Method::Uniform ? 4 : 16, 2);
        ASSERT_EQ(prepareIllumination(*buildScene(loadSceneFile(file, common)), m).indirect, nullptr);
        SampleStats d, mean;
        for (int y = 0; y < ref.height; ++y)
            for (int x = 0; x < ref.width; ++x) {
                d.add(average(img.rgb(x, y)) - average(ref.rgb(x, y)));
                mean.add(average(ref.rgb(x, y)));
            }
        if (std::getenv("VDBMARCH_VERBOSE"))
            std::printf("continuation %s: mean diff %.4g (%.2f%% of %.4g), %.1f SE\n", methodName(m), d.mean(),
                        100 * d.mean() / mean.mean(), mean.mean(), d.mean() / d.stdError());
        EXPECT_NEAR(d.mean(), 0.0, 4 * d.stdError() + 0.01 * mean.mean()) << methodName(m);
    }
}

}  // namespace
}  // namespace vdbmarch
