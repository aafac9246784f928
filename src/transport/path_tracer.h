// The volumetric path tracer's loop, written once for the reference method
// (camera paths) and for the marchers' continuation estimate of L_i (paths
// that start at a march sample):
//  - free flights by delta tracking against local majorants (homogeneous
//    media: exact exponential sampling), emission of eq. 1 collected at every
//    tentative collision (sigma_a L_e / sigma_maj), absorption / scattering /
//    null chosen by their ratios;
//  - next-event estimation to every light at every scattering vertex with
//    unbiased ray-marching transmittance; sphere lights are also hit by the
//    path and the two strategies meet by the power heuristic;
//  - phase-mixture sampling, the shared surface event, Russian roulette
//    after RouletteMinDepth events; max_depth counts scattering events
//    (media and diffuse surfaces).
// Media whose extinction differs between RGB channels are tracked one
// channel per path (`channel` >= 0), which keeps every estimator unbiased;
// grey-extinction media share one path with RGB weights (channel < 0).
#pragma once

#include "core/rng.h"
#include "transport/direct_light.h"
#include "transport/roulette.h"
#include "transport/thread_context.h"

namespace vdbmarch {
struct PhaseMixture;

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
}

namespace vdbmarch {

// Where a path stands when the loop takes it over.
struct PathState {
    int depth = 0;           // scattering events so far
    bool specular = true;    // the last direction was not sampled from a density (no MIS)
    float lastPdf = 0;       // solid-angle pdf of that direction
    Vec3 lastPoint{0, 0, 0};  // where it was sampled
    // Next-event estimation leaves point and spot lights out (photons carry
    // their multiply scattered light: near them it has unbounded variance).
    bool pointLightsByPhotons = false;
    // Added at the next medium vertex, then cleared (InScatteredLight).
    const InScatteredLight* firstVertexLight = nullptr;
    // Roulette by throughput judges a path by beta x rouletteScale: the
    // throughput it would carry had every vertex sampled f alone. A
    // direction drawn towards a spot beam (beam_directions.h) carries the
    // small weight f / pdf because it
    // went where the light is, and roulette by beta alone ended most such
    // paths before their next segment found that light.
    float rouletteScale = 1;
    // Sphere caustic connections (sphere_caustics.h) were made at lastPoint,
    // and the refractions since then at one glass sphere: a sphere light
    // hit after one (across its surface) or two (in and out) takes the MIS
    // weight against them. -1 in lensSphere: none yet; lensRefractions < 0: another event
    // broke the pattern.
    bool causticsAtLast = false;
    Vec3 lastDir{0, 0, 1};  // the direction sampled at lastPoint
    int lensSphere = -1;
    int lensRefractions = 0;
    // Surfaces met (render.max_surface_bounces), and glass events whose two
    // outcomes the path followed both (SplitDielectricEvents).
    int surfaceBounces = 0;
    int glassSplits = 0;
    // The light or background the last glass reflection's ray meets first
    // was counted at the glass (mirroredLight in path_tracer.cpp): the path
    // that took that reflection must not count it again.
    bool mirrorCounted = false;
};

// What a path brings back: a camera path's result (Estimator::radiance) and a
// continuation's alike.
struct PathRadiance {
    Color L;                  // radiance arriving at ray.o along -ray.d
    float transmittance = 0;  // fraction of the background seen straight (camera paths; alpha = 1 - this)
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
};

// The radiance the path ray (in `region`) brings back, from `state`.
PathRadiance tracePath(ThreadContext& ctx, Ray ray, int region, int channel, Rng& rng, PathState state);

// A direction wi of density pdf drawn at vertex v by a sampler other than
// f's own (a beam mixture): scales the
// state's roulette to what f's own sampling would have left the throughput
// (PathState::rouletteScale).
void scaleRoulette(PathState& st, const ScatterVertex& v, const Vec3& wi, float pdf);

// True when some medium's extinction differs between channels.
bool hasChromaticExtinction(const Scene& scene);

// Tracking probabilities of the channel, or for grey extinction the channel
// average (sigma_a + sigma_s sums to sigma_t either way).
inline float trackedOrAverage(const Color& c, int channel) { return channel < 0 ? average(c) : c[channel]; }

}  // namespace vdbmarch
