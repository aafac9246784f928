// Scene::shadowRaysCanReach: next-event estimation skips lights that no
// shadow ray from a region can reach (a medium sealed in glass that bends
// light, with the light outside). The table must never claim "out of reach"
// where a shadow ray gets through: checked against the shadow-ray walk
// itself from points inside the region, for each configuration that should
// and should not be sealed.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "support/support.h"
#include "transport/thread_context.h"
#include "transport/transmittance.h"

namespace vdbmarch {
namespace {

using namespace test;

constexpr int Milk = 2;  // region of media[0], the glass's interior

// A unit sphere of `material` (a transform's scale `scale`) filled with milk,
// in an empty world, with `lights` (JSON array items) and a grey background.
std::unique_ptr<Scene> milkScene(const std::string& material, const std::string& lights,
                                 const std::string& shape = R"("shape": "sphere")") {
    return sceneFromJson(str(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "resolution": [8, 8]},
        "lights": [)", lights, R"(],
        "media": [{"name": "milk", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 1, "g": 0.5}],
        "surfaces": [{)", shape, R"(, "transform": {"scale": 1.2}, "material": )", material, R"(, "interior": "milk"}],
        "background": [0.2, 0.2, 0.2]})"));
}

const std::string Glass = R"({"type": "dielectric", "ior": 1.5})";
const std::string LightOutside = R"({"type": "sphere", "position": [0, 3, 0], "radius": 0.3, "power": [10, 10, 10]},
    {"type": "point", "position": [2, 0, 0], "intensity": [1, 1, 1]},
    {"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]})";

// Shadow rays from points inside `region` (rejection-sampled in the box
// [-1.2, 1.2]^3) towards light `light` (lights.size(): the environment, by
// uniform directions): how many of `rays` arrive with some transmittance.
int raysThrough(const Scene& scene, int region, size_t light, int rays = 400) {
    ThreadContext ctx(scene);
    Rng rng(hashValues(0x7265616368, uint64_t(light)));
    int through = 0;
    for (int n = 0; n < rays;) {
        const Vec3 p(2.4f * rng.uniform() - 1.2f, 2.4f * rng.uniform() - 1.2f, 2.4f * rng.uniform() - 1.2f);
        if (regionAtRayStart(scene, Ray{p, normalize(Vec3(0.3f, 0.5f, 0.8f))}) != region) continue;
        ++n;
        Vec3 wi;
        float dist = Infinity;
        if (light < scene.lights.size()) {
            LightSample ls;
            if (!scene.lights[light].sample(p, rng.uniform(), rng.uniform(), ls)) continue;
            wi = ls.wi;
            dist = ls.dist;
        } else {
            const float z = 2 * rng.uniform() - 1, phi = 2 * Pi * rng.uniform(), s = std::sqrt(1 - z * z);
            wi = Vec3(s * std::cos(phi), s * std::sin(phi), z);
        }
        const Color T = shadowTransmittance(ctx, region, p, wi, dist, rng, TransmittanceEstimator::RatioTracking);
        through += maxComponent(T) > 0;
    }
    return through;
}

// Every light the table puts out of reach of `region` is out of reach of
// every shadow ray tried; returns how many lights (and the environment) it
// puts out of reach.
int expectTableIsSound(const Scene& scene, int region) {
    int sealed = 0;
    for (size_t i = 0; i <= scene.lights.size(); ++i) {
        if (scene.shadowRaysCanReach(region, i)) continue;
        ++sealed;
        EXPECT_EQ(raysThrough(scene, region, i), 0) << "light " << i << " marked out of reach of region " << region;
    }
    return sealed;
}

TEST(ShadowReach, LightsOutsideBendingGlassAreOutOfReachOfItsMedium) {
    auto scene = milkScene(Glass, LightOutside);
    EXPECT_EQ(expectTableIsSound(*scene, Milk), 4);  // three lights and the environment
    for (size_t i = 0; i <= scene->lights.size(); ++i) {
        EXPECT_TRUE(scene->shadowRaysCanReach(Scene::WorldRegion, i));
        EXPECT_GT(raysThrough(*scene, Scene::WorldRegion, i, 100), 0) << "light " << i << " from the world";
    }
}

TEST(ShadowReach, LightsInsideOrAcrossTheGlassStayInReach) {
    // A sphere light inside, one whose centre is outside but whose sphere
    // crosses the glass (at radius 1.2), and a point light inside.
    auto scene = milkScene(Glass, R"({"type": "sphere", "position": [0.3, 0, 0], "radius": 0.2, "power": [10, 10, 10]},
        {"type": "sphere", "position": [0, 1.35, 0], "radius": 0.2, "power": [10, 10, 10]},
        {"type": "point", "position": [0, -0.5, 0], "intensity": [1, 1, 1]})");
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_TRUE(scene->shadowRaysCanReach(Milk, i)) << "light " << i;
        EXPECT_GT(raysThrough(*scene, Milk, i), 0) << "light " << i;
    }
    EXPECT_EQ(expectTableIsSound(*scene, Milk), 1);  // the environment only
}

TEST(ShadowReach, SurfacesThatLetShadowRaysThroughSealNothing) {
    for (const std::string& m : {std::string(R"({"type": "interface"})"),
                                 std::string(R"({"type": "dielectric", "ior": 1})")}) {
        auto scene = milkScene(m, LightOutside);
        EXPECT_EQ(expectTableIsSound(*scene, Milk), 0) << m;
        EXPECT_GT(raysThrough(*scene, Milk, 1), 0) << m;
    }
}

TEST(ShadowReach, AnOpenMeshSealsNothing) {
    // A cube with its top face missing: rays from inside escape upwards.
    TempDir dir;
    const std::string obj = dir.write("open_box.obj", "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                   "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 4 1 5\nf 4 5 8\n");
    setWarningsQuiet(true);
    auto scene = milkScene(Glass, LightOutside, str(R"("shape": "mesh", "file": ")", obj, R"(")"));
    setWarningsQuiet(false);
    EXPECT_EQ(expectTableIsSound(*scene, Milk), 0);
    EXPECT_GT(raysThrough(*scene, Milk, 0), 0);  // the sphere light above the open top
}

TEST(ShadowReach, TheGlassKnotSampleSealsItsMilk) {
    // exp1_sphere: the sphere light sits in the knot's loops, close to the
    // glass but outside it (the exact distance test, not a bounding box).
    auto scene = buildScene(loadSceneFile(samplePath("scenes/exp1_sphere.json")));
    int milk = -1;
    for (size_t i = 0; i < scene->media.size(); ++i)
        if (scene->desc.media[i].name == "milk") milk = 2 + int(i);
    ASSERT_GE(milk, 2);
    EXPECT_EQ(expectTableIsSound(*scene, milk), 2);  // the sphere light and the environment
}

}  // namespace
}  // namespace vdbmarch
