// What happens where a path meets a surface, written once for camera paths,
// the reference tracer and photons: interfaces switch regions, diffuse
// surfaces bounce (cosine-sampled), smooth dielectrics reflect or refract by
// Fresnel. The shading-normal rule: the shading normal (smooth_normals)
// bends the direction; the geometric normal decides which side a ray is on,
// and wins when the shading normal would send the ray to the wrong side.
// With shading normals the scattering is not symmetric, so photons (which
// carry importance's adjoint) take Veach's correction (thesis, eq. 5.19).
#pragma once

#include "core/rng.h"
#include "scene/scene.h"

namespace vdbmarch {

enum class TransportMode { Radiance, Importance };  // camera paths; photons

struct SurfaceEvent {
    enum class Kind { Interface, Diffuse, Reflect, Refract } kind = Kind::Interface;
    Ray ray;                // the continuing ray, its origin offset to the side it leaves on
    int region = 0;         // the region it travels in
    Color weight{1, 1, 1};  // f cos / pdf (the diffuse albedo; Fresnel choices cancel)
    float pdf = 0;          // solid-angle pdf of a diffuse bounce (MIS); 0 for the delta events
    // The ray goes on unbent (an interface, or refraction through index-
    // matched glass): a shadow ray would have followed it.
    bool straight = false;
};

// The event at `hit` for a ray travelling along d in `region`; u: the three
// uniforms it may use (Fresnel choice, then the diffuse direction).
SurfaceEvent sampleSurfaceEvent(const Scene& scene, const SurfaceHit& hit, const Vec3& d, int region, const float u[3],
                                TransportMode mode);


// The two outcomes of a smooth dielectric (glass) event and the chance of
// the first: reflection with probability F (Fresnel), else refraction (or
// the reflection the geometric normal gives where the shading normal bends
// a refraction to the wrong side). sampleSurfaceEvent picks one by u[0];
// a camera path may follow both instead, weighted F and 1 - F
// (SplitDielectricEvents), which is the same expectation.
struct DielectricEvents {
    SurfaceEvent outcome[2];  // [0] with probability reflectProbability, [1] otherwise
    float reflectProbability = 0;
};
DielectricEvents dielectricEvents(const Scene& scene, const SurfaceHit& hit, const Vec3& d, int region,
                                  TransportMode mode);

// Camera paths follow both outcomes of their first this many glass events
// before any scattering event. A small light mirrored in glass is a
// highlight a thousand times the surroundings' brightness that a Fresnel
// choice of a few percent finds in only a few of a pixel's samples;
// following both outcomes removes the noise of that count
// (docs/benchmarks/history.md, "Glass highlights: both outcomes of a camera
// path's first glass event").
constexpr int SplitDielectricEvents = 1;

// Offset origin for a ray leaving a surface at p in direction d.
Vec3 offsetRayOrigin(const Scene& scene, const Vec3& p, const Vec3& n, const Vec3& d);

// Closest sphere light hit in (tMin, tMax); returns the light index or -1.
int intersectSphereLights(const Scene& scene, const Ray& r, float tMin, float tMax, float& t);

// Sphere lights count from this far along a ray (times the scene scale), on
// path and shadow rays alike: a photon leaving a light's surface never hits
// that light again.
constexpr float SphereLightRayOffset = 1e-4f;

// What a path ray meets first: the closest surface, and a sphere light before
// it. Every path loop (camera and continuation paths, the marchers' camera
// rays, photons, the AOVs' first event) starts each segment here, so they
// agree on what a ray hits.
struct RaySegment {
    SurfaceHit surface;
    bool hitSurface = false;
    int light = -1;         // the sphere light hit before any surface, or -1
    float tEnd = Infinity;  // the light's hit, else the surface's, else tMax
    // Nothing was looked for beyond a finite tMax: the ray goes on past tEnd.
    bool cut = false;
};
RaySegment nextRaySegment(const Scene& scene, const Ray& r, float tMax = Infinity);

}  // namespace vdbmarch
