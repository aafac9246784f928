// Distance sampling towards the folds of point and parallel lights' caustics
// behind glass spheres.
//
// A point, spot or directional light seen through a glass ball reaches a
// medium point x only along the connections of sphere_caustics.h, each
// bringing I T / G. Where two connections merge, on the fold of the caustic
// (scene.h's CausticFold: a surface of revolution about the light's axis through the
// ball), G goes to 0 as sqrt(distance), so the light scattered at x grows
// as 1 / sqrt(d): integrable along a ray, but a position drawn by a density
// that stays bounded there (the histogram, transmittance, equiangular
// sampling) has weights with a tail as heavy as P(w > v) ~ 1 / v^2, the
// variance of a log-divergent integral: rare draws near a fold show as
// fireflies.
//
// So a segment that crosses a fold also draws positions near each crossing
// t_f with the density 1 / (4 sqrt(W |t - t_f|)) over [t_f - W, t_f + W]
// (FoldSampler), whose weights stay bounded where the light grows as
// 1 / sqrt(|t - t_f|), down to the float next to t_f. At t_f itself the
// light is bounded only by how close that float point happens to lie to
// the fold, so the folds' draws step off it, and only the other samplers'
// rare draws (about 1e-6 of those near a crossing) land there. The crossings come from the fold's polyline: each of
// its edges sweeps a cone's frustum about the axis, which a ray meets at the
// roots of a quadratic.
#pragma once

#include <vector>

#include "scene/scene.h"
#include "strategies/strategy.h"

namespace vdbmarch {

// Crossings of one segment with the folds, and the density drawing
// positions near them (each crossing with equal odds).
class FoldSampler {
public:
    static constexpr int MaxCrossings = 8;

    void clear() { mCount = 0; }
    bool empty() const { return mCount == 0; }
    int count() const { return mCount; }
    float crossing(int i) const { return mT[i]; }
    // Adds a crossing at t with half-width w (kept sorted; at most MaxCrossings).
    void add(float t, float w);

    float sample(float u) const;
    double pdf(float t) const;
    // t, or the next float up where t is exactly a crossing: what every
    // other sampler's draw becomes there. At the float point t_f the light
    // is bounded only by how far that point lies from the fold, which can be
    // far below a float step (values of 1e6-1e7 where its neighbourhood
    // holds about 10); the fold density leaves t_f too (sample()).
    float offCrossing(float t) const;

private:
    float mT[MaxCrossings] = {}, mW[MaxCrossings] = {};
    int mCount = 0;
};

// The folds of the scene's point-like and parallel lights through its glass
// spheres (experiments.sphere_caustics, Scene::deltaLightCaustics), traced
// once per render, and the distance strategy drawing positions near where a
// segment crosses them; the tracking collisions keep the complementary
// share of those lights' connections (CollisionWeights::connectionWeight).
class CausticFolds final : public DistanceStrategy {
public:
    CausticFolds(const Scene& scene, size_t slot);
    bool empty() const { return mSurfaces.empty(); }

    // The crossings of the segment [0, tEnd) of `ray` in `region` with the
    // folds of the spheres around it, into `out`; false when there are none.
    bool crossings(int region, const Ray& ray, float tEnd, FoldSampler& out) const;

    bool prepare(ThreadContext& ctx, const PathSegment& seg) const override;
    Color sample(ThreadContext& ctx, const PathSegment& seg, Rng& rng) const override;
    float collisionAt(ThreadContext& ctx, float t) const override { return sampler(ctx).offCrossing(t); }
    void weighCollision(ThreadContext& ctx, const PathSegment& seg, float t, const MediumPoint& mp,
                        CollisionWeights& w) const override;

private:
    struct Scratch final : ThreadContextExtension {
        FoldSampler folds;  // the prepared segment's crossings
    };
    FoldSampler& sampler(ThreadContext& ctx) const { return ctx.extensionAt<Scratch>(mSlot).folds; }

    struct Surface {
        int sphere = -1, light = -1;
        CausticFold fold;
        Vec3 boundCenter;
        float boundRadius = 0, halfWidth = 0;  // a bounding sphere; the density's half-width about a crossing
    };
    const Scene& mScene;
    const size_t mSlot;
    std::vector<Surface> mSurfaces;
};

// The crossings of ray o + t d (d unit), t in [t0, t1], with the surface of
// revolution of `fold`, the fold of light l through sphere s (up to `max`,
// in no order): found on the polyline, then moved onto the exact fold
// (causticFoldPoint); returns their number.
int foldCrossings(const GlassSphere& s, const Light& l, const CausticFold& fold, const Ray& ray, float t0, float t1,
                  float* out, int max);

}  // namespace vdbmarch
