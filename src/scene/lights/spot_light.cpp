#include "scene/lights/light_kinds.h"

#include <cmath>


namespace vdbmarch {

SpotLight::SpotLight(const LightDesc& d) : Light(d) {
    setEmittingBall(d.position, 0);
    mCone.apex = d.position;
    mCone.axis = d.direction;
    mCone.coneDeg = d.coneDeg;
    mCone.falloffDeg = d.falloffDeg;
    mCone.cosCone = std::cos(radians(d.coneDeg));
    mCone.cosFalloffStart = std::cos(radians(d.coneDeg - d.falloffDeg));
    mCone.omcCone = 1 - mCone.cosCone;
    mCone.omcFalloffStart = 1 - mCone.cosFalloffStart;
}

bool SpotLight::sample(const Vec3& x, float u1, float u2, LightSample& s) const {
    float d2;
    if (!towardsPoint(x, mDesc.position, s, d2)) return false;
    const float falloff = spotFalloff(oneMinusCosTo(-s.wi, mDesc.direction), mCone.omcCone, mCone.omcFalloffStart);
    if (!(falloff > 0)) return false;
    s.L = mDesc.intensity * (falloff / d2);
    return true;
}

bool SpotLight::reachInterval(const Ray& r, float& t0, float& t1) const {
    t0 = 0;
    t1 = Infinity;
    // Points x = o + t d inside the cone: cos(x - p, axis) > cos(cone). On
    // the cone's surface (both nappes) f(t) = (a.v + t a.d)^2 - c2 |v + t d|^2
    // vanishes (v = o - p, a the axis, c2 = cos^2): a quadratic whose roots
    // cut the ray into at most three pieces, each wholly in or out.
    const Vec3& a = mDesc.direction;
    const Vec3 v = r.o - mDesc.position;
    const double c = mCone.cosCone, c2 = c * c;
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
        return len > 0 && dot(x, a) > mCone.cosCone * len;
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

}  // namespace vdbmarch
