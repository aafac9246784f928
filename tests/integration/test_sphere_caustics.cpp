// Sphere caustic connections in the path tracer (strategies/sphere_caustics.h):
// renders with experiments.sphere_caustics on must agree with renders where the
// paths alone find the light through the glass (off), region by region
// within 4 standard errors of the paired difference: the paper's caustic
// scene (fog and a diffuse floor under a glass ball, a sphere light above),
// a heterogeneous VDB cloud with glass, lights and an environment map, and a
// glass ball with a diffuse sphere inside it (connections are then tested
// for what lies inside), and for the guided marcher, whose L_i samples
// connect too. And the connections must actually carry the
// caustic: less noise per sample on the caustic scene.
//
// Point and spot lights (Scene::deltaLightCaustics): their connections are
// the limit of a sphere light shrunk to a point, so a point light must
// agree with a small sphere light of its intensity (whose connections the
// tests above check against the paths), a spot whose cone holds the ball
// must add the point light's caustic, and the guided marcher, which then
// takes no caustic photons, must agree with the path tracer.
//
// A globe of milk (the ball holding a medium): lights inside it reached
// across its surface once from outside, lights over it reached from the
// milk across the surface and through the milk from the fog; the same
// agreements. The sun (directional and collimated lights): a collimated beam
// holding the ball adds what the sun adds, and what the connections add
// matches what the guided marcher's caustic photons add.
#include <gtest/gtest.h>

#include <cmath>

#include "illumination/illumination.h"
#include "photons/photon_tracer.h"
#include "strategies/sphere_caustics.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

// Off: the paths alone find sphere lights through the glass (not the
// caustic photons that would otherwise take over, experiments.caustic_photons).
Image renderWithCaustics(const std::string& sample, std::vector<std::string> overrides, bool caustics, int seed = 3) {
    overrides.push_back("experiments.caustic_photons=false");
    return renderSampleToggled(sample, overrides, "experiments.sphere_caustics", caustics, seed);
}

// The path tracer without the connections and without the caustic photons
// that then take their place in media: the light paths find alone.
Image pathsAlone(const std::string& sample, std::vector<std::string> overrides, int seed = 3) {
    overrides.push_back("photons.count=0");
    return renderWithCaustics(sample, overrides, false, seed);
}

const std::vector<std::string> CausticScene = {"camera.resolution=[32,24]", "render.method=\"reference\"",
                                               "render.max_depth=4", "render.spp=768"};

// A sphere light over the ball that paths through it find often.
const char* const LargeLight =
    R"(lights=[{"type": "sphere", "position": [0, 2.2, 0], "radius": 0.5, "power": [300, 290, 270]}])";

TEST(SphereCausticRenders, FogAndFloorUnderAGlassBallAgreeWithPathsAlone) {
    const Image on = renderWithCaustics("scenes/fig4_caustic_sphere.json", CausticScene, true);
    const Image off = renderWithCaustics("scenes/fig4_caustic_sphere.json", CausticScene, false);
    expectPairedAgreement(off, on, "fig4_caustic_sphere");
}

TEST(SphereCausticRenders, ALargeLightThatPathsFindOftenAgreesWithPathsAlone) {
    // A light the paths find often through the ball: every technique's
    // share counts (connections, directions towards the ball, the paths).
    std::vector<std::string> o = CausticScene;
    o.push_back(LargeLight);
    const Image on = renderWithCaustics("scenes/fig4_caustic_sphere.json", o, true);
    const Image off = renderWithCaustics("scenes/fig4_caustic_sphere.json", o, false);
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
    const Image on = renderWithCaustics("scenes/fig4_caustic_sphere.json", o, true);
    const Image off = renderWithCaustics("scenes/fig4_caustic_sphere.json", o, false);
    expectPairedAgreement(off, on, "guided on fig4_caustic_sphere");
}

TEST(SphereCausticRenders, ConnectionsQuietTheCaustic) {
    // Pair RMSE of two seeds, with and without: the connections must take
    // the noise per sample well below the paths' (measured 0.13x the MSE at
    // 160x120; here at least 2x less).
    auto noise = [](bool caustics) {
        return test::pairMse(renderWithCaustics("scenes/fig4_caustic_sphere.json", CausticScene, caustics, 11),
                             renderWithCaustics("scenes/fig4_caustic_sphere.json", CausticScene, caustics, 23));
    };
    EXPECT_LT(noise(true), 0.5 * noise(false));
}

// The scene's sphere light alone: with connections off, no path could find
// the caustics of its point and spot lights.
const char* const CloudSkySphereLight =
    R"(lights=[{"type": "sphere", "position": [0.6, 0.7, -0.4], "radius": 0.05, "power": 8}])";

TEST(SphereCausticRenders, CloudWithGlassLightsAndSkyAgreesWithPathsAlone) {
    std::vector<std::string> o = cloudSkyWithLightsAndGlass();
    o.insert(o.end(), {"render.method=\"reference\"", "render.spp=256", CloudSkySphereLight});
    expectPairedAgreement(renderWithCaustics("cloud_sky.json", o, false), renderWithCaustics("cloud_sky.json", o, true), "cloud_sky");
}

// A sphere light of radius r and power 4 pi I has the far-field intensity I
// of a point light; at r = 0.01, 1.85 from the ball, the two differ by
// (r / d)^2 ~ 3e-5 relative, far below the tests' errors.
std::string pointLightJson(const char* position, const char* intensity) {
    return std::string(R"({"type": "point", "position": )") + position + R"(, "intensity": )" + intensity + "}";
}
std::string smallSphereLight(const char* position, double intensity) {
    return std::string(R"({"type": "sphere", "radius": 0.01, "position": )") + position +
           R"(, "power": )" + std::to_string(4 * 3.14159265358979 * intensity) + "}";
}

TEST(SphereCausticRenders, APointLightAgreesWithASmallSphereLightOfItsIntensity) {
    std::vector<std::string> point = CausticScene, sphere = CausticScene;
    point.push_back("lights=[" + pointLightJson("[0, 2.6, 0]", "23") + "]");
    sphere.push_back("lights=[" + smallSphereLight("[0, 2.6, 0]", 23) + "]");
    expectPairedAgreement(renderWithCaustics("scenes/fig4_caustic.json", sphere, true),
                          renderWithCaustics("scenes/fig4_caustic.json", point, true), "point light over the ball");
    // And the connections carry light the paths cannot find: without
    // them the image is darker by far more than its noise.
    const Image on = renderWithCaustics("scenes/fig4_caustic.json", point, true);
    const Image off = pathsAlone("scenes/fig4_caustic.json", point);
    SampleStats diff;
    for (int y = 0; y < on.height; ++y)
        for (int x = 0; x < on.width; ++x) diff.add(average(on.rgb(x, y)) - average(off.rgb(x, y)));
    EXPECT_GT(diff.mean(), 10 * diff.stdError());
    // The floor's caustic alone (the fog only absorbs): both estimates are
    // nearly deterministic there, so this comparison is sharp (a missing
    // Fresnel factor, 8 % of the caustic, fails it).
    for (auto* o : {&point, &sphere}) o->insert(o->end(), {"media.0.sigma_s=0", "render.max_depth=1"});
    expectPairedAgreement(renderWithCaustics("scenes/fig4_caustic.json", sphere, true),
                          renderWithCaustics("scenes/fig4_caustic.json", point, true), "the floor's caustic");
}

TEST(SphereCausticRenders, APointLightInACloudAgreesWithASmallSphereLight) {
    // The heterogeneous VDB cloud under the sky, the glass ball beside it.
    const char* const at = "[-0.2, 0.75, 1.5]";
    std::vector<std::string> point = cloudSkyWithLightsAndGlass(), sphere = point;
    for (auto* o : {&point, &sphere}) o->insert(o->end(), {"render.method=\"reference\"", "render.spp=256"});
    point.push_back("lights=[" + pointLightJson(at, "0.6") + "]");
    sphere.push_back("lights=[" + smallSphereLight(at, 0.6) + "]");
    expectPairedAgreement(renderWithCaustics("cloud_sky.json", sphere, true), renderWithCaustics("cloud_sky.json", point, true),
                          "point light in cloud_sky");
}

TEST(SphereCausticRenders, ASpotWhoseConeHoldsTheBallAddsThePointLightsCaustic) {
    // What the connections add (on - off) depends only on the intensity
    // towards the ball, which this spot shares with the point light (the
    // ball subtends 14 degrees from the light; full intensity to 20).
    std::vector<std::string> point = CausticScene, spot = CausticScene;
    point.push_back("lights=[" + pointLightJson("[0, 2.6, 0]", "23") + "]");
    spot.push_back(R"(lights=[{"type": "spot", "position": [0, 2.6, 0], "direction": [0, -1, 0], "cone_deg": 25,
                              "falloff_deg": 5, "intensity": 23}])");
    auto added = [](const std::vector<std::string>& o) {
        Image on = renderWithCaustics("scenes/fig4_caustic.json", o, true);
        const Image off = pathsAlone("scenes/fig4_caustic.json", o);
        for (size_t i = 0; i < on.rgba.size(); ++i) on.rgba[i] -= off.rgba[i];
        return on;
    };
    expectPairedAgreement(added(point), added(spot), "a spot's caustic");
}

TEST(SphereCausticRenders, GuidedMarcherConnectsToPointLightsLikeThePathTracer) {
    // Single scattering, so the marcher traces no photon at all (the
    // connections carry the caustic) and both estimators are unbiased.
    std::vector<std::string> o = CausticScene;
    o[2] = "render.max_depth=1";
    std::vector<std::string> guided = o;
    guided[1] = "render.method=\"guided\"";
    guided.back() = "render.spp=128";
    const auto scene = buildScene(loadSceneFile(samplePath("scenes/fig4_caustic.json"), guided));
    EXPECT_TRUE(scene->deltaLightCaustics);
    EXPECT_FALSE(illuminationRequest(*scene, Method::Guided, {}).indirect);
    expectPairedAgreement(renderWithCaustics("scenes/fig4_caustic.json", o, true),
                          renderWithCaustics("scenes/fig4_caustic.json", guided, true), "guided on fig4_caustic");
    // A sphere light: max_depth ends the marcher's path at the floor, so
    // the floor's connections carry all of its caustic there (no path hit
    // to weigh against).
    // The large light over the ball, whose caustic lights much of the floor.
    for (auto* v : {&o, &guided}) v->push_back(LargeLight);
    expectPairedAgreement(renderWithCaustics("scenes/fig4_caustic.json", o, true),
                          renderWithCaustics("scenes/fig4_caustic.json", guided, true), "guided, a sphere light");
}

TEST(SphereCaustics, ThePathTracerWarnsWhereItMissesCaustics) {
    auto warnings = [](const std::vector<std::string>& extra) {
        std::vector<std::string> o = {"render.method=\"reference\""};
        o.insert(o.end(), extra.begin(), extra.end());
        const int before = warningCount();
        buildScene(loadSceneFile(samplePath("scenes/fig4_caustic.json"), o));
        return warningCount() - before;
    };
    EXPECT_EQ(warnings({}), 0);  // the point light's caustics are connected
    EXPECT_EQ(warnings({"experiments.sphere_caustics=false"}), 1);
    EXPECT_NE(lastWarning().find("experiments.sphere_caustics"), std::string::npos) << lastWarning();
    EXPECT_EQ(warnings({R"(surfaces.0.transform={"scale": [0.45, 0.3, 0.45], "translate": [0, 0.75, 0]})"}), 1);
}

TEST(SphereCaustics, DeltaLightCausticsOnlyWhereConnectionsFindThemAll) {
    auto flag = [](const std::vector<std::string>& o) {
        return buildScene(loadSceneFile(samplePath("scenes/fig4_caustic.json"), o))->deltaLightCaustics;
    };
    EXPECT_TRUE(flag({}));
    EXPECT_FALSE(flag({"experiments.sphere_caustics=false"}));
    // Directional lights connect along their direction; a collimated quad
    // must lie outside the ball.
    EXPECT_TRUE(flag({R"(lights=[{"type": "point", "position": [0, 2.6, 0], "intensity": 1},
                                 {"type": "directional", "direction": [0, -1, 0], "irradiance": 1}])"}));
    EXPECT_TRUE(flag({R"(lights=[{"type": "collimated_quad", "center": [0, 2.6, 0], "u": [1, 0, 0],
                                  "v": [0, 0, 1], "direction": [0, -1, 0]}])"}));
    EXPECT_FALSE(flag({R"(lights=[{"type": "collimated_quad", "center": [0, 1.0, 0], "u": [1, 0, 0],
                                   "v": [0, 0, 1], "direction": [0, -1, 0]}])"}));
    // A light inside the ball is connected across its surface; one on the
    // surface is not (no root of the solver there).
    EXPECT_TRUE(flag({R"(lights=[{"type": "point", "position": [0, 0.8, 0], "intensity": 1}])"}));
    EXPECT_FALSE(flag({R"(lights=[{"type": "point", "position": [0, 1.2, 0], "intensity": 1}])"}));
    // Glass that is not a sphere.
    EXPECT_FALSE(flag({R"(surfaces.0.transform={"scale": [0.45, 0.3, 0.45], "translate": [0, 0.75, 0]})"}));
    // No delta light: nothing to connect (sphere lights connect anyway).
    EXPECT_FALSE(flag({R"(lights=[{"type": "sphere", "position": [0, 2.6, 0], "radius": 0.1, "power": 1}])"}));
}

TEST(SphereCausticRenders, SomethingInsideTheBallIsSeenByTheConnections) {
    // A diffuse ball inside the glass ball: connections through the glass
    // must find it in the way (their shadow ray through the ball meets it).
    std::vector<std::string> o = CausticScene;
    o.push_back(R"(surfaces=[{"shape": "sphere", "transform": {"scale": 0.45, "translate": [0, 0.75, 0]},
                              "material": {"type": "dielectric", "ior": 1.5}},
                             {"shape": "sphere", "transform": {"scale": 0.2, "translate": [0.05, 0.8, 0]},
                              "material": {"type": "diffuse", "albedo": 0.3}},
                             {"shape": "box", "transform": {"scale": [6, 0.1, 6], "translate": [0, -0.85, 0]},
                              "material": {"type": "diffuse", "albedo": 0.5}}])");
    const Image on = renderWithCaustics("scenes/fig4_caustic_sphere.json", o, true);
    const Image off = renderWithCaustics("scenes/fig4_caustic_sphere.json", o, false);
    expectPairedAgreement(off, on, "a ball inside the glass ball");
}

// The caustic scenes' fog, and milk inside the ball.
const char* const GlobeOfMilk =
    R"(media=[{"name": "fog", "type": "homogeneous", "sigma_a": 0.03, "sigma_s": 0.6, "g": 0.0,
               "bounds": {"min": [-1.6, -0.8, -1.2], "max": [1.6, 0.25, 1.2]}},
              {"name": "milk", "type": "homogeneous", "sigma_a": 0.2, "sigma_s": 1.5, "g": 0.5,
               "bounds": {"min": [-0.5, 0.25, -0.5], "max": [0.5, 1.25, 0.5]}}])";

std::vector<std::string> globeOfMilk(const char* lights) {
    std::vector<std::string> o = CausticScene;
    o.insert(o.end(), {GlobeOfMilk, R"(surfaces.0.interior="milk")", lights});
    return o;
}

// A sphere light in the milk, off the ball's centre.
const char* const LightInTheMilk =
    R"(lights=[{"type": "sphere", "position": [0.08, 0.8, 0.05], "radius": 0.08, "power": [60, 55, 50]}])";

TEST(SphereCausticRenders, ALightInAGlobeOfMilkAgreesWithPathsAlone) {
    // The fog and the floor see it across the surface once, through the milk.
    const auto o = globeOfMilk(LightInTheMilk);
    expectPairedAgreement(renderWithCaustics("scenes/fig4_caustic_sphere.json", o, false),
                          renderWithCaustics("scenes/fig4_caustic_sphere.json", o, true), "a light in a globe of milk");
}

TEST(SphereCausticRenders, ALightOverAGlobeOfMilkAgreesWithPathsAlone) {
    // The milk sees it across the surface once; the fog and the floor
    // through the ball and its milk.
    const auto o = globeOfMilk(LargeLight);
    expectPairedAgreement(renderWithCaustics("scenes/fig4_caustic_sphere.json", o, false),
                          renderWithCaustics("scenes/fig4_caustic_sphere.json", o, true), "a light over a globe of milk");
}

TEST(SphereCausticRenders, PointLightsInAndOverAGlobeOfMilkAgreeWithSmallSphereLights) {
    for (const char* at : {"[0.08, 0.8, 0.05]", "[0, 2.6, 0]", "[0, 0.75, 0]"}) {
        const std::string point = "lights=[" + pointLightJson(at, "5") + "]";
        const std::string sphere = "lights=[" + smallSphereLight(at, 5) + "]";
        expectPairedAgreement(renderWithCaustics("scenes/fig4_caustic.json", globeOfMilk(sphere.c_str()), true),
                              renderWithCaustics("scenes/fig4_caustic.json", globeOfMilk(point.c_str()), true),
                              std::string("a point light at ") + at + " and a globe of milk");
    }
}

TEST(SphereCausticRenders, GuidedMarcherConnectsThroughAGlobeOfMilkLikeThePathTracer) {
    // Single scattering: no photons, the connections carry all the light
    // of the point light over the ball to the milk and below it.
    const std::string point = "lights=[" + pointLightJson("[0, 2.6, 0]", "23") + "]";
    std::vector<std::string> o = globeOfMilk(point.c_str());
    o[2] = "render.max_depth=1";
    std::vector<std::string> guided = o;
    guided[1] = "render.method=\"guided\"";
    guided[3] = "render.spp=128";
    const auto scene = buildScene(loadSceneFile(samplePath("scenes/fig4_caustic.json"), guided));
    EXPECT_TRUE(scene->deltaLightCaustics);
    EXPECT_FALSE(illuminationRequest(*scene, Method::Guided, {}).indirect);
    expectPairedAgreement(renderWithCaustics("scenes/fig4_caustic.json", o, true),
                          renderWithCaustics("scenes/fig4_caustic.json", guided, true), "guided, a globe of milk");
}

TEST(SphereCaustics, ConnectedPhotonsInAndBelowAGlobeOfMilkCameAcrossOrThroughIt) {
    // Photon::Connected in the milk: straight from the light across the
    // ball's surface; below it: straight through the ball and its milk.
    const std::string point = "lights=[" + pointLightJson("[0, 2.6, 0]", "23") + "]";
    const auto scene = buildScene(loadSceneFile(samplePath("scenes/fig4_caustic.json"), globeOfMilk(point.c_str())));
    ASSERT_TRUE(scene->deltaLightCaustics);
    const GlassSphere& ball = scene->glassSpheres.at(0);
    const Vec3 light = scene->lights.at(0).desc().position;
    size_t inside = 0, outside = 0, milk = 0;
    for (const Photon& p : tracePhotons(*scene, 400000, 5).photons) {
        const bool in = length(p.position - ball.center) < ball.radius;
        milk += in;
        if (!p.isConnected()) continue;
        (in ? inside : outside) += 1;
        SphereConnection tr;
        const Vec3 back = -p.travelDirection();
        ASSERT_TRUE(in ? traceAcrossSphere(ball, p.position, back, tr) : traceThroughSphere(ball, p.position, back, tr));
        const Vec3 v = light - tr.p2;
        EXPECT_GT(dot(v, tr.wo), 0.f);
        // Within the 32-bit direction's precision, which refraction near
        // grazing angles magnifies (a photon that scattered first would
        // miss the light by far more).
        EXPECT_LT(length(v - tr.wo * dot(v, tr.wo)), 1e-2f * length(v))
            << "photon at " << p.position.x << " " << p.position.y << " " << p.position.z << (in ? " (in)" : "");
    }
    EXPECT_GT(inside, 100u);
    EXPECT_GT(outside, 100u);
    EXPECT_LT(inside, milk);  // what scattered in the milk first is not connected
}

// The sun through the ball, slanted so that its caustic lands on the floor.
const char* const Sun = R"({"type": "directional", "direction": [0.25, -1, 0.1], "irradiance": [3, 2.9, 2.7]})";

TEST(SphereCausticRenders, ACollimatedBeamHoldingTheBallAddsTheSunsCaustic) {
    // What the connections add (on - off) depends only on the irradiance
    // along the beam, which the quad shares with the directional light
    // where its beam holds the ball.
    std::vector<std::string> sun = CausticScene, quad = CausticScene;
    sun.push_back(std::string("lights=[") + Sun + "]");
    quad.push_back(R"(lights=[{"type": "collimated_quad", "center": [-0.6, 3.1, -0.24], "u": [1.4, 0.35, 0],
                               "v": [0, 0.14, 1.4], "direction": [0.25, -1, 0.1], "irradiance": [3, 2.9, 2.7]}])");
    auto added = [](const std::vector<std::string>& o) {
        Image on = renderWithCaustics("scenes/fig4_caustic.json", o, true);
        const Image off = pathsAlone("scenes/fig4_caustic.json", o);
        for (size_t i = 0; i < on.rgba.size(); ++i) on.rgba[i] -= off.rgba[i];
        return on;
    };
    const Image fromSun = added(sun), fromQuad = added(quad);
    expectPairedAgreement(fromSun, fromQuad, "a collimated beam's caustic");
    // And the caustic is there: the sun's connections add far more than
    // their noise.
    SampleStats diff;
    for (int y = 0; y < fromSun.height; ++y)
        for (int x = 0; x < fromSun.width; ++x) diff.add(average(fromSun.rgb(x, y)));
    EXPECT_GT(diff.mean(), 10 * diff.stdError());
}

TEST(SphereCausticRenders, TheSunsCausticAgreesWithThePhotonsOfTheMarcher) {
    // Single scattering in fog under the ball and in a globe of milk: the
    // light the connections add to the path tracer (on - off) against what
    // the guided marcher's caustic photons add (experiments.sphere_caustics off;
    // both take the rest from shadow rays), in the image's mean: photons
    // blur the caustic but keep its light. Within 6 % of it: the blur
    // across the image's edges and the noise of both (measured: 1.7 %).
    std::vector<std::string> o = globeOfMilk((std::string("lights=[") + Sun + "]").c_str());
    o[2] = "render.max_depth=1";
    std::vector<std::string> marcher = o;
    marcher[1] = "render.method=\"guided\"";
    marcher[3] = "render.spp=64";
    marcher.insert(marcher.end(), {"photons.count=2000000", "photons.k=20"});
    auto mean = [](const Image& img) {
        SampleStats m;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) m.add(average(img.rgb(x, y)));
        return m.mean();
    };
    const double off = mean(pathsAlone("scenes/fig4_caustic.json", o));
    const double byConnections = mean(renderWithCaustics("scenes/fig4_caustic.json", o, true)) - off;
    const double byPhotons = mean(renderWithCaustics("scenes/fig4_caustic.json", marcher, false)) - off;
    EXPECT_GT(byPhotons, 0.03 * off);  // the caustic is a visible part of the image
    EXPECT_NEAR(byConnections, byPhotons, 0.06 * byPhotons)
        << "connections add " << byConnections << ", photons " << byPhotons << " to " << off;
}

}  // namespace
}  // namespace vdbmarch
