#include "transport/surface_event.h"

#include <cmath>

#include "core/sampling.h"

namespace vdbmarch {

Vec3 offsetRayOrigin(const Scene& scene, const Vec3& p, const Vec3& n, const Vec3& d) {
    float eps = 1e-5f * std::max(scene.sceneScale, maxComponent(max(p, -p)));
    return p + (dot(n, d) > 0 ? n : -n) * eps;
}

int intersectSphereLights(const Scene& scene, const Ray& r, float tMin, float tMax, float& t) {
    if (!scene.hasSphereLights) return -1;
    int best = -1;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        float ti;
        if (scene.lights[i].intersect(r, tMin, tMax, ti)) {
            tMax = ti;
            t = ti;
            best = int(i);
        }
    }
    return best;
}

RaySegment nextRaySegment(const Scene& scene, const Ray& r, float tMax) {
    RaySegment seg;
    seg.hitSurface = scene.surfaceSet->intersect(r, 0.f, tMax, seg.surface);
    const float tSurface = seg.hitSurface ? seg.surface.t : tMax;
    float tLight = Infinity;
    seg.light = intersectSphereLights(scene, r, SphereLightRayOffset * scene.sceneScale, tSurface, tLight);
    seg.tEnd = seg.light >= 0 ? tLight : tSurface;
    seg.cut = !seg.hitSurface && seg.light < 0 && std::isfinite(tMax);
    return seg;
}

namespace {

// What both outcomes of a smooth dielectric event share: the normals, the
// relative index and the Fresnel reflectance F0 about the shading normal
// (the chance of the reflection).
struct GlassHit {
    int across;  // the region beyond the surface
    Vec3 ng;     // geometric normal on the arriving side
    Vec3 n0;     // the shading normal on that side (ng where it faces away from the ray)
    float ior, eta, F0, cosT0;
};

GlassHit glassHit(const Scene& scene, const SurfaceHit& h, const Vec3& d) {
    const SurfaceInfo& s = scene.surfaces[size_t(h.surface)];
    const bool entering = dot(d, h.n) < 0;
    GlassHit g;
    g.across = entering ? s.interiorRegion : s.exteriorRegion;
    g.ng = entering ? h.n : -h.n;
    g.ior = s.material.ior;
    g.eta = entering ? g.ior : 1 / g.ior;
    g.n0 = dot(h.ns, g.ng) > 0 ? h.ns : -h.ns;
    if (-dot(d, g.n0) <= 0) g.n0 = g.ng;  // the shading normal faces away from the ray
    g.F0 = fresnelDielectric(-dot(d, g.n0), g.eta, &g.cosT0);
    return g;
}

// Outcome `branch` of the event (0: the reflection, chance F0; 1: the
// refraction). Smooth Fresnel: a path that picks one by its chance has
// the weights F/F and (1-F)/(1-F), which cancel.
SurfaceEvent glassOutcome(const Scene& scene, const SurfaceHit& h, const Vec3& d, int region, TransportMode mode,
                          const GlassHit& g, int branch) {
    const Vec3& ng = g.ng;
    const float eta = g.eta;
    Vec3 n = g.n0;
    float cosI = -dot(d, n), cosT = g.cosT0;
    bool reflect = branch == 0;
    Vec3 wo = reflect ? d + n * (2 * cosI) : d / eta + n * (cosI / eta - cosT);
    if (reflect ? dot(wo, ng) <= 0 : dot(wo, ng) >= 0) {
        // The shading normal sent the ray to the wrong side of the true
        // surface: redo the event with the geometric one.
        n = ng;
        cosI = -dot(d, n);
        const float F = fresnelDielectric(cosI, eta, &cosT);
        reflect = reflect || F >= 1;
        wo = reflect ? d + n * (2 * cosI) : d / eta + n * (cosI / eta - cosT);
    }
    wo = normalize(wo);
    SurfaceEvent e;
    e.kind = reflect ? SurfaceEvent::Kind::Reflect : SurfaceEvent::Kind::Refract;
    e.straight = !reflect && g.ior == 1.f;
    e.region = reflect ? region : g.across;
    if (mode == TransportMode::Importance) {
        float w = 1;
        if (n != ng) {
            // Adjoint of the shading-normal BSDF: |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|),
            // wo towards where the photon came from, wi where it goes.
            const float num = std::fabs(dot(d, n)) * std::fabs(dot(wo, ng));
            const float den = std::fabs(dot(d, ng)) * std::fabs(dot(wo, n));
            w = den > 0 ? num / den : 0.f;
        }
        // Camera paths carry basic radiance L / n^2, which refraction leaves
        // unchanged (their weight is 1 both ways); photons carry flux, so
        // the radiance they stand for is divided by (eta_t / eta_i)^2 at
        // every refraction (Veach's thesis, 5.2).
        if (!reflect) w /= eta * eta;
        e.weight = Color(w);
    }
    e.ray = Ray{offsetRayOrigin(scene, h.p, h.n, wo), wo};
    return e;
}

}  // namespace

SurfaceEvent sampleSurfaceEvent(const Scene& scene, const SurfaceHit& h, const Vec3& d, int region, const float u[3],
                                TransportMode mode) {
    const SurfaceInfo& s = scene.surfaces[size_t(h.surface)];
    const bool entering = dot(d, h.n) < 0;
    const int across = entering ? s.interiorRegion : s.exteriorRegion;
    const Vec3 ng = entering ? h.n : -h.n;  // geometric normal on the arriving side
    SurfaceEvent e;
    switch (s.material.type) {
        case MaterialDesc::Type::Interface:
            e.kind = SurfaceEvent::Kind::Interface;
            e.straight = true;
            e.region = across;
            e.ray = Ray{offsetRayOrigin(scene, h.p, h.n, d), d};
            return e;
        case MaterialDesc::Type::Diffuse: {
            // Lambertian on the arriving side: cosine sampling, so f cos / pdf = albedo.
            const float cosT = std::sqrt(1 - u[1]);
            const Vec3 wi = directionAround(ng, cosT, u[2]);
            e.kind = SurfaceEvent::Kind::Diffuse;
            e.region = region;
            e.weight = s.material.albedo;
            e.pdf = cosT * InvPi;
            e.ray = Ray{offsetRayOrigin(scene, h.p, ng, wi), wi};
            return e;
        }
        case MaterialDesc::Type::Dielectric:
            break;
    }
    const GlassHit g = glassHit(scene, h, d);
    return glassOutcome(scene, h, d, region, mode, g, u[0] < g.F0 ? 0 : 1);
}

DielectricEvents dielectricEvents(const Scene& scene, const SurfaceHit& h, const Vec3& d, int region,
                                  TransportMode mode) {
    const GlassHit g = glassHit(scene, h, d);
    DielectricEvents out;
    out.reflectProbability = g.F0;
    for (int branch = 0; branch < 2; ++branch) out.outcome[branch] = glassOutcome(scene, h, d, region, mode, g, branch);
    return out;
}

}  // namespace vdbmarch
