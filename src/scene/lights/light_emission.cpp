#include "scene/lights/light_emission.h"

#include <cmath>

namespace vdbmarch {

bool finiteBox(const BBox& b) { return !b.empty() && isFinite(b.lo) && isFinite(b.hi); }

bool targetEmpty(const PhotonTarget& t) { return !t.unbounded && t.bounds.empty(); }

bool targetSphere(const PhotonTarget& t, Vec3& center, float& radius) {
    if (!finiteBox(t.bounds)) return false;
    center = t.bounds.center();
    radius = 0.5f * length(t.bounds.extent()) * 1.01f;
    return std::isfinite(radius);
}

bool targetCone(const PhotonTarget& t, const Vec3& p, TargetCone& c) {
    Vec3 center;
    float radius;
    if (t.unbounded || !targetSphere(t, center, radius)) return false;
    // Double: distances may square past float range.
    Vec3 to = center - p;
    double d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += double(to[a]) * to[a];
    double r2 = double(radius) * radius;
    if (!(d2 > r2)) return false;
    c.axis = to / float(std::sqrt(d2));
    double sin2 = r2 / d2;
    c.oneMinusCos = float(sin2 / (1 + std::sqrt(1 - sin2)));
    c.halfAngle = std::asin(std::sqrt(sin2));
    return true;
}

Vec3 coneDirection(const Vec3& axis, float t, float u) {
    Vec3 s, b;
    coordinateSystem(axis, s, b);
    float sinTheta = safeSqrt(t * (2 - t)), phi = 2 * Pi * u;
    return s * (sinTheta * std::cos(phi)) + b * (sinTheta * std::sin(phi)) + axis * (1 - t);
}

Vec3 unitOr(const Vec3& v, const Vec3& fallback) {
    float len = length(v);
    return len > 0 && std::isfinite(len) ? v / len : fallback;
}

Vec3 ConeEmission::sampleCone(float u1, float u2, float& oneMinusCos) const {
    oneMinusCos = u1 * mOneMinusCos;
    return coneDirection(mAxis, oneMinusCos, u2);
}

bool DiscEmission::aim(const Color& irradiance, const Vec3& dir, const PhotonTarget& target) {
    Vec3 center;
    float radius;
    if (targetEmpty(target) || isBlack(irradiance) || !targetSphere(target, center, radius) || !(radius > 0))
        return false;
    mOrigin = center;
    mAxis = dir;
    mRadius = radius;
    mDiscDist = 1.01f * radius;
    mWeight = irradiance * (Pi * radius * radius);
    mPower = mWeight;
    return isFinite(mPower);
}

Vec3 DiscEmission::sampleDisc(const Vec3& dir, float u1, float u2) const {
    Vec3 s, t;
    coordinateSystem(dir, s, t);
    float r = mRadius * std::sqrt(u1), phi = 2 * Pi * u2;
    return mOrigin - dir * mDiscDist + s * (r * std::cos(phi)) + t * (r * std::sin(phi));
}

bool DiscEmission::sample(const float u[4], EmittedPhoton& out) const {
    startPhoton(out);
    out.ray.o = sampleDisc(mAxis, u[0], u[1]);
    out.power = mWeight;
    return true;
}

}  // namespace vdbmarch
