// The path loop iterates whatever strategies the render's set holds
// (strategies/strategy.h): test-only strategies plugged in from here, with
// no change to the loop, keep the estimate unbiased.
//  - A direction strategy drawing half its directions uniformly over the
//    sphere: the furnace (albedo 1 under a background of 1) stays at 1.
//  - A distance strategy drawing positions uniformly along the medium part
//    of each segment towards a point light, weighed against the tracking
//    collisions by MIS: the render agrees with tracking alone.
//  - A surface strategy choosing reflection or refraction at glass with
//    chance 1/2 each in place of the Fresnel choice: a furnace of glass in
//    white fog stays at 1, with the reference path tracer and the marcher.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

#include "core/sampling.h"
#include "render/render.h"
#include "strategies/strategy_set.h"
#include "support/support.h"
#include "transport/direct_light.h"

namespace vdbmarch {
namespace {

using test::pixelStats;
using test::sceneFromJson;

// Half phase sampling, half uniform directions, at medium vertices.
class UniformDirections final : public DirectionStrategy {
public:
    UniformDirections(const Scene&, size_t slot) : mSlot(slot) {}
    bool attach(ThreadContext& ctx, int, ScatterVertex& v, bool) const override {
        if (!v.phase) return false;
        Scratch& s = ctx.extensionAt<Scratch>(mSlot);
        s.vertex = &v;
        v.pathPdf = &pdfOf;
        v.pathSampler = &s;
        return true;
    }
    Vec3 sample(ThreadContext& ctx, Rng& rng, Color& weight, float& pdf) const override {
        const Scratch& s = ctx.extensionAt<Scratch>(mSlot);
        const ScatterVertex& v = *s.vertex;
        const float u = rng.uniform(), u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        Vec3 wi;
        if (u < 0.5f) {
            wi = sampleUniformSphere(u1, u2);
        } else {
            Color unused(1);
            float phasePdf;
            wi = v.phase->sample(v.d, u0, u1, u2, unused, phasePdf);
        }
        pdf = pdfOf(&s, wi);
        weight *= v.f(wi) / pdf;
        ++samples;
        return wi;
    }
    mutable std::atomic<long> samples{0};

private:
    struct Scratch final : ThreadContextExtension {
        const ScatterVertex* vertex = nullptr;
    };
    static float pdfOf(const void* self, const Vec3& wi) {
        const ScatterVertex& v = *static_cast<const Scratch*>(self)->vertex;
        return 0.5f * v.fPdf(wi) + 0.5f * uniformSpherePdf();
    }
    const size_t mSlot;
};

// One position per segment, uniform over the part of the segment in the
// region's scattering media, estimating every light's single scattering
// there; a tracking collision keeps the complementary MIS weight.
class UniformDistances final : public DistanceStrategy {
public:
    UniformDistances(const Scene& scene, size_t slot) : mBounds(scatterBoundsOf(scene)), mSlot(slot) {}
    bool prepare(ThreadContext& ctx, const PathSegment& seg) const override {
        Scratch& s = ctx.extensionAt<Scratch>(mSlot);
        s.a = 0;
        s.b = seg.tEnd;
        return mBounds[size_t(seg.region)].intersect(seg.ray, s.a, s.b) && s.b > s.a && std::isfinite(s.b);
    }
    Color sample(ThreadContext& ctx, const PathSegment& seg, Rng& rng) const override {
        const Scratch& s = ctx.extensionAt<Scratch>(mSlot);
        const float t = s.a + rng.uniform() * (s.b - s.a);
        ++samples;
        return scatteredAt(ctx, seg, t, pdf(s, t), false, rng, [&](const ScatterVertex& v) {
            DirectLightOptions o;
            o.transmittance = TransmittanceEstimator::UnbiasedMarching;
            o.sampleBackground = false;
            return directLight(ctx, seg.region, v, rng, o);
        });
    }
    void weighCollision(ThreadContext& ctx, const PathSegment& seg, float t, const MediumPoint& mp,
                        CollisionWeights& w) const override {
        Scratch& s = ctx.extensionAt<Scratch>(mSlot);
        s.weights.assign(ctx.scene.lights.size(), 1 - distanceWeight(pdf(s, t), trackingDensity(ctx, seg, t, mp)));
        w.lightWeights = s.weights.data();
    }
    mutable std::atomic<long> samples{0};

private:
    struct Scratch final : ThreadContextExtension {
        float a = 0, b = 0;
        std::vector<float> weights;
    };
    static float pdf(const Scratch& s, float t) { return t >= s.a && t <= s.b ? 1 / (s.b - s.a) : 0.f; }
    std::vector<BBox> mBounds;
    const size_t mSlot;
};

// Reflection or refraction at glass with chance 1/2 each, weighted by the
// Fresnel chance over 1/2: unbiased, with other variance than the Fresnel choice.
class EvenGlassChoice final : public SurfaceStrategy {
public:
    EvenGlassChoice(const Scene&, size_t) {}
    bool sample(ThreadContext& ctx, const SurfaceHit& hit, const Vec3& d, int region, const float u[3],
                const SurfaceRequest&, Rng&, PathSurfaceEvent& out) const override {
        const Scene& scene = ctx.scene;
        if (scene.surfaces[size_t(hit.surface)].material.type != MaterialDesc::Type::Dielectric) return false;
        const DielectricEvents both = dielectricEvents(scene, hit, d, region, TransportMode::Radiance);
        const float F = both.reflectProbability;
        const bool reflect = u[0] < 0.5f;
        out.event = both.outcome[reflect ? 0 : 1];
        out.weight = out.event.weight * (reflect ? 2 * F : 2 * (1 - F));
        ++samples;
        return true;
    }
    mutable std::atomic<long> samples{0};
};

// Every channel's pixel mean is 1 within 4 standard errors.
void expectFurnaceAtOne(const Image& image, const std::string& label) {
    for (int c = 0; c < 3; ++c) {
        const auto s = pixelStats(image, c);
        EXPECT_NEAR(s.mean, 1.0, 4 * s.stdError + 1e-6) << label << " channel " << c;
    }
}

// Renders `scene` with its default strategies plus a Strategy(scene, slot);
// `samples` is the plugged strategy's sample count.
template <typename Strategy>
RenderResult renderPlugged(const Scene& scene, long& samples) {
    auto set = StrategySet::build(scene);
    auto strategy = std::make_unique<Strategy>(scene, set->newSlot());
    const Strategy& plugged = *strategy;
    set->add(std::move(strategy));
    RenderOptions options;
    options.strategies = set;
    RenderResult r = renderImage(scene, options);
    samples = plugged.samples.load();
    return r;
}

TEST(PluggedStrategies, AUniformDirectionMixtureKeepsTheFurnaceAtTheBackground) {
    for (const char* sigma : {"4", "[1, 4, 9]"}) {  // grey, then chromatic extinction
        auto scene = sceneFromJson(str(
            R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [16, 16]},
            "media": [{"type": "homogeneous", "sigma_a": 0, "sigma_s": )", sigma, R"(, "g": 0.7,
                       "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
            "background": [1, 1, 1], "render": {"method": "reference", "spp": 8, "max_depth": 100000, "seed": 4}})"));
        long samples = 0;
        const RenderResult r = renderPlugged<UniformDirections>(*scene, samples);
        EXPECT_GT(samples, 1000) << "the loop never asked the plugged strategy";
        EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
        expectFurnaceAtOne(r.image, str("sigma_s ", sigma));
    }
}

TEST(PluggedStrategies, AUniformDistanceSamplerAgreesWithTrackingAlone) {
    // Equiangular sampling off, so that the plugged sampler is the only one
    // weighing the point light's next-event estimates.
    auto scene = sceneFromJson(
        R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [24, 24]},
        "lights": [{"type": "point", "position": [0.3, 1.6, 0.2], "intensity": [3, 3, 3]}],
        "media": [{"type": "homogeneous", "sigma_a": 0.2, "sigma_s": [0.8, 1.0, 1.2], "g": 0.4,
                   "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
        "render": {"method": "reference", "spp": 32, "max_depth": 3, "seed": 9},
        "experiments": {"volume_sampling": "distance"}})");
    const RenderResult plain = renderImage(*scene);
    long samples = 0;
    const RenderResult r = renderPlugged<UniformDistances>(*scene, samples);
    EXPECT_GT(samples, 1000) << "the loop never asked the plugged strategy";
    EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
    test::expectPairedAgreement(plain.image, r.image, "uniform distances against tracking alone");
}

TEST(PluggedStrategies, AnEvenGlassChoiceKeepsAFurnaceOfGlassInFogAtTheBackground) {
    // As GlassSplitting.AFurnaceOfGlassInWhiteFogStaysAtTheBackground, with
    // glass splitting off so that the plugged strategy takes every glass event.
    for (const char* method : {"reference", "guided"}) {
        auto scene = test::glassInWhiteFog(method, false);
        long samples = 0;
        const RenderResult r = renderPlugged<EvenGlassChoice>(*scene, samples);
        EXPECT_GT(samples, 1000) << "the loop never asked the plugged strategy";
        EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
        expectFurnaceAtOne(r.image, method);
    }
}

}  // namespace
}  // namespace vdbmarch
