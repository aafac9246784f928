#include "strategies/glass_splitting.h"

#include "transport/transmittance.h"

namespace vdbmarch {

PathSurfaceEvent pathSurfaceEvent(ThreadContext& ctx, const SurfaceHit& h, const Vec3& d, int region, const float u[3],
                                  bool split, bool seenFromCamera, Rng& rng) {
    const Scene& scene = ctx.scene;
    PathSurfaceEvent out;
    if (scene.surfaces[size_t(h.surface)].material.type != MaterialDesc::Type::Dielectric) {
        out.event = sampleSurfaceEvent(scene, h, d, region, u, TransportMode::Radiance);
        out.weight = out.event.weight;
        return out;
    }
    const DielectricEvents both = dielectricEvents(scene, h, d, region, TransportMode::Radiance);
    const float F = both.reflectProbability;
    const bool reflect = u[0] < F;
    out.event = both.outcome[reflect ? 0 : 1];
    out.weight = out.event.weight;
    if (!(F > 0 && F < 1) || !scene.desc.experiments.glassSplitting) return out;
    const SurfaceEvent& mirror = both.outcome[0];
    if (split) {
        out.split = true;
        out.mirror = mirror;
        out.mirrorWeight = mirror.weight * F;
        out.event = both.outcome[1];
        out.weight = out.event.weight * (1 - F);
        return out;
    }
    if (!scene.hasSphereLights && scene.environment.isBlack()) return out;
    // What the reflection's first segment ends on.
    const RaySegment seg = nextRaySegment(scene, mirror.ray);
    Color Le(0);
    if (seg.light >= 0)
        Le = scene.lights[size_t(seg.light)].emittedRadiance();
    else if (!seg.hitSurface)
        Le = seenFromCamera ? scene.environment.radianceSeen(mirror.ray.d) : scene.environment.radiance(mirror.ray.d);
    if (isBlack(Le)) return out;
    if (scene.regions[size_t(mirror.region)].media.empty()) {
        // Nothing but that light on the way: the reflection is done.
        out.light = mirror.weight * F * Le;
        if (seg.light < 0) out.backgroundSeen = average(mirror.weight) * F;
        out.event = both.outcome[1];
        out.weight = out.event.weight * (1 - F);
        return out;
    }
    out.light = mirror.weight * F * Le *
                regionTransmittance(ctx, mirror.region, mirror.ray, seg.tEnd, rng, TransmittanceEstimator::UnbiasedMarching);
    out.mirrorCounted = reflect;
    return out;
}

}  // namespace vdbmarch
