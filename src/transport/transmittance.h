// Shadow rays: the walk across surfaces (interfaces and index-matched glass
// are crossed, anything else blocks) and the two transmittance estimators
// the estimators use along it.
#pragma once

#include <cmath>

#include "core/rng.h"
#include "transport/surface_event.h"
#include "transport/thread_context.h"

namespace vdbmarch {

// Walks a shadow ray from r.o over distance `dist` (Infinity: to the
// environment), starting in `region`: calls segment(region, ray, tEnd) for
// each piece between surfaces. Returns false when blocked (a surface that is
// not crossed, or a sphere light before `dist`) or when `segment` returned false.
template <typename Segment>
bool walkShadowRay(const Scene& scene, int region, Ray r, float dist, Segment&& segment) {
    float remaining = dist;
    for (int crossing = 0; crossing <= scene.desc.render.maxSurfaceBounces; ++crossing) {
        // A target sphere light sits at `remaining`; stop just short of it.
        float tLimit = std::isfinite(remaining) ? remaining * (1 - 1e-4f) : Infinity;
        SurfaceHit h;
        bool hit = scene.surfaceSet->intersect(r, 0.f, tLimit, h);
        float tLight;
        if (intersectSphereLights(scene, r, SphereLightRayOffset * scene.sceneScale, hit ? h.t : tLimit, tLight) >= 0) return false;
        if (!segment(region, r, hit ? h.t : remaining)) return false;
        if (!hit) return true;
        const SurfaceInfo& s = scene.surfaces[size_t(h.surface)];
        if (!crossedByShadowRays(s.material)) return false;
        region = dot(r.d, h.n) < 0 ? s.interiorRegion : s.exteriorRegion;
        r.o = offsetRayOrigin(scene, h.p, h.n, r.d);
        if (std::isfinite(remaining)) remaining -= h.t;
    }
    return false;
}

enum class TransmittanceEstimator {
    // exp(-tau) with tau integrated in uniform steps of render.shadow_step
    // from a random offset (the marchers: cheap, consistent as steps shrink).
    Stepped,
    // Residual ratio tracking against local density bounds: unbiased, each
    // estimate in [0, 1] (what a path's throughput may be multiplied by).
    RatioTracking,
    // Unbiased ray marching (Kettunen et al. 2021): the power series of
    // core/power_series.h over stratified optical-depth estimates. Unbiased
    // and nearly as quiet as Stepped; one estimate may be negative or above
    // 1, so it weighs light that ends there (next-event estimation), not a
    // path that goes on.
    UnbiasedMarching,
};

// Transmittance from p along the unit direction wi over `dist` (Infinity
// for directional lights and the environment), starting in `region`.
// Constant media integrate exactly with either estimator.
Color shadowTransmittance(ThreadContext& ctx, int region, const Vec3& p, const Vec3& wi, float dist, Rng& rng,
                          TransmittanceEstimator estimator);

// Transmittance along [0, tEnd) of ray r inside `region` (no surface in
// between); constant media exactly.
Color regionTransmittance(ThreadContext& ctx, int region, const Ray& r, float tEnd, Rng& rng,
                          TransmittanceEstimator estimator = TransmittanceEstimator::RatioTracking);

}  // namespace vdbmarch
