// The one radiance-path loop: the reference method's camera paths, the
// marchers' continuation estimate of L_i (paths that start at a march
// sample), the marchers' camera paths and the feature AOVs' first-event
// paths (paths/first_event.h):
//  - media crossed by free flights of delta tracking against local majorants
//    (homogeneous media: exact exponential sampling), emission of eq. 1
//    collected at every tentative collision (sigma_a L_e / sigma_maj),
//    absorption / scattering / null chosen by their ratios; or, for the
//    marchers' camera paths, marched segment by segment (SegmentMarch: eq. 3
//    by quadrature, L_i at march samples), the path going on at the
//    segment's end;
//  - the render's sampling strategies (strategies/strategy.h), iterated in
//    the set's order: distance samples along each segment, directions at
//    each vertex, connections through specular surfaces;
//  - next-event estimation to every light at every scattering vertex with
//    unbiased ray-marching transmittance; sphere lights are also hit by the
//    path and the strategies meet by the power heuristic;
//  - the shared surface event, Russian roulette (PathOptions); max_depth
//    counts scattering events (media and diffuse surfaces).
// Media whose extinction differs between RGB channels are tracked with
// spectral MIS from a hero channel (PathState::spectral, HeroChannel in
// transport/tracking.h): one path carries all three channels, each weighed
// by the balance heuristic over the channels' densities.
#pragma once

#include <memory>

#include "core/rng.h"
#include "strategies/strategy_set.h"
#include "transport/direct_light.h"
#include "transport/roulette.h"
#include "transport/thread_context.h"

namespace vdbmarch {

// Light a path cannot find, estimated by a layer above this one and added
// once, at a path's first medium vertex: the caustics of delta lights through
// refracting glass, from the photons (estimators/reference_tracer.cpp). Its
// value at x is the whole in-scattered radiance of that light towards wo,
// every later scattering included, so the path's later vertices leave it out.
class InScatteredLight {
public:
    virtual ~InScatteredLight() = default;
    virtual Color at(const Vec3& x, int region, const Vec3& wo, const PhaseMixture& phase) const = 0;
};

// How a path crosses the media of a segment when it does not track them:
// a ray marcher integrates emission and in-scattered light along [0, tEnd)
// and attenuates the throughput, and the path goes on from tEnd
// (estimators/segment_marcher.h). March samples are scattering events
// number depth + 1: past max_depth a march adds emission only.
class SegmentMarch {
public:
    virtual ~SegmentMarch() = default;
    // Adds to L, attenuates beta; false when roulette ended the path.
    virtual bool march(ThreadContext& ctx, int region, const Ray& ray, float tEnd, int depth, Rng& rng, Color& L,
                       Color& beta) const = 0;
};

// Where a path stands when the loop takes it over.
struct PathState {
    int depth = 0;           // scattering events so far
    int surfaceBounces = 0;  // surfaces met (render.max_surface_bounces)
    bool specular = true;    // the last direction was not sampled from a density (no MIS)
    float lastPdf = 0;       // solid-angle pdf of that direction
    Vec3 lastPoint{0, 0, 0};  // where it was sampled
    Vec3 lastDir{0, 0, 1};    // the direction sampled there
    // Roulette judges the path by beta x rouletteScale: the throughput it
    // would carry had every vertex sampled f alone (scaleRoulette).
    float rouletteScale = 1;
    // Connection strategies made connections at lastPoint, and the specular
    // events since: a light the path hits through them weighs against those.
    bool connectedAtLast = false;
    SpecularChain chain;
    int glassSplits = 0;  // glass events whose two outcomes the path followed (SplitDielectricEvents)
    // The light or background the last glass reflection's ray meets first
    // was counted at the glass (glass_splitting.h): not again.
    bool mirrorCounted = false;
    // PathOptions::firstVertexLight is still to be added.
    bool firstVertexPending = true;
    // Caustic photons gave the light that reaches this path's vertices
    // through bending glass (added at its first medium vertex, or at the
    // march sample it starts from): where Scene::sphereLightCausticPhotons
    // holds, the sphere lights it meets through such glass are left out.
    bool causticPhotonsGathered = false;
    // Spectral MIS in chromatic media: the hero channel (< 0 for grey
    // extinction) and the channels' path densities (startingHero).
    HeroChannel spectral;
};


// The path's first event, for the feature AOVs (render.aovs depth, albedo,
// normal; docs/aovs.md): its first real collision in a medium or its first
// visible surface, glass followed to the first non-specular event for
// albedo and normal, as OpenImageDenoise recommends.
struct FirstEvent {
    bool hasDepth = false;  // the path met a medium, a surface or a light
    Vec3 depthPoint{0, 0, 0};  // where (before any bend)
    // Throughput to the first non-specular event times its albedo (sigma_s /
    // sigma_t in a medium, the diffuse albedo on a surface); zero when the
    // path leaves the scene or ends on a light first.
    Color albedo{0};
    // Unit direction back along the path at a medium event, the shading
    // normal facing the arriving ray on a diffuse surface, zero otherwise.
    Vec3 normal{0, 0, 0};
    bool done = false;  // the first non-specular event was met
};

// What a path brings back: a camera path's result (Estimator::radiance) and a
// continuation's alike.
struct PathRadiance {
    Color L;                  // radiance arriving at ray.o along -ray.d
    // The fraction of the background seen with no scattering event, straight
    // or through glass (camera paths; alpha = 1 - this).
    float transmittance = 0;
    // The part of L after at most one scattering event in all (counting the
    // state's depth; emission and unscattered light included): the "direct"
    // AOV (docs/aovs.md). Zero for paths that start at depth >= 2; marchers
    // fill it only when render.aovs asks for "direct" or "indirect".
    Color direct;
    // The part of L emitted by media and lights and seen with no scattering
    // event (straight, or through glass): sharp and nearly noise-free where
    // the estimator integrates emission smoothly, so the denoiser takes it
    // apart from the scattered light (docs/denoise.md, "Emission apart").
    Color emitted;
    FirstEvent first;  // of a tracked path (marched paths: at surfaces only)
};

// What the estimator above sets once for all its paths.
struct PathOptions {
    // Next-event estimation and distance sampling leave point and spot
    // lights out: photons carry their multiply scattered light (near them
    // next-event estimation has unbounded variance).
    bool pointLightsByPhotons = false;
    // Added at a path's first medium vertex (null: nothing).
    const InScatteredLight* firstVertexLight = nullptr;
    // Media crossed by this march (null: delta tracking).
    const SegmentMarch* march = nullptr;
    // Russian roulette after scattering events from this depth on, by this
    // threshold (transport/roulette.h).
    int rouletteMinDepth = RouletteMinDepth;
    float rouletteThreshold = ScatterRouletteThreshold;
    // Scattering events allowed (-1: render.max_depth).
    int maxDepth = -1;
};

class PathTracer {
public:
    PathTracer(const Scene& scene, std::shared_ptr<const StrategySet> strategies, PathOptions options = {});

    // The radiance the path ray (in `region`) brings back, from `state`.
    PathRadiance trace(ThreadContext& ctx, Ray ray, int region, Rng& rng, PathState state) const;

    const Scene& scene() const { return mScene; }
    const StrategySet& strategies() const { return *mStrategies; }
    const PathOptions& options() const { return mOptions; }
    // The first direction strategy that takes vertex v (null: f's own sampling).
    const DirectionStrategy* attachDirections(ThreadContext& ctx, int region, ScatterVertex& v) const;

private:
    friend class PathWalk;
    // trace(), from throughput beta.
    PathRadiance walk(ThreadContext& ctx, Ray ray, int region, Rng& rng, PathState state,
                      const Color& beta) const;
    const Scene& mScene;
    std::shared_ptr<const StrategySet> mStrategies;
    PathOptions mOptions;
};

// A direction wi of density pdf drawn at vertex v by a sampler other than
// f's own (a direction strategy): scales the state's roulette to what f's
// own sampling would have left the throughput (PathState::rouletteScale).
void scaleRoulette(PathState& st, const ScatterVertex& v, const Vec3& wi, float pdf);

}  // namespace vdbmarch
