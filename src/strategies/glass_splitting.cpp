#include "strategies/glass_splitting.h"

namespace vdbmarch {

PathSurfaceEvent materialSurfaceEvent(const Scene& scene, const SurfaceHit& h, const Vec3& d, int region,
                                      const float u[3]) {
    PathSurfaceEvent out;
    if (scene.surfaces[size_t(h.surface)].material.type != MaterialDesc::Type::Dielectric) {
        out.event = sampleSurfaceEvent(scene, h, d, region, u, TransportMode::Radiance);
    } else {
        const DielectricEvents both = dielectricEvents(scene, h, d, region, TransportMode::Radiance);
        out.event = both.outcome[u[0] < both.reflectProbability ? 0 : 1];
    }
    out.weight = out.event.weight;
    return out;
}

bool GlassSplitting::sample(ThreadContext& ctx, const SurfaceHit& h, const Vec3& d, int region, const float u[3],
                            const SurfaceRequest& request, Rng& rng, PathSurfaceEvent& out) const {
    const Scene& scene = ctx.scene;
    if (scene.surfaces[size_t(h.surface)].material.type != MaterialDesc::Type::Dielectric) return false;
    const DielectricEvents both = dielectricEvents(scene, h, d, region, TransportMode::Radiance);
    const float F = both.reflectProbability;
    const bool reflect = u[0] < F;
    out.event = both.outcome[reflect ? 0 : 1];
    out.weight = out.event.weight;
    if (!(F > 0 && F < 1)) return true;
    const SurfaceEvent& mirror = both.outcome[0];
    if (request.split) {
        out.split = true;
        out.mirror = mirror;
        out.mirrorWeight = mirror.weight * F;
        out.event = both.outcome[1];
        out.weight = out.event.weight * (1 - F);
        return true;
    }
    if (!scene.hasSphereLights && scene.environment.isBlack()) return true;
    // What the reflection's first segment ends on.
    const RaySegment seg = nextRaySegment(scene, mirror.ray);
    Color Le(0);
    if (seg.light >= 0 && !request.sphereLightsByPhotons)
        Le = scene.lights[size_t(seg.light)].emittedRadiance();
    else if (!seg.hitSurface)
        Le = request.seenFromCamera ? scene.environment.radianceSeen(mirror.ray.d)
                                    : scene.environment.radiance(mirror.ray.d);
    if (isBlack(Le)) return true;
    if (scene.regions[size_t(mirror.region)].media.empty()) {
        // Nothing but that light on the way: the reflection is done.
        out.light = mirror.weight * F * Le;
        if (seg.light < 0) out.backgroundSeen = average(mirror.weight) * F;
        out.event = both.outcome[1];
        out.weight = out.event.weight * (1 - F);
        return true;
    }
    out.light = mirror.weight * F * Le *
                regionTransmittance(ctx, mirror.region, mirror.ray, seg.tEnd, rng, TransmittanceEstimator::UnbiasedMarching);
    out.mirrorCounted = reflect;
    return true;
}

}  // namespace vdbmarch
