// Shadow-ray roulette by the phase value (direct_light.h, PhaseRouletteShare):
// at vertices inside the sample cloud with a forward-scattering phase
// (g = 0.8), next-event estimation with the roulette must have the mean of
// next-event estimation without it (within 4 standard errors of the
// difference), cast fewer shadow rays, and leave weakly anisotropic media
// (the cloud's own g = 0.2) untouched: the same numbers, no draw taken.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"
#include "transport/direct_light.h"
#include "transport/media_point.h"
#include "transport/thread_context.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

std::unique_ptr<Scene> cloudWithG(float g) {
    SceneDesc desc = loadSceneFile(samplePath("cloud.json"));
    desc.media[0].g = g;
    return buildScene(desc);
}

struct Estimate {
    double mean = 0, variance = 0;
    uint64_t shadowRays = 0;
};

// n next-event estimates (grey average) at x for a path arriving along d.
Estimate nextEvent(ThreadContext& ctx, const Vec3& x, const Vec3& d, bool roulette, int n, uint64_t seed) {
    MediumPoint mp;
    evalMedia(ctx, Scene::WorldRegion, x, mp);
    const ScatterVertex v = ScatterVertex::inMedium(x, d, mp.phase);
    DirectLightOptions o;
    o.transmittance = TransmittanceEstimator::UnbiasedMarching;
    o.misWithPathHits = true;
    o.sampleBackground = false;
    o.phaseRoulette = roulette;
    Rng rng(seed, 1);
    const uint64_t before = ctx.counters.shadowRays;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        const double L = average(directLight(ctx, Scene::WorldRegion, v, rng, o));
        sum += L;
        sum2 += L * L;
    }
    Estimate e;
    e.mean = sum / n;
    e.variance = std::max(0.0, sum2 / n - e.mean * e.mean) / n;
    e.shadowRays = ctx.counters.shadowRays - before;
    return e;
}

// Points in the cloud (where it scatters) and arriving directions: two
// against the sun's light (the path travels towards the sun, so the sun's
// light scatters forward into it: inside the lobe) and the rest at random.
struct Vertex {
    Vec3 x, d;
};
std::vector<Vertex> vertices(const Scene& scene) {
    ThreadContext ctx(scene);
    const BBox b = scene.media[0]->worldBounds();
    const Vec3 sunTravel = normalize(scene.desc.lights[0].direction);
    Rng rng(29, 2);
    std::vector<Vertex> out;
    MediumPoint mp;
    while (out.size() < 8) {
        const Vec3 x = b.lo + Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * b.extent();
        evalMedia(ctx, Scene::WorldRegion, x, mp);
        if (!mp.scatters()) continue;
        const Vec3 d = out.size() < 2 ? -sunTravel : sampleUniformSphere(rng.uniform(), rng.uniform());
        out.push_back({x, d});
    }
    return out;
}

TEST(PhaseRoulette, KeepsTheMeanOfNextEventEstimation) {
    const auto scene = cloudWithG(0.8f);
    ASSERT_TRUE(scene->regions[Scene::WorldRegion].gridded);
    ThreadContext ctx(*scene);
    uint64_t raysOn = 0, raysOff = 0;
    int k = 0;
    for (const Vertex& v : vertices(*scene)) {
        const Estimate off = nextEvent(ctx, v.x, v.d, false, 4000, 100 + k);
        const Estimate on = nextEvent(ctx, v.x, v.d, true, 4000, 200 + k);
        ++k;
        raysOn += on.shadowRays;
        raysOff += off.shadowRays;
        if (k <= 2) {
            EXPECT_EQ(on.shadowRays, off.shadowRays) << "inside the lobe every shadow ray is cast";
        }
        const double se = std::sqrt(off.variance + on.variance);
        EXPECT_LE(std::fabs(on.mean - off.mean), 4 * se + 1e-12)
            << "vertex " << k << ": with roulette " << on.mean << ", without " << off.mean << ", se " << se;
    }
    // Most random directions lie outside a g = 0.8 lobe: fewer shadow rays.
    EXPECT_LT(double(raysOn), 0.8 * double(raysOff)) << raysOn << " against " << raysOff;
}

TEST(PhaseRoulette, LeavesWeaklyAnisotropicMediaAlone) {
    const auto scene = cloudWithG(0.2f);  // level 0.5 x 1.11: below the isotropic value
    ThreadContext ctx(*scene);
    for (const Vertex& v : vertices(*scene)) {
        const Estimate off = nextEvent(ctx, v.x, v.d, false, 200, 7);
        const Estimate on = nextEvent(ctx, v.x, v.d, true, 200, 7);
        EXPECT_EQ(on.mean, off.mean);
        EXPECT_EQ(on.shadowRays, off.shadowRays);
    }
}

}  // namespace
}  // namespace vdbmarch
