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

#include "core/rng.h"
#include "transport/caustic_folds.h"
#include "transport/media_point.h"

namespace vdbmarch {

// One path segment [0, tEnd) of `ray` in `region`, with the equiangular
// samplers of its lights (kept in ctx.lightDistances).
struct LightDistanceSegment {
    Ray ray;
    int region;
    int channel;  // tracked channel, < 0 for grey extinction
    // experiments.volume_sampling = "equiangular": the distance samples take all
    // of a light's single scattering where they can land (no MIS).
    bool equiangularOnly = false;
    bool active = false;  // some light has a sampler
    float tEnd = 0;
};

// Sets up the samplers of the segment: one per point-like or sphere light
// that reaches a scattering part of it (point-like lights left out when
// `skipPointLights`, as next-event estimation leaves them), with the odds of
// choosing each.
LightDistanceSegment prepareLightDistances(ThreadContext& ctx, int region, const Ray& ray, float tEnd, int channel,
                                           bool skipPointLights);

// The hull of the bounds of `region`'s scattering media (made on first use).
const BBox& scatterBounds(ThreadContext& ctx, int region);

// Whether a light at `position` sees `region` with no surface that blocks
// shadow rays between: in a scene with such surfaces, the light must lie in
// the region (a conservative test; one without them sees every region).
bool openToRegion(const Scene& scene, const Vec3& position, int region);

// Whether some light may get distance samples on segments in `region`
// (prepareLightDistances then needs the segment's true end).
bool regionHasLightDistances(ThreadContext& ctx, int region, bool skipPointLights);

// Light::reachInterval of scene light `light` for `ray`, remembered per
// thread for the last ray asked (bit-identical rays only).
bool lightReach(ThreadContext& ctx, int light, const Ray& ray, float& t0, float& t1);

// One distance sample, for one prepared light (chosen by its odds):
// T(t) sigma_s(t) f L T_shadow w / pdf(t), the light's single scattering
// along the segment weighted for MIS.
Color sampleLightDistances(ThreadContext& ctx, const LightDistanceSegment& seg, Rng& rng);

// Near the folds of caustics behind glass spheres (caustic_folds.h), where
// the light of point-like and parallel lights connected through the glass
// grows as 1 / sqrt(distance): one distance sample by the folds' density
// (crossings of the segment, prepareFoldDistances), estimating those
// connections there (sphereCausticLight's delta part; point-like lights
// only with `pointLights`, as the vertices connect them), weighed against
// the tracking collisions' by the power heuristic. foldTrackingWeight is
// the collisions' share at t (CausticLights::deltaWeight).
Color sampleFoldDistances(ThreadContext& ctx, const LightDistanceSegment& seg, const FoldSampler& folds, bool pointLights,
                          Rng& rng);
float foldTrackingWeight(ThreadContext& ctx, const LightDistanceSegment& seg, const FoldSampler& folds, float t,
                         const MediumPoint& mp);

// Per scene light, the weight of next-event estimation at a tracking
// collision at t (media mp there): 1 for lights without a sampler. Written to
// ctx.lightWeights; returns its data for DirectLightOptions::lightWeights.
const float* trackingWeights(ThreadContext& ctx, const LightDistanceSegment& seg, float t, const MediumPoint& mp);

}  // namespace vdbmarch
