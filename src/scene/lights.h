// Light sources for next-event estimation. A sample gives the direction to
// the light, the distance to it, and the incident quantity: irradiance (W/m^2
// at the point, perpendicular to wi) for delta lights, radiance / pdf for area
// lights; either way in-scattered radiance is sigma_s * phase * L * T.
#pragma once

#include "core/math.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

// A spot light's falloff, written once for next-event estimation and photon
// emission: 1 inside the inner cone, a smoothstep to 0 at the cone's edge.
// In t = 1 - cos of the angle to the spot axis, with omcCone = 1 - cosCone
// and omcFalloff = 1 - cosFalloffStart (both exact in float), so that
// hair-thin cones keep their shape. omcFalloff >= omcCone: hard edge.
template <typename T>
T spotFalloff(T t, T omcCone, T omcFalloff) {
    if (t >= omcCone) return 0;
    if (t > omcFalloff) {
        T s = (omcCone - t) / (omcCone - omcFalloff);
        return s * s * (3 - 2 * s);  // smoothstep
    }
    return 1;
}

struct LightSample {
    Vec3 wi;     // unit, from the shaded point towards the light
    float dist;  // distance to the light along wi (Infinity: directional)
    Color L;
    float pdf = 0;  // solid-angle pdf of wi for area lights; 0 for delta lights
};

class Light {
public:
    explicit Light(const LightDesc& d);
    // False when the light cannot illuminate x (outside a spot cone, beside a
    // collimated quad, inside a sphere light).
    bool sample(const Vec3& x, float u1, float u2, LightSample& s) const;
    // The solid-angle density with which sample() at x draws a direction
    // that hits the light: uniform over the cone a sphere light subtends,
    // so the same for every such direction. 0 for delta lights and where
    // sample() cannot draw (inside a sphere light). The path loops weigh a
    // path's own light hits against next-event estimation by it (MIS).
    float directionPdf(const Vec3& x) const;
    bool isDelta() const { return mDesc.type != LightDesc::Type::Sphere; }
    bool isSphere() const { return mDesc.type == LightDesc::Type::Sphere; }
    // A point or spot light: its irradiance grows as 1/d^2 close to it, so
    // next-event estimation at scattering vertices around it has unbounded variance.
    bool isPointLike() const { return mDesc.type == LightDesc::Type::Point || mDesc.type == LightDesc::Type::Spot; }
    // The part [t0, t1] of the ray r (t >= 0) that the light can reach: a
    // spot's cone (the hull of its two pieces when the cone is wider than a
    // hemisphere), all of the ray for other lights. False when the ray never
    // enters the light's reach. Distance sampling towards the light only
    // draws points there.
    bool reachInterval(const Ray& r, float& t0, float& t1) const;
    // Sphere lights only: nearest hit in (tMin, tMax).
    bool intersect(const Ray& r, float tMin, float tMax, float& t) const;
    // Radiance leaving a sphere light's surface: power / (4 pi^2 r^2).
    Color emittedRadiance() const { return mRadiance; }
    const LightDesc& desc() const { return mDesc; }

private:
    LightDesc mDesc;
    Color mRadiance;
    float mCosCone = -1;                    // spot cone (reachInterval)
    float mOmcCone = 2, mOmcFalloffStart = 2;  // 1 - the cone's and falloff start's cosines (spotFalloff)
    Vec3 mQuadNormal, mDualU, mDualV;  // collimated quad plane and dual basis
};

}  // namespace vdbmarch
