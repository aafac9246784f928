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
#include "illumination/illumination.h"
#include "photons/photon_tracer.h"
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

// Sphere lights' caustics (Scene::sphereLightCausticPhotons): a sphere light
// outside the glass icosahedron, thin fog around it. The photons give all
// the light the paths would find through the glass, in the smoke and in the
// fog, and the paths leave it out from the vertex that gathered them on; the
// image has the expectation of the paths alone (experiments.caustic_photons
// false, unbiased) up to the photons' blur, which the passes shrink.
std::string writeSphereLightScene(int count, const std::string& fog) {
    test::writeIcosahedron(workDir() + "/ico.obj");
    const std::string file = workDir() + "/sphere_light.json";
    std::ofstream(file) << R"({
  "camera": {"position": [0, 0.2, 3], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [32, 24]},
  "lights": [{"type": "sphere", "position": [1.2, 1.4, 0.6], "radius": 0.4, "power": [40, 40, 40]}],
  "media": [{"name": "fog", "type": "homogeneous", "sigma_a": 0.01, "sigma_s": )" + fog + R"(, "g": 0.2,
             "bounds": {"min": [-2, -1.5, -2], "max": [2, 2, 2]}},
            {"name": "smoke", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 1.5, "g": 0.3}],
  "surfaces": [{"shape": "mesh", "file": "ico.obj", "smooth_normals": false, "transform": {"scale": 0.8},
                "material": {"type": "dielectric", "ior": 1.5}, "interior": "smoke"}],
  "background": 0,
  "photons": {"count": )" + std::to_string(count) + R"(, "k": 30, "seed": 5},
  "render": {"max_depth": 6, "seed": 7, "step": 0.02}
})";
    return file;
}

Image renderSphereLight(Method method, int spp, uint64_t seed, bool causticPhotons, int count, const std::string& fog) {
    const std::string file = writeSphereLightScene(count, fog);
    SceneDesc d = loadSceneFile(file, {str("render.spp=", spp), str("render.seed=", seed),
                                       str("experiments.caustic_photons=", causticPhotons ? "true" : "false")});
    d.render.method = method;
    const auto scene = buildScene(d);
    EXPECT_EQ(scene->sphereLightCausticPhotons, causticPhotons);
    return renderImage(*scene).image;
}

// The photons that bring a sphere light into the smoke all passed the glass:
// flagged caustic with experiments.caustic_photons, none without, and the
// guided marcher then asks for the caustic map.
TEST(PathCaustics, SphereLightPhotonsThroughGlassAreCaustic) {
    const std::string file = writeSphereLightScene(20000, "0");
    for (bool on : {true, false}) {
        const auto scene = buildScene(loadSceneFile(file,
                                                    {str("experiments.caustic_photons=", on ? "true" : "false")}));
        const int smoke = scene->surfaces[0].interiorRegion;
        size_t inSmoke = 0, caustic = 0;
        for (const Photon& p : tracePhotons(*scene, 20000, 5).photons) {
            if (p.region() != smoke) continue;
            ++inSmoke;
            caustic += p.isCaustic();
        }
        EXPECT_GT(inSmoke, 100u);
        EXPECT_EQ(caustic, on ? inSmoke : 0u);
        EXPECT_EQ(illuminationRequest(*scene, Method::Guided).indirect, on);
        // The reference keeps its paths for sphere lights.
        EXPECT_FALSE(illuminationRequest(*scene, Method::Reference).indirect);
    }
}

// Without fog every pixel's light is a caustic: counted twice it would
// double the image, left out it would be black. With fog, the light the
// glass throws into the fog and the light the fog sees through the glass are
// left to photons too. The image means agree with the paths' within 4
// standard errors of the difference.
void expectSphereLightCausticsAsThePaths(Method method, int spp, const std::string& fog) {
    const Image paths = renderSphereLight(Method::Reference, 16 * spp, 1, false, 0, fog);
    const Image photons = renderSphereLight(method, spp, 2, true, 4000, fog);
    const MeanAndError p = meanOf(paths), q = meanOf(photons);
    EXPECT_GT(p.mean, 10 * p.error);
    const double error = std::hypot(p.error, q.error);
    EXPECT_NEAR(q.mean, p.mean, 4 * error) << "paths " << p.mean << " +- " << p.error << ", photons " << q.mean
                                           << " +- " << q.error;
}

TEST(PathCaustics, TheGuidedMarcherTakesSphereLightCausticsFromPhotons) {
    expectSphereLightCausticsAsThePaths(Method::Guided, 32, "0");
}

TEST(PathCaustics, SphereLightCausticsInFogAroundTheGlass) {
    expectSphereLightCausticsAsThePaths(Method::Guided, 32, "0.3");
}

// Where a delta light makes the reference gather caustic photons, those of
// a sphere light come with them, and its paths leave that light's caustics
// out past the gathering vertex as the marcher's do: the same expectation
// as the guided marcher given the same photons.
TEST(PathCaustics, TheReferenceLeavesSphereLightCausticsToPhotonsItGathers) {
    expectCausticsAsTheMarcher(R"({"type": "directional", "direction": [-0.4, -1, -0.3], "irradiance": [1, 1, 1]},
                                  {"type": "sphere", "position": [-1.2, 1.4, 0.6], "radius": 0.3, "power": [30, 30, 30]})",
                               4, 64);
}

}  // namespace
}  // namespace vdbmarch
