// The path tracer and the caustics of delta lights through refracting glass:
// no path can find a point light through a glass mesh (shadow rays cannot
// bend), so the caustic photons give that light at a camera path's first
// medium vertex, as they do at the guided marcher's L_i samples. Smoke
// inside a glass icosahedron, lit only by a point light outside it, with no
// other medium and a black background: every pixel's light is a caustic.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "core/error.h"
#include "render/render.h"
#include "scene/scene.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

const std::string& workDir() {
    static const test::TempDir dir("path_caustics");
    return dir.path();
}

// The guided marcher's L_i and the path tracer's first medium vertex take
// the same caustic photons (the same passes, seeds and radii: the photon
// seed is fixed while the pixels' seed varies), and paths for the rest, so
// their images have the same expectation given those photons, for any
// photon count, and their per-pixel difference has independent pixels.
// (Not for point lights beyond single scattering: there the marcher's
// photons also carry their multiply scattered light.)
Image render(Method method, int spp, uint64_t seed, const std::string& light, int maxDepth) {
    test::writeIcosahedron(workDir() + "/ico.obj");
    const std::string file = workDir() + "/scene.json";
    std::ofstream(file) << R"({
  "camera": {"position": [0, 0.2, 3], "look_at": [0, 0, 0], "fov_deg": 35, "resolution": [40, 30]},
  "lights": [)" + light + R"(],
  "media": [{"name": "smoke", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 1.5, "g": 0.3}],
  "surfaces": [{"shape": "mesh", "file": "ico.obj", "smooth_normals": true, "transform": {"scale": 0.8},
                "material": {"type": "dielectric", "ior": 1.5}, "interior": "smoke"}],
  "background": 0,
  "photons": {"count": 20000, "k": 30, "seed": 5},
  "render": {"max_depth": )" + std::to_string(maxDepth) + R"(, "seed": 7, "step": 0.02}
})";
    SceneDesc d = loadSceneFile(file, {str("render.spp=", spp), str("render.seed=", seed)});
    d.render.method = method;
    return renderImage(*buildScene(d)).image;
}

// Mean over pixels and channels, and its standard error from the pixels.
struct MeanAndError {
    double mean = 0, error = 0;
};
MeanAndError meanOf(const Image& img, const Image* minus = nullptr) {
    double s = 0, s2 = 0;
    const size_t n = img.pixelCount();
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            double v = 0;
            for (int c = 0; c < 3; ++c) v += (double(img.rgb(x, y)[c]) - (minus ? double(minus->rgb(x, y)[c]) : 0)) / 3;
            s += v;
            s2 += v * v;
        }
    MeanAndError m;
    m.mean = s / double(n);
    m.error = std::sqrt(std::max(0.0, s2 / double(n) - m.mean * m.mean) / double(n - 1));
    return m;
}

// Every pixel's light is a caustic here: before the caustic photons, the
// path tracer's image was black. And the guided marcher, whose L_i takes
// the same photons, gives the same image in expectation (paired by pixel,
// different camera samples).
void expectCausticsAsTheMarcher(const std::string& light, int maxDepth, int spp) {
    const Image reference = render(Method::Reference, spp, 1, light, maxDepth);
    const MeanAndError lit = meanOf(reference);
    EXPECT_GT(lit.mean, 10 * lit.error);
    const Image guided = render(Method::Guided, spp, 2, light, maxDepth);
    const MeanAndError diff = meanOf(reference, &guided);
    EXPECT_NEAR(diff.mean, 0.0, 4 * diff.error) << "reference mean " << lit.mean;
}

TEST(PathCaustics, ThePathTracerSeesAPointLightThroughAGlassMesh) {
    expectCausticsAsTheMarcher(R"({"type": "point", "position": [1.5, 2.0, 0.5], "intensity": [5, 5, 5]})", 1, 64);
}

TEST(PathCaustics, MultipleScatteringOfTheSunThroughAGlassMesh) {
    expectCausticsAsTheMarcher(R"({"type": "directional", "direction": [-0.4, -1, -0.3], "irradiance": [3, 3, 3]})",
                               4, 32);
}

}  // namespace
}  // namespace vdbmarch
