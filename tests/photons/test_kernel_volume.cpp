// The part of a photon gather's sphere inside its medium region
// (photons/kernel_volume.h), against the closed forms of a sphere cut by a
// plane and of a ball inside a smaller glass ball.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "photons/kernel_volume.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

// A glass box far larger than the kernels: its face z = 1 is a plane to them.
std::unique_ptr<Scene> scene(const std::string& surface) {
    return test::sceneFromJson(R"({
  "camera": {"position": [0, 0, 30], "look_at": [0, 0, 0], "resolution": [8, 8]},
  "lights": [{"type": "point", "position": [0, 5, 0], "intensity": 1}],
  "media": [{"name": "smoke", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 1}],
  "surfaces": [)" + surface + R"(]
})");
}

// Volume of the ball of radius r about a point at distance h inside a plane:
// the ball less the cap beyond the plane, of height r - h.
double planeFraction(double h, double r) {
    if (h >= r) return 1;
    const double a = r - h;
    return 1 - Pi * a * a * (3 * r - a) / 3 / (4.0 / 3.0 * Pi * r * r * r);
}

TEST(KernelVolume, ABallCutByAPlaneHasTheCapsVolumeInExpectation) {
    const auto s = scene(R"({"shape": "box", "transform": {"scale": [40, 40, 2]},
                             "material": {"type": "dielectric", "ior": 1.5}, "interior": "smoke"})");
    const float r = 0.2f;
    for (double h : {0.002, 0.05, 0.1, 0.15, 0.19}) {
        // Points at the same depth, each with its own rotation of the directions.
        const int n = 4000;
        double sum = 0, sum2 = 0;
        Rng rng(17, uint64_t(h * 1000));
        for (int i = 0; i < n; ++i) {
            const Vec3 x(4 * rng.uniform() - 2, 4 * rng.uniform() - 2, float(1 - h));
            const double f = kernelFractionInside(*s, x, r);
            sum += f;
            sum2 += f * f;
        }
        const double mean = sum / n, error = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
        EXPECT_NEAR(mean, planeFraction(h, r), 4 * error + 1e-6) << "h " << h;
    }
}

TEST(KernelVolume, ABallInsideSmallerGlassKeepsTheGlassVolume) {
    // A unit glass ball about the origin: a kernel of radius 2 there holds
    // the ball alone, (1/2)^3 of it, along every direction.
    const auto s = scene(R"({"shape": "sphere", "transform": {"scale": 1},
                             "material": {"type": "dielectric", "ior": 1.5}, "interior": "smoke"})");
    EXPECT_NEAR(kernelFractionInside(*s, Vec3(0, 0, 0), 2.f), 0.125, 1e-3);
    EXPECT_FLOAT_EQ(kernelFractionInside(*s, Vec3(0, 0, 0), 0.5f), 1.f);
    // A sliver: never below MinKernelFraction.
    EXPECT_GE(kernelFractionInside(*s, Vec3(0.999f, 0, 0), 20.f), MinKernelFraction);
}

}  // namespace
}  // namespace vdbmarch
