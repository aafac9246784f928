// Surfaces and regions: a medium inside an interface sphere exists only there,
// world fog only outside; smooth glass neither loses nor creates energy.
#include <gtest/gtest.h>

#include <cmath>

#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

// Orthographic rays along -z through a world fog box [-2,2]^3 (sigma_w) that
// holds a unit sphere (interface) filled with sigma_i: the transmittance of a
// ray at distance rho from the axis is exp(-sigma_w (4 - c) - sigma_i c) with
// chord c = 2 sqrt(1 - rho^2). The marcher counts whole steps, so each medium's
// depth is off by at most one step: tolerance 2 (sigma_w + sigma_i) dx.
TEST(Regions, InteriorMediumOnlyInsideWorldFogOnlyOutside) {
    const double sw = 0.3, si = 2.0, dx = 1e-3;
    auto scene = sceneFromJson(str(R"({"camera": {"type": "orthographic", "position": [0, 0, 5], "look_at": [0, 0, 0],
        "width_world": 3, "resolution": [24, 24]},
        "media": [{"name": "fog", "type": "homogeneous", "sigma_a": )", sw, R"(, "sigma_s": 0,
                   "bounds": {"min": [-2, -2, -2], "max": [2, 2, 2]}},
                  {"name": "ink", "type": "homogeneous", "sigma_a": )", si, R"(, "sigma_s": 0}],
        "surfaces": [{"shape": "sphere", "material": {"type": "interface"}, "interior": "ink"}],
        "render": {"step": )", dx, R"(, "pixel_jitter": false}})"));
    RenderResult r = renderImage(*scene);
    int inside = 0, outside = 0;
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 24; ++x) {
            double px = -1.5 + 3.0 * (x + 0.5) / 24, py = 1.5 - 3.0 * (y + 0.5) / 24;
            double rho2 = px * px + py * py;
            double c = rho2 < 1 ? 2 * std::sqrt(1 - rho2) : 0;
            double T = std::exp(-sw * (4 - c) - si * c);
            (rho2 < 1 ? inside : outside)++;
            ASSERT_NEAR(r.image.alpha(x, y), 1 - T, 2 * (sw + si) * dx + 1e-5) << x << "," << y;
        }
    EXPECT_GT(inside, 100);
    EXPECT_GT(outside, 100);
}

// Under a uniform background of radiance 1 with no media, every camera path
// through lossless glass ends on the background with weight exactly 1
// (Fresnel choice weights cancel, total internal reflection keeps the ray):
// the image is 1 everywhere and no sample is lost or non-finite.
TEST(Glass, LosslessDielectricsConserveRadianceUnderUniformBackground) {
    auto scene = sceneFromJson(R"({"camera": {"position": [0.3, 0.4, 4], "look_at": [0, 0, 0], "fov_deg": 45,
        "resolution": [32, 32]},
        "surfaces": [{"shape": "sphere", "transform": {"scale": [1, 0.7, 0.9]}, "material": {"type": "dielectric", "ior": 1.5}},
                     {"shape": "box", "transform": {"scale": 0.8, "rotate": [1, 1, 0, 30], "translate": [0.6, 0.3, 1]},
                      "material": {"type": "dielectric", "ior": 2.4}}],
        "background": [1, 1, 1], "render": {"spp": 4, "max_surface_bounces": 1000}})");
    RenderResult r = renderImage(*scene);
    EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
    EXPECT_GT(r.counters.surfaceHits, 1000u);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            ASSERT_NEAR(r.image.rgb(x, y).x, 1.f, 1e-6) << x << "," << y;
            ASSERT_NEAR(r.image.alpha(x, y), 0.f, 1e-6);
        }
}

// Index-matched glass (ior 1) bends nothing, so shadow rays cross it: an
// ior-1 sphere around a medium gives the same image as an interface sphere in
// expectation, for every method (glass draws one more random number per
// crossing, so the noise differs): the mean per-pixel difference is zero
// within 4 standard errors. Blocked shadow rays would darken it by far more.
TEST(Glass, IndexMatchedGlassLetsShadowRaysThrough) {
    auto scene = [](const std::string& material, Method method) {
        return sceneFromJson(R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_deg": 30, "resolution": [16, 16]},
            "lights": [{"type": "point", "position": [2, 3, 2], "intensity": 20}],
            "media": [{"name": "m", "type": "homogeneous", "sigma_s": 2, "sigma_a": 0.1}],
            "surfaces": [{"shape": "sphere", "material": )" + material + R"(, "interior": "m"}],
            "render": {"method": ")" + std::string(methodName(method)) + R"(", "spp": 4, "step": 0.01, "seed": 5}})");
    };
    for (Method method : estimatorMethods()) {
        SCOPED_TRACE(methodName(method));
        RenderResult a = renderImage(*scene(R"({"type": "interface"})", method));
        RenderResult b = renderImage(*scene(R"({"type": "dielectric", "ior": 1})", method));
        Image diff(a.image.width, a.image.height);
        for (int y = 0; y < diff.height; ++y)
            for (int x = 0; x < diff.width; ++x) diff.set(x, y, a.image.rgb(x, y) - b.image.rgb(x, y), 0);
        ChannelStats sa = pixelStats(a.image, 0), d = pixelStats(diff, 0);
        EXPECT_GT(sa.mean, 0.01);
        EXPECT_NEAR(d.mean, 0.0, 4 * d.stdError + 1e-7);
        EXPECT_LT(4 * d.stdError, 0.2 * sa.mean);  // power: blocking would remove most of the light
    }
}

}  // namespace
}  // namespace vdbmarch
