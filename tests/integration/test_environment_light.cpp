// Environment maps in whole renders, every method: a constant map gives the
// constant background's image, and a map that is black but for a small
// bright patch gives the image of the equivalent directional light.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "app/command_line.h"
#include "image/exr_io.h"
#include "render/render.h"
#include "scene/environment.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;


// The sample cloud at 32x24 with multiple scattering and no lights of its own.
std::vector<std::string> cloudOverrides(Method m, int spp, int seed) {
    return {"camera.resolution=[32,24]", "render.max_depth=8", "render.step=0.01", "lights=[]",
            R"(media=[{"name": "cloud", "type": "vdb", "file": "cloud.vdb", "sigma_a": 0.3, "sigma_s": 6, "g": 0.6}])",
            methodOverride(m), str("render.spp=", spp), str("render.seed=", seed), "background=0"};
}

Image render(std::vector<std::string> overrides) {
    return renderImage(*buildScene(loadSceneFile(samplePath("cloud.json"), overrides))).image;
}

int sppFor(Method m) { return m == Method::Uniform ? 4 : 16; }

// Mean over pixels of the paired difference of two independent renders and
// its standard error, and the mean of the first.
struct Difference {
    SampleStats d, mean;
};
// `what` labels the VDBMARCH_VERBOSE printout.
Difference difference(const Image& a, const Image& b, Method m, const char* what) {
    Difference r;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            r.d.add(average(a.rgb(x, y)) - average(b.rgb(x, y)));
            r.mean.add(average(a.rgb(x, y)));
        }
    if (std::getenv("VDBMARCH_VERBOSE"))
        std::printf("%s %s: mean diff %.4g (%.2f%% of %.4g), %.1f SE\n", methodName(m), what, r.d.mean(),
                    100 * r.d.mean() / r.mean.mean(), r.mean.mean(), r.d.mean() / r.d.stdError());
    return r;
}

class EnvironmentLight : public ::testing::TestWithParam<Method> {};

// A map of one constant radiance is the constant background: the same image
// within 4 standard errors of the paired pixel differences (the map takes
// the light-sampling + MIS path, the background f-sampling alone), and camera
// rays that escape see exactly the constant.
TEST_P(EnvironmentLight, ConstantMapEqualsTheConstantBackground) {
    const Method m = GetParam();
    TempDir dir;
    const Color sky(0.4f, 0.6f, 0.9f);
    Image map(64, 32);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x) map.set(x, y, sky, 1);
    writeExr(dir / "sky.exr", map);
    std::vector<std::string> withBackground = cloudOverrides(m, sppFor(m), 3);
    withBackground.back() = "background=[0.4, 0.6, 0.9]";
    std::vector<std::string> withMap = cloudOverrides(m, sppFor(m), 4);
    withMap.push_back(str("environment={\"file\": \"", dir / "sky.exr", "\"}"));
    const Image a = render(withBackground), b = render(withMap);
    const Difference r = difference(a, b, m, "constant map");
    EXPECT_NEAR(r.d.mean(), 0.0, 4 * r.d.stdError()) << methodName(m);
    // The top-left corner of the frame misses the cloud: the sky, up to the
    // rounding of the average over samples.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(b.rgb(0, 0)[c], sky[c], 1e-6f * sky[c]);
}

// A 256x128 map, black but for a 2x2-texel patch (2.8 degrees across) of
// radiance L at 60 degrees from the zenith, against a directional light of
// the patch's irradiance sum(L dOmega) along minus its mean direction. The
// images differ only by the patch's angular extent: its first-order effect
// cancels by symmetry about the mean direction, and the second order is
// bounded by (half-width)^2 x the relative curvature of the phase (g = 0.6:
// at most ~5 per rad^2) ~ 0.0245^2 x 5 = 0.3% of the mean; the bound allows
// 1% beside 4 standard errors.
TEST_P(EnvironmentLight, SmallPatchMatchesTheDirectionalLight) {
    const Method m = GetParam();
    TempDir dir;
    const int w = 256, h = 128, px = 40, py = 42;  // patch texels [px, px+1] x [py, py+1]
    const float L = 2000;
    Image map(w, h);
    double solid = 0;
    Vec3 centroid(0);
    for (int y = py; y < py + 2; ++y) {
        const double t0 = PiD * y / h, t1 = PiD * (y + 1) / h;
        const double dOmega = 2 * PiD / w * (std::cos(t0) - std::cos(t1));
        for (int x = px; x < px + 2; ++x) {
            map.set(x, y, Color(L), 1);
            solid += dOmega;
            centroid += Environment::uvToDirection((x + 0.5f) / w, (y + 0.5f) / h) * float(dOmega);
        }
    }
    writeExr(dir / "patch.exr", map);
    const Vec3 toLight = normalize(centroid);
    const float E = float(L * solid);
    std::vector<std::string> withLight = cloudOverrides(m, sppFor(m), 5);
    withLight[3] = str("lights=[{\"type\": \"directional\", \"direction\": [", -toLight.x, ", ", -toLight.y, ", ",
                       -toLight.z, "], \"irradiance\": [", E, ", ", E, ", ", E, "]}]");
    std::vector<std::string> withMap = cloudOverrides(m, sppFor(m), 6);
    withMap.push_back(str("environment={\"file\": \"", dir / "patch.exr", "\"}"));
    const Image a = render(withLight), b = render(withMap);
    const Difference r = difference(a, b, m, "patch vs directional");
    EXPECT_GT(r.mean.mean(), 0.02);  // the patch lights the cloud
    EXPECT_NEAR(r.d.mean(), 0.0, 4 * r.d.stdError() + 0.01 * r.mean.mean()) << methodName(m);
}

INSTANTIATE_TEST_SUITE_P(Methods, EnvironmentLight, ::testing::ValuesIn(estimatorMethods()), methodParamName);

}  // namespace
}  // namespace vdbmarch
