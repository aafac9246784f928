// render.method = "auto": the default, resolved from the scene description
// by the documented rule (docs/method.md, "The automatic method"); an
// explicit method always wins; --preview renders the documented quick look.
#include <gtest/gtest.h>

#include "image/exr_io.h"
#include "parse/scene_desc.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

SceneDesc parse(const std::string& json) { return parseSceneText(json, "scene.json"); }

const char* const kSun = R"({"type": "directional", "direction": [0, -1, 0], "irradiance": 1})";
const char* const kSphereLight = R"({"type": "sphere", "position": [0, 2, 0], "radius": 0.2, "power": 10})";
const char* const kFog = R"({"name": "fog", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 1,
                              "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}})";

std::string scene(const std::string& lights, const std::string& surfaces, const std::string& render) {
    return str(R"({"lights": [)", lights, R"(], "media": [)", kFog, R"(], "surfaces": [)", surfaces,
               R"(], "render": )", render, "}");
}

TEST(AutoMethod, IsTheDefaultAndFollowsTheRule) {
    // Multiple scattering in open media: the path tracer.
    SceneDesc d = parse(scene(kSun, "", R"({"max_depth": 8})"));
    EXPECT_TRUE(d.render.methodAuto);
    EXPECT_EQ(d.render.method, Method::Reference);
    EXPECT_NE(d.render.methodReason.find("multiple scattering"), std::string::npos);
    // Single scattering: guided.
    d = parse(scene(kSun, "", "{}"));
    EXPECT_EQ(d.render.method, Method::Guided);
    // A delta light and refracting glass (photons carry its caustics): guided.
    const std::string glass = R"({"shape": "sphere", "material": {"type": "dielectric", "ior": 1.5}})";
    d = parse(scene(kSun, glass, R"({"max_depth": 8})"));
    EXPECT_EQ(d.render.method, Method::Guided);
    // The same glass under a sphere light: the path tracer finds it.
    d = parse(scene(kSphereLight, glass, R"({"max_depth": 8})"));
    EXPECT_EQ(d.render.method, Method::Reference);
    // Media inside glass: guided.
    const std::string filled = R"({"shape": "sphere", "interior": "fog", "material": {"type": "dielectric", "ior": 1.33}})";
    d = parse(scene(kSphereLight, filled, R"({"max_depth": 8})"));
    EXPECT_EQ(d.render.method, Method::Guided);
    // Index-matched glass bends nothing: not a reason for photons.
    const std::string matched = R"({"shape": "sphere", "material": {"type": "dielectric", "ior": 1.0}})";
    d = parse(scene(kSun, matched, R"({"max_depth": 8})"));
    EXPECT_EQ(d.render.method, Method::Reference);
}

TEST(AutoMethod, AnExplicitMethodWins) {
    for (Method m : allMethods()) {
        SceneDesc d = parse(scene(kSun, "", str(R"({"max_depth": 8, "method": ")", methodName(m), R"("})")));
        EXPECT_FALSE(d.render.methodAuto);
        EXPECT_EQ(d.render.method, m);
    }
    SceneDesc d = parseSceneText(scene(kSun, "", R"({"method": "uniform"})"), "scene.json", {"render.method=\"auto\""});
    EXPECT_TRUE(d.render.methodAuto);
    EXPECT_EQ(d.render.method, Method::Guided);
}

TEST_F(BadInput, AutoIsListedAmongTheMethodsInErrors) {
    scene("s.json", homogeneousScene());
    const CliResult r = cli({"render", "s.json", "-o", "out.exr", "--method", "automatic"});
    expectCliError(r, {"render.method", "automatic", "auto"});
}

// --preview: half the width and height and an eighth of the samples; the
// output records them.
TEST_F(BadInput, PreviewRendersTheDocumentedQuickLookCli) {
    scene("s.json", homogeneousScene());
    CliResult r = cli({"render", "s.json", "-o", "full.exr", "--res", "64x48", "--spp", "16"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    r = cli({"render", "s.json", "-o", "preview.exr", "--res", "64x48", "--spp", "16", "--preview"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const Image full = readExr(work("full.exr")), preview = readExr(work("preview.exr"));
    EXPECT_EQ(full.width, 64);
    EXPECT_EQ(preview.width, 32);
    EXPECT_EQ(preview.height, 24);
    std::string spp;
    for (const auto& [k, v] : readExrStringAttributes(work("preview.exr")))
        if (k == "vdbmarch:spp") spp = v;
    EXPECT_EQ(spp, "2");
}

}  // namespace
}  // namespace vdbmarch
