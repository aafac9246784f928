// Sphere caustic connections in the path tracer (transport/sphere_caustics.h):
// renders with render.sphere_caustics on must agree with renders where the
// paths alone find the light through the glass (off), region by region
// within 4 standard errors of the paired difference: the paper's caustic
// scene (fog and a diffuse floor under a glass ball, a sphere light above),
// a heterogeneous VDB cloud with glass, lights and an environment map, and a
// glass ball with a diffuse sphere inside it (connections are then tested
// for what lies inside), and for the guided marcher, whose L_i samples
// connect too. And the connections must actually carry the
// caustic: less noise per sample on the caustic scene.
#include <gtest/gtest.h>

#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

Image renderWith(const std::string& sample, const std::vector<std::string>& overrides, bool caustics, int seed = 3) {
    return renderSampleToggled(sample, overrides, "render.sphere_caustics", caustics, seed);
}

const std::vector<std::string> CausticScene = {"camera.resolution=[32,24]", "render.method=\"reference\"",
                                               "render.max_depth=4", "render.spp=768"};

// A sphere light over the ball that paths through it find often.
const char* const LargeLight =
    R"(lights=[{"type": "sphere", "position": [0, 2.2, 0], "radius": 0.5, "power": [300, 290, 270]}])";

TEST(SphereCausticRenders, FogAndFloorUnderAGlassBallAgreeWithPathsAlone) {
    const Image on = renderWith("scenes/fig4_caustic_sphere.json", CausticScene, true);
    const Image off = renderWith("scenes/fig4_caustic_sphere.json", CausticScene, false);
    expectPairedAgreement(off, on, "fig4_caustic_sphere");
}

TEST(SphereCausticRenders, ALargeLightThatPathsFindOftenAgreesWithPathsAlone) {
    // A light the paths find often through the ball: every technique's
    // share counts (connections, directions towards the ball, the paths).
    std::vector<std::string> o = CausticScene;
    o.push_back(LargeLight);
    const Image on = renderWith("scenes/fig4_caustic_sphere.json", o, true);
    const Image off = renderWith("scenes/fig4_caustic_sphere.json", o, false);
    expectPairedAgreement(off, on, "a large light over the ball");
}

TEST(SphereCausticRenders, GuidedMarcherAgreesWithItsPathsAlone) {
    // The marcher's L_i samples connect too (li = "path"), and its
    // continuation paths weigh their hits against that.
    // The large light: paths find it often, so the comparison is sharp.
    std::vector<std::string> o = CausticScene;
    o.back() = "render.spp=128";
    o[1] = "render.method=\"guided\"";
    o.push_back(LargeLight);
    const Image on = renderWith("scenes/fig4_caustic_sphere.json", o, true);
    const Image off = renderWith("scenes/fig4_caustic_sphere.json", o, false);
    expectPairedAgreement(off, on, "guided on fig4_caustic_sphere");
}

TEST(SphereCausticRenders, ConnectionsQuietTheCaustic) {
    // Pair RMSE of two seeds, with and without: the connections must take
    // the noise per sample well below the paths' (measured 0.13x the MSE at
    // 160x120; here at least 2x less).
    auto noise = [](bool caustics) {
        return test::pairMse(renderWith("scenes/fig4_caustic_sphere.json", CausticScene, caustics, 11),
                             renderWith("scenes/fig4_caustic_sphere.json", CausticScene, caustics, 23));
    };
    EXPECT_LT(noise(true), 0.5 * noise(false));
}

TEST(SphereCausticRenders, CloudWithGlassLightsAndSkyAgreesWithPathsAlone) {
    std::vector<std::string> o = cloudSkyWithLightsAndGlass();
    o.insert(o.end(), {"render.method=\"reference\"", "render.spp=256"});
    expectPairedAgreement(renderWith("cloud_sky.json", o, false), renderWith("cloud_sky.json", o, true), "cloud_sky");
}

TEST(SphereCausticRenders, SomethingInsideTheBallIsSeenByTheConnections) {
    // A diffuse ball inside the glass ball: connections through the glass
    // must find it in the way (GlassSphere::clearInside false).
    std::vector<std::string> o = CausticScene;
    o.push_back(R"(surfaces=[{"shape": "sphere", "transform": {"scale": 0.45, "translate": [0, 0.75, 0]},
                              "material": {"type": "dielectric", "ior": 1.5}},
                             {"shape": "sphere", "transform": {"scale": 0.2, "translate": [0.05, 0.8, 0]},
                              "material": {"type": "diffuse", "albedo": 0.3}},
                             {"shape": "box", "transform": {"scale": [6, 0.1, 6], "translate": [0, -0.85, 0]},
                              "material": {"type": "diffuse", "albedo": 0.5}}])");
    const Image on = renderWith("scenes/fig4_caustic_sphere.json", o, true);
    const Image off = renderWith("scenes/fig4_caustic_sphere.json", o, false);
    expectPairedAgreement(off, on, "a ball inside the glass ball");
}

}  // namespace
}  // namespace vdbmarch
