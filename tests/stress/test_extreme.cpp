// Numerical stability under extreme inputs: every pixel stays finite, no path
// sample is dropped as NaN/Inf, and limits behave as physics says.
#include <gtest/gtest.h>

#include <cmath>

#include "../integration/test_helpers.h"

namespace vdbmarch::testing {
namespace {

void expectAllFinite(const RenderResult& r) {
    for (float v : r.image.rgba) ASSERT_TRUE(std::isfinite(v));
    EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
}

std::string boxScene(const std::string& vdb, const std::string& mediumExtra, const std::string& lightExtra = "1") {
    return R"({"camera": {"type": "perspective", "position": [0.5, 0.6, 2.5], "look_at": [0.475, 0.475, 0.475],
               "fov_deg": 40, "resolution": [16, 16]},
               "lights": [{"type": "point", "position": [2, 2, 2], "intensity": )" + lightExtra + R"(},
                          {"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": )" + lightExtra + R"(}],
               "media": [{"type": "vdb", "file": ")" + vdb + R"(", )" + mediumExtra + R"(}],
               "background": [0.1, 0.2, 0.3], "render": {"spp": 2, "seed": 9}})";
}

TEST(Stress, HugeCoefficientsGiveAnOpaqueFiniteImage) {
    std::string vdb = tempDir() + "/stress_box.vdb";
    writeBoxGrid(vdb, openvdb::Coord(0), openvdb::Coord(19), 1.f, 0.05);
    auto scene = sceneFromJson(boxScene(vdb, R"("density_scale": 1e30, "sigma_a": 1e30, "sigma_s": 1e30, "g": 0.99)"));
    RenderResult r = renderImage(*scene);
    expectAllFinite(r);
    EXPECT_FLOAT_EQ(r.image.alpha(8, 8), 1.f);  // the centre pixel sees the box
}

TEST(Stress, TinyCoefficientsShowTheBackground) {
    std::string vdb = tempDir() + "/stress_box.vdb";
    writeBoxGrid(vdb, openvdb::Coord(0), openvdb::Coord(19), 1.f, 0.05);
    auto scene = sceneFromJson(boxScene(vdb, R"("density_scale": 1e-30, "sigma_a": 1e-30, "sigma_s": 1e-30)"));
    RenderResult r = renderImage(*scene);
    expectAllFinite(r);
    Color c = r.image.rgb(8, 8);
    EXPECT_NEAR(c.x, 0.1, 1e-6);
    EXPECT_NEAR(c.z, 0.3, 1e-6);
}

TEST(Stress, HugeLightAndStrongAnisotropyStayFinite) {
    std::string vdb = tempDir() + "/stress_box.vdb";
    writeBoxGrid(vdb, openvdb::Coord(0), openvdb::Coord(19), 1.f, 0.05);
    auto scene = sceneFromJson(boxScene(vdb, R"("sigma_s": 40, "g": -0.999)", "1e30"));
    expectAllFinite(renderImage(*scene));
}

TEST(Stress, FarCameraAndAxisAlignedRaysStayFinite) {
    std::string vdb = tempDir() + "/stress_box.vdb";
    writeBoxGrid(vdb, openvdb::Coord(0), openvdb::Coord(19), 1.f, 0.05);
    // Orthographic rays exactly along -z: two direction components are zero.
    auto scene = sceneFromJson(R"({"camera": {"type": "orthographic", "position": [0.475, 0.475, 1e6],
        "look_at": [0.475, 0.475, 0], "width_world": 2, "resolution": [16, 16]},
        "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1}],
        "media": [{"type": "vdb", "file": ")" + vdb + R"(", "sigma_s": 10}]})");
    RenderResult r = renderImage(*scene);
    expectAllFinite(r);
    EXPECT_GT(r.image.alpha(8, 8), 0.9f);
}

TEST(Stress, StepMuchLargerThanTheMediumStaysFinite) {
    std::string vdb = tempDir() + "/stress_box.vdb";
    writeBoxGrid(vdb, openvdb::Coord(0), openvdb::Coord(19), 1.f, 0.05);
    auto scene = sceneFromJson(boxScene(vdb, R"("sigma_s": 5)") );
    SceneDesc d = scene->desc;
    d.render.step = 1000.f;
    expectAllFinite(renderImage(*buildScene(d)));
}

TEST(Stress, UnboundedFogWithDirectionalLightAndBackground) {
    // Infinite optical depth towards infinity: directional light and sky are
    // fully extinguished, point lights still reach; nothing becomes NaN.
    auto scene = sceneFromJson(R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [8, 8]},
        "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": 5},
                   {"type": "point", "position": [0, 1, 0], "intensity": 1}],
        "media": [{"type": "homogeneous", "sigma_a": [0.1, 0, 0.1], "sigma_s": [0.5, 0, 0.2]}],
        "background": [1, 1, 1], "render": {"step": 0.05}})");
    RenderResult r = renderImage(*scene);
    expectAllFinite(r);
    // The green channel has no extinction: the background shows through it.
    EXPECT_NEAR(r.image.rgb(4, 4).y, 1.0, 1e-5);
}

}  // namespace
}  // namespace vdbmarch::testing
