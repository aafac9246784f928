#include "scene/lights.h"

#include <cmath>

#include "core/sampling.h"

namespace vdbmarch {

Light::Light(const LightDesc& d) : mDesc(d) {
    switch (d.type) {
        case LightDesc::Type::Sphere:
            mRadiance = d.power / (4 * Pi * Pi * d.radius * d.radius);
            break;
        case LightDesc::Type::Spot:
            mCosCone = std::cos(radians(d.coneDeg));
            mOmcCone = 1 - mCosCone;
            mOmcFalloffStart = 1 - std::cos(radians(d.coneDeg - d.falloffDeg));
            break;
        case LightDesc::Type::CollimatedQuad: {
            // Dual basis so a point's (a, b) in h = center + a u + b v comes
            // from two dot products even when u and v are not orthogonal.
            mQuadNormal = cross(d.u, d.v);
            float n2 = lengthSquared(mQuadNormal);
            mDualU = cross(d.v, mQuadNormal) / n2;
            mDualV = cross(mQuadNormal, d.u) / n2;
            break;
        }
        default:
            break;
    }
}

namespace {
// Direction and distance from x to a point source; false when x is on it.
bool towardsPoint(const Vec3& x, const Vec3& position, LightSample& s, float& d2) {
    Vec3 to = position - x;
    d2 = lengthSquared(to);
    if (!(d2 > 0)) return false;
    s.dist = std::sqrt(d2);
    s.wi = to / s.dist;
    return true;
}
}  // namespace

bool Light::sample(const Vec3& x, float u1, float u2, LightSample& s) const {
    float d2;
    switch (mDesc.type) {
        case LightDesc::Type::Point: {
            if (!towardsPoint(x, mDesc.position, s, d2)) return false;
            s.L = mDesc.intensity / d2;
            return true;
        }
        case LightDesc::Type::Spot: {
            if (!towardsPoint(x, mDesc.position, s, d2)) return false;
            const float falloff = spotFalloff(oneMinusCosTo(-s.wi, mDesc.direction), mOmcCone, mOmcFalloffStart);
            if (!(falloff > 0)) return false;
            s.L = mDesc.intensity * (falloff / d2);
            return true;
        }
        case LightDesc::Type::Directional:
            s.wi = -mDesc.direction;
            s.dist = Infinity;
            s.L = mDesc.irradiance;
            return true;
        case LightDesc::Type::CollimatedQuad: {
            // Follow the beam backwards to the emitting plane.
            float denom = dot(-mDesc.direction, mQuadNormal);
            float t = dot(mDesc.center - x, mQuadNormal) / denom;
            if (!(t > 0)) return false;
            Vec3 h = x - mDesc.direction * t - mDesc.center;
            float a = dot(h, mDualU), b = dot(h, mDualV);
            if (std::fabs(a) > 0.5f || std::fabs(b) > 0.5f) return false;
            s.wi = -mDesc.direction;
            s.dist = t;
            s.L = mDesc.irradiance;
            return true;
        }
        case LightDesc::Type::Sphere: {
            Vec3 to = mDesc.position - x;
            float d2 = lengthSquared(to), r2 = mDesc.radius * mDesc.radius;
            if (d2 <= r2 * 1.0001f) return false;
            float d = std::sqrt(d2);
            Vec3 axis = to / d;
            // Uniform sampling of the cone of directions that sees the sphere.
            float sin2Max = r2 / d2;
            float cosMax = safeSqrt(1 - sin2Max);
            if (sin2Max < 1e-6f) cosMax = 1 - 0.5f * sin2Max;  // keep 1 - cosMax accurate
            s.wi = sampleUniformCone(axis, cosMax, u1, u2);
            float b = dot(to, s.wi);
            float disc = b * b - (d2 - r2);
            s.dist = b - safeSqrt(disc);
            if (!(s.dist > 0)) s.dist = b;
            s.pdf = uniformConePdf(cosMax);
            s.L = mRadiance / s.pdf;
            return true;
        }
    }
    return false;
}

float Light::directionPdf(const Vec3& x) const {
    if (mDesc.type != LightDesc::Type::Sphere) return 0;
    const Vec3 to = mDesc.position - x;
    const float d2 = lengthSquared(to), r2 = mDesc.radius * mDesc.radius;
    if (d2 <= r2 * 1.0001f) return 0;
    const float sin2 = r2 / d2, cosMax = sin2 < 1e-6f ? 1 - 0.5f * sin2 : safeSqrt(1 - sin2);
    return uniformConePdf(cosMax);
}

bool Light::reachInterval(const Ray& r, float& t0, float& t1) const {
    t0 = 0;
    t1 = Infinity;
    if (mDesc.type != LightDesc::Type::Spot) return true;
    // Points x = o + t d inside the cone: cos(x - p, axis) > cos(cone). On
    // the cone's surface (both nappes) f(t) = (a.v + t a.d)^2 - c2 |v + t d|^2
    // vanishes (v = o - p, a the axis, c2 = cos^2): a quadratic whose roots
    // cut the ray into at most three pieces, each wholly in or out.
    const Vec3& a = mDesc.direction;
    const Vec3 v = r.o - mDesc.position;
    const double c = mCosCone, c2 = c * c;
    const double av = dot(a, v), ad = dot(a, r.d), vd = dot(v, r.d), vv = lengthSquared(v), dd = lengthSquared(r.d);
    const double A = ad * ad - c2 * dd, B = 2 * (av * ad - c2 * vd), C = av * av - c2 * vv;
    const bool quadratic = std::fabs(A) > 1e-12 * (std::fabs(B) + std::fabs(C) + 1e-30);
    // A cone narrower than a hemisphere is convex: the ray meets it in one
    // interval, which the roots and the signs of A and a.d give without
    // probing the pieces (the same set as the general walk below).
    if (c > 0.01 && quadratic) {
        const double disc = B * B - 4 * A * C;
        if (disc >= 0) {
            const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
            double r0 = q / A, r1 = q != 0 ? C / q : r0;
            if (r0 > r1) std::swap(r0, r1);
            double lo, hi;
            if (A < 0) {  // f > 0 between the roots, in one nappe: the lit one?
                if (!(av + 0.5 * (r0 + r1) * ad > 0)) return false;
                lo = r0;
                hi = r1;
            } else if (ad > 0) {  // f > 0 outside the roots; the lit nappe ahead
                lo = r1;
                hi = Infinity;
            } else {  // the lit nappe behind
                lo = -Infinity;
                hi = r0;
            }
            lo = std::max(lo, 0.0);
            if (!(hi > lo)) return false;
            t0 = float(lo);
            t1 = std::isinf(hi) ? Infinity : float(hi);
            return true;
        }
        if (A < 0) return false;  // f < 0 everywhere: outside both nappes
    }
    double cuts[4];
    int n = 0;
    cuts[n++] = 0;
    if (quadratic) {
        const double disc = B * B - 4 * A * C;
        if (disc >= 0) {
            const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
            double r0 = q / A, r1 = q != 0 ? C / q : r0;
            if (r0 > r1) std::swap(r0, r1);
            if (r0 > 0) cuts[n++] = r0;
            if (r1 > 0 && r1 > cuts[n - 1]) cuts[n++] = r1;
        }
    } else if (B != 0 && -C / B > 0) {
        cuts[n++] = -C / B;
    }
    // Each piece is in or out as its middle point (or, for the unbounded
    // last piece, a point past its start) is.
    auto inside = [&](double t) {
        const Vec3 x = r.at(t) - mDesc.position;
        const float len = length(x);
        return len > 0 && dot(x, a) > mCosCone * len;
    };
    double lo = Infinity, hi = -1;
    for (int i = 0; i < n; ++i) {
        const double s = cuts[i], e = i + 1 < n ? cuts[i + 1] : double(Infinity);
        const double probe = std::isinf(e) ? s + std::max(1.0, 2 * s) : 0.5 * (s + e);
        if (!inside(probe)) continue;
        lo = std::min(lo, s);
        hi = std::max(hi, e);
    }
    if (!(hi > lo)) return false;
    t0 = float(lo);
    t1 = std::isinf(hi) ? Infinity : float(hi);
    return true;
}

bool Light::intersect(const Ray& r, float tMin, float tMax, float& t) const {
    if (mDesc.type != LightDesc::Type::Sphere) return false;
    Vec3 oc = r.o - mDesc.position;
    float b = dot(oc, r.d);
    float c = lengthSquared(oc) - mDesc.radius * mDesc.radius;
    float disc = b * b - c;
    if (disc < 0) return false;
    float sq = std::sqrt(disc);
    float t0 = -b - sq, t1 = -b + sq;
    if (t0 > tMin && t0 < tMax) { t = t0; return true; }
    if (t1 > tMin && t1 < tMax) { t = t1; return true; }
    return false;
}

}  // namespace vdbmarch
