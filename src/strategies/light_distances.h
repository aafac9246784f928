// Distance sampling towards lights (equiangular sampling, Kulla & Fajardo
// 2012), combined with the free flights of delta tracking by multiple
// importance sampling. Near a point, spot or sphere light the light that
// scatters grows as 1/r^2, and a free flight drawn by transmittance alone
// seldom lands there: in a thin haze a spot's narrow beam holds a few
// collisions in a hundred, and a collision close to a light inside a medium
// brings a 1/d^2 firefly. So every path segment in a scattering region also
// draws one point by the equiangular density over the part of the segment a
// light reaches (a spot's cone, the scattering media's bounds), for one such
// light chosen in proportion to its unoccluded single scattering along the
// segment, and estimates that light's single scattering there; the
// next-event estimate of the same light at a tracking collision takes the
// complementary weight (the choice's probability is part of the density).
//
// The two strategies' power-heuristic weights sum to one at every t, so the
// sum is unbiased whatever densities the weights are computed from. The
// tracking density in them is sigma_s(t) T(t) with T exact in constant media
// and taken as 1 in gridded ones: an estimate of T is random, and a weight
// must be a function of t alone. At the sample, T itself comes from ratio
// tracking (unbiased).
#pragma once

#include <vector>

#include "core/sampling.h"
#include "strategies/strategy.h"

namespace vdbmarch {

// One light's equiangular sampler on a segment, with the odds that the
// segment samples this light.
struct LightDistance {
    int light;
    EquiangularSampler sampler;
    float choice = 1;
};

class LightDistances final : public DistanceStrategy {
public:
    // slot: this strategy's thread-context extension (StrategySet).
    LightDistances(const Scene& scene, size_t slot);

    bool needsSegmentEnd(int region, bool skipPointLights) const override {
        return regionHasCandidates(region, skipPointLights);
    }
    // Sets up one sampler per point-like or sphere light that reaches a
    // scattering part of the segment (point-like lights left out when the
    // segment skips them, as next-event estimation does), with the odds of
    // choosing each.
    bool prepare(ThreadContext& ctx, const PathSegment& seg) const override;
    // One distance sample, for one prepared light (chosen by its odds): the
    // light's single scattering T sigma_s f L T_shadow w / pdf(t).
    Color sample(ThreadContext& ctx, const PathSegment& seg, Rng& rng) const override;
    // Per scene light, the weight of next-event estimation at a tracking
    // collision at t: 1 for lights without a sampler.
    void weighCollision(ThreadContext& ctx, const PathSegment& seg, float t, const MediumPoint& mp,
                        CollisionWeights& w) const override;

    // The prepared segment's samplers (the guided marcher mixes their
    // densities into its per-ray pdf).
    const std::vector<LightDistance>& prepared(ThreadContext& ctx) const { return scratch(ctx).lights; }
    // Whether some light may get distance samples on segments in `region`,
    // and whether light `light` may.
    bool regionHasCandidates(int region, bool skipPointLights) const;
    bool candidate(int region, int light) const { return mCandidate[size_t(region) * mLights + size_t(light)] != 0; }
    const BBox& scatterBounds(int region) const { return mScatterBounds[size_t(region)]; }

private:
    struct Scratch final : ThreadContextExtension {
        std::vector<LightDistance> lights;
        std::vector<float> weights;  // per scene light (weighCollision)
    };
    Scratch& scratch(ThreadContext& ctx) const { return ctx.extensionAt<Scratch>(mSlot); }

    const Scene& mScene;
    const size_t mSlot;
    const size_t mLights;
    // experiments.volume_sampling = "equiangular": the distance samples take
    // all of a light's single scattering where they can land (no MIS);
    // "distance": none is made.
    const bool mEquiangularOnly, mOff;
    std::vector<BBox> mScatterBounds;  // per region
    // Per (region, light) whether distance sampling can ever pay there.
    std::vector<char> mCandidate;
};

}  // namespace vdbmarch
