// Smooth-shaded glass seen and lit through by every method: a 20-triangle
// icosahedron with smooth_normals holding smoke, in front of coloured
// diffuse tiles, in thin fog, under a sphere light (so the reference path
// tracer converges through the glass). Every path loop shares one surface
// event, so camera paths, reference paths and photons all refract about the
// shading normal; before, only the marchers' camera rays did, and the
// reference rendered the same with smooth_normals on or off.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "core/error.h"
#include "estimators/estimator.h"
#include "render/render.h"
#include "scene/scene.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

const std::string& smoothGlassDir() {
    static const test::TempDir dir("smooth_glass");
    return dir.path();
}

std::string sceneText(bool smooth, bool smoke) {
    return str(R"({
  "camera": {"position": [0, 0.2, 4], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [48, 36]},
  "lights": [{"type": "sphere", "position": [1.2, 1.8, 2.5], "radius": 0.5, "power": [300, 300, 300]}],
  "media": [
    {"name": "fog", "type": "homogeneous", "sigma_a": 0.01, "sigma_s": 0.05, "g": 0.3,
     "bounds": {"min": [-3, -2, -3], "max": [3, 3, 5]}},
    {"name": "smoke", "type": "homogeneous", "sigma_a": )", smoke ? 0.05 : 0.0, R"(, "sigma_s": )", smoke ? 0.5 : 0.0, R"(, "g": 0.5}],
  "surfaces": [
    {"shape": "mesh", "file": "ico.obj", "smooth_normals": )", smooth ? "true" : "false", R"(,
     "transform": {"scale": 0.75}, "material": {"type": "dielectric", "ior": 1.5},
     "interior": "smoke", "exterior": "fog"},
    {"shape": "box", "transform": {"scale": [1.2, 1.2, 0.1], "translate": [-0.6, 0.6, -1.2]},
     "material": {"type": "diffuse", "albedo": [0.8, 0.1, 0.1]}},
    {"shape": "box", "transform": {"scale": [1.2, 1.2, 0.1], "translate": [0.6, 0.6, -1.2]},
     "material": {"type": "diffuse", "albedo": [0.1, 0.8, 0.1]}},
    {"shape": "box", "transform": {"scale": [1.2, 1.2, 0.1], "translate": [-0.6, -0.6, -1.2]},
     "material": {"type": "diffuse", "albedo": [0.1, 0.1, 0.8]}},
    {"shape": "box", "transform": {"scale": [1.2, 1.2, 0.1], "translate": [0.6, -0.6, -1.2]},
     "material": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}],
  "photons": {"count": 200000, "k": 50},
  "render": {"max_depth": 4, "seed": 7, "step": 0.02}
})");
}

Image render(bool smooth, bool smoke, Method method, int spp, uint64_t seed) {
    const std::string file = smoothGlassDir() + (smooth ? "/smooth" : "/flat") + (smoke ? "_smoke.json" : ".json");
    test::writeIcosahedron(smoothGlassDir() + "/ico.obj");
    std::ofstream(file) << sceneText(smooth, smoke);
    SceneDesc d = loadSceneFile(file, {str("render.spp=", spp), str("render.seed=", seed)});
    d.render.method = method;
    return renderImage(*buildScene(d)).image;
}

// Paired differences of two images over B x B pixel blocks: the statistic
// sum_b (D_b / SE_b)^2 / blocks is about 1 when the two images estimate the
// same picture (the block means differ by noise alone) and grows with
// low-frequency disagreement; also the mean difference and its SE. Pixels
// are clamped at `clampAt` first: light refracted onto the tiles reaches
// the path tracer as rare bright samples, whose heavy tail would make the
// per-block standard errors unreliable; two renders with the same method
// and sample count have the same clamped expectation.
struct BlockAgreement {
    double meanDiff = 0, stdError = 0, mean = 0, blockChi2PerBlock = 0;
    int blocks = 0;
};

BlockAgreement compareBlocks(const Image& a, const Image& b, int B, float clampAt = Infinity) {
    BlockAgreement r;
    double s = 0, s2 = 0, m = 0;
    size_t n = 0;
    for (int by = 0; by + B <= a.height; by += B)
        for (int bx = 0; bx + B <= a.width; bx += B) {
            double bs = 0, bs2 = 0;
            int bn = 0;
            for (int y = by; y < by + B; ++y)
                for (int x = bx; x < bx + B; ++x) {
                    // One value per pixel: its channels share their samples.
                    double d = 0;
                    for (int c = 0; c < 3; ++c) {
                        d += (double(std::min(a.rgb(x, y)[c], clampAt)) - double(std::min(b.rgb(x, y)[c], clampAt))) / 3;
                        m += double(std::min(b.rgb(x, y)[c], clampAt)) / 3;
                    }
                    bs += d;
                    bs2 += d * d;
                    ++bn;
                }
            const double mean = bs / bn, var = std::max(0.0, bs2 / bn - mean * mean) / (bn - 1);
            if (var > 0) {
                r.blockChi2PerBlock += mean * mean / var;
                ++r.blocks;
            }
            s += bs;
            s2 += bs2;
            n += size_t(bn);
        }
    r.meanDiff = s / double(n);
    r.stdError = std::sqrt(std::max(0.0, s2 / double(n) - r.meanDiff * r.meanDiff) / double(n - 1));
    r.mean = m / double(n);
    r.blockChi2PerBlock /= std::max(1, r.blocks);
    return r;
}

void report(const char* what, const BlockAgreement& a) {
    if (std::getenv("VDBMARCH_VERBOSE"))
        std::printf("%s: mean diff %.4g (%.2f%% of mean %.4g, %.1f SE), block chi2/block %.3g over %d blocks\n", what,
                    a.meanDiff, 100 * a.meanDiff / a.mean, a.mean, a.meanDiff / a.stdError, a.blockChi2PerBlock,
                    a.blocks);
}

constexpr int Block = 4;

TEST(SmoothGlass, ReferenceSeesTheShadingNormals) {
    const int spp = 1024;
    // Without smoke in the glass, the tiles are seen sharply through it.
    const Image smooth = render(true, false, Method::Reference, spp, 1),
                flat = render(false, false, Method::Reference, spp, 2),
                smooth2 = render(true, false, Method::Reference, spp, 3);
    const float clampAt = 0.4f;  // four times the image mean
    const BlockAgreement same = compareBlocks(smooth2, smooth, Block, clampAt),
                         differ = compareBlocks(flat, smooth, Block, clampAt);
    report("reference smooth vs smooth (other seed)", same);
    report("reference flat vs smooth", differ);
    // Two seeds: blocks x the statistic is chi-square with `blocks` degrees
    // of freedom. Facets against a smooth surface move the tiles' image:
    // far outside the noise.
    EXPECT_GT(test::chiSquareQ(same.blockChi2PerBlock * same.blocks, same.blocks), 1e-4);
    EXPECT_LT(test::chiSquareQ(differ.blockChi2PerBlock * differ.blocks, differ.blocks), 1e-9);
}

TEST(SmoothGlass, EveryMethodAgreesWithTheReference) {
    const Image ref = render(true, true, Method::Reference, 512, 11);
    for (Method m : estimatorMethods()) {
        if (m == Method::Reference) continue;
        const Image img = render(true, true, m, m == Method::Uniform ? 8 : 48, 12);
        const BlockAgreement a = compareBlocks(img, ref, Block);
        report(methodName(m), a);
        // The photon map's kNN bias (3% of the mean, as in MarcherAgreement).
        EXPECT_NEAR(a.meanDiff, 0.0, 4 * a.stdError + 0.03 * a.mean) << methodName(m);
    }
}

}  // namespace
}  // namespace vdbmarch
