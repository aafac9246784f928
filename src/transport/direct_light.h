// Next-event estimation, written once for the marchers' L_i and the
// reference tracer: at a scattering point in a medium (phase mixture) or on
// a diffuse surface (albedo cos / pi), a sample of every light with its
// shadow-ray transmittance, the environment map as a light, and optionally
// one direction sampled by f towards the background.
#pragma once

#include "core/rng.h"
#include "transport/phase.h"
#include "transport/transmittance.h"

namespace vdbmarch {

// Where light is gathered: a medium point (phase != null) or a diffuse
// surface point (geometric normal n, albedo).
struct ScatterVertex {
    Vec3 p;
    Vec3 d;  // travel direction of the path arriving here (the light leaves along -d)
    const PhaseMixture* phase = nullptr;
    Vec3 n;  // surface only
    Color albedo{0, 0, 0};
    // The path's own direction density when it does not sample f alone (a
    // beam mixture, beam_directions.h): MIS weighs light samples against it.
    float (*pathPdf)(const void* sampler, const Vec3& wi) = nullptr;
    const void* pathSampler = nullptr;

    static ScatterVertex inMedium(const Vec3& p, const Vec3& d, const PhaseMixture& phase) {
        return {p, d, &phase, Vec3(0), Color(0)};
    }
    static ScatterVertex onSurface(const Vec3& p, const Vec3& d, const Vec3& n, const Color& albedo) {
        return {p, d, nullptr, n, albedo};
    }

    // Surface only: the normal on the side the path arrived from.
    Vec3 arrivalNormal() const { return dot(n, d) < 0 ? n : -n; }
    // Where shadow rays from here start: p, or off a surface on the
    // arrival side.
    Vec3 shadowOrigin(const Scene& scene) const;

    // f (phase, or albedo cos / pi) for light arriving from direction wi; 0
    // below a surface.
    Color f(const Vec3& wi) const;
    // Solid-angle pdf with which the path itself would sample wi (MIS).
    float pdf(const Vec3& wi) const;
    // Solid-angle pdf of sampling f itself (phase, or cosine on a surface).
    float fPdf(const Vec3& wi) const;
};

struct DirectLightOptions {
    TransmittanceEstimator transmittance = TransmittanceEstimator::Stepped;
    // The path goes on from here by sampling f, and counts the sphere lights
    // it hits: weight both strategies by the power heuristic.
    bool misWithPathHits = false;
    // The path does not go on: sample the background here (by f, and an
    // environment map by its texels too, the two weighed by MIS).
    bool sampleBackground = true;
    // Leave point and spot lights out: photons carry their light here.
    bool skipPointLights = false;
    // One weight per scene light multiplying its sample (the share of
    // distance sampling's MIS left to this vertex, light_distances.h); null:
    // all 1. A light of weight 0 casts no shadow ray.
    const float* lightWeights = nullptr;
    // >= 0: sample that light alone (no environment, no background).
    int onlyLight = -1;
    // Shadow-ray roulette by the phase value at medium vertices (the path
    // tracer, PhaseRouletteShare).
    bool phaseRoulette = false;
};

// Shadow-ray roulette by the phase value (DirectLightOptions::phaseRoulette).
// In a forward-scattering medium most light samples fall outside the lobe
// and carry little light, yet their shadow rays cost as much as the lobe's.
// A light sample whose phase value f is below the level PhaseRouletteShare x
// the phase's mean value (PhaseMixture::meanPhaseValue) casts its shadow ray
// with probability f / level and then counts as if f were the level:
// unbiased, bounded, and its survivors are no larger than the lobe's own
// samples. Levels at or below the isotropic value (g up to about 0.5)
// roulette nothing, and so do regions without a VDB medium, where a shadow
// ray is only an intersection and an exp. The share was tuned by
// measurement: docs/benchmarks/history.md, "Shadow-ray roulette by the phase
// value; a cheaper block walk".
constexpr float PhaseRouletteShare = 0.5f;

Color directLight(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng, const DirectLightOptions& options);

inline float powerHeuristic(float a, float b) {
    const float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.f;
}

}  // namespace vdbmarch
