#include "transport/first_event.h"

#include "transport/media_point.h"
#include "transport/surface_event.h"
#include "transport/tracking.h"

namespace vdbmarch {

FirstEvent traceFirstEvent(ThreadContext& ctx, const Ray& cameraRay, Rng& rng) {
    const Scene& scene = ctx.scene;
    FirstEvent out;
    // Chromatic extinction: the free flight of one channel picked uniformly,
    // so the event density is the channels' average (as the reference's).
    const int channel = hasChromaticExtinction(scene) ? std::min(2, int(rng.uniform() * 3)) : -1;
    auto seen = [&](const Vec3& p) {
        if (!out.hasDepth) out.depthPoint = p;
        out.hasDepth = true;
    };
    Ray ray = cameraRay;
    int region = regionAtRayStart(scene, ray);
    Color beta(1);
    MediumPoint mp;
    for (int bounce = 0; bounce <= scene.desc.render.maxSurfaceBounces; ++bounce) {
        const RaySegment seg = nextRaySegment(scene, ray);
        const SurfaceHit& h = seg.surface;
        const bool hit = seg.hitSurface;
        const int light = seg.light;
        const float tEnd = seg.tEnd;
        bool collided = false;
        deltaTrack(ctx, region, ray, tEnd, channel, rng, [&](const Vec3& x, float sigmaMaj) {
            evalMedia(ctx, region, x, mp);
            if (rng.uniform() * sigmaMaj >= trackedOrAverage(mp.sigma_t, channel)) return true;  // null
            collided = true;
            seen(x);
            for (int c = 0; c < 3; ++c)
                out.albedo[c] = beta[c] * (mp.sigma_t[c] > 0 ? mp.sigma_s[c] / mp.sigma_t[c] : 0.f);
            out.normal = -ray.d;
            return false;
        });
        if (collided) return out;
        if (light >= 0) {
            seen(ray.at(tEnd));
            return out;
        }
        if (!hit) return out;
        const float u[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
        const SurfaceEvent e = sampleSurfaceEvent(scene, h, ray.d, region, u, TransportMode::Radiance);
        if (!e.straight) seen(h.p);  // interfaces and index-matched glass are invisible
        if (e.kind == SurfaceEvent::Kind::Diffuse) {
            out.albedo = beta * scene.surfaces[size_t(h.surface)].material.albedo;
            out.normal = dot(h.ns, ray.d) > 0 ? -h.ns : h.ns;
            return out;
        }
        beta *= e.weight;  // Fresnel choices: the blend of both sides on average
        ray = e.ray;
        region = e.region;
    }
    return out;
}

}  // namespace vdbmarch
