// Sampling routines come with their pdf (and inverse where it exists).
#pragma once

#include "core/math.h"

namespace vdbmarch {

// Direction around `axis` with the given cosine and azimuth u2 in [0,1).
inline Vec3 directionAround(const Vec3& axis, float cosTheta, float u2) {
    Vec3 s, t;
    coordinateSystem(axis, s, t);
    float sinTheta = safeSqrt(1 - cosTheta * cosTheta);
    float phi = 2 * Pi * u2;
    return s * (sinTheta * std::cos(phi)) + t * (sinTheta * std::sin(phi)) + axis * cosTheta;
}

inline Vec3 sampleUniformSphere(float u1, float u2) {
    float z = 1 - 2 * u1;
    float r = safeSqrt(1 - z * z), phi = 2 * Pi * u2;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
inline float uniformSpherePdf() { return Inv4Pi; }

// Uniform direction inside the cone of half-angle acos(cosMax) around axis.
inline Vec3 sampleUniformCone(const Vec3& axis, float cosMax, float u1, float u2) {
    float cosTheta = 1 - u1 * (1 - cosMax);
    return directionAround(axis, cosTheta, u2);
}
inline float uniformConePdf(float cosMax) { return 1 / (2 * Pi * (1 - cosMax)); }

// Fresnel reflectance of a smooth dielectric for unpolarised light;
// cosI > 0 on the incident side, eta = n_transmitted / n_incident.
inline float fresnelDielectric(float cosI, float eta, float* cosTOut = nullptr) {
    cosI = clamp(cosI, 0.f, 1.f);
    float sin2T = (1 - cosI * cosI) / (eta * eta);
    if (sin2T >= 1) {
        if (cosTOut) *cosTOut = 0;
        return 1;  // total internal reflection
    }
    float cosT = safeSqrt(1 - sin2T);
    if (cosTOut) *cosTOut = cosT;
    float rPar = (eta * cosI - cosT) / (eta * cosI + cosT);
    float rPerp = (cosI - eta * cosT) / (cosI + eta * cosT);
    return 0.5f * (rPar * rPar + rPerp * rPerp);
}

// Equiangular distance sampling (Kulla & Fajardo 2012, "Importance Sampling
// Techniques for Path Tracing in Participating Media"): t in [a, b] along
// the ray o + t d (d unit) with density proportional to 1 / r(t)^2, r the
// distance to a point c, the falloff of a light at c. With delta the
// parameter of c's foot on the ray and D the distance of c from the ray,
// t = delta + D tan(theta) with theta uniform between the angles of a and b.
// D is kept at least minDistance (a ray through the point itself). Double
// inside: tan near +-pi/2 and far intervals lose float digits.
class EquiangularSampler {
public:
    EquiangularSampler() = default;
    EquiangularSampler(const Vec3& o, const Vec3& d, const Vec3& c, float a, float b, float minDistance) {
        const Vec3 oc = c - o;
        mDelta = double(dot(oc, d));
        const Vec3 perp = oc - d * float(mDelta);
        mD = std::max(double(length(perp)), double(minDistance));
        mA = a;
        mB = b;
        mThetaA = std::atan2(double(a) - mDelta, mD);
        mThetaB = std::isinf(b) ? 0.5 * 3.14159265358979323846 : std::atan2(double(b) - mDelta, mD);
        mValid = b > a && mThetaB > mThetaA && mD > 0;
    }
    bool valid() const { return mValid; }
    float sample(float u) const {
        const double t = mDelta + mD * std::tan(mThetaA + double(u) * (mThetaB - mThetaA));
        return clamp(float(t), mA, mB);
    }
    // The ratio of the largest to the smallest 1/r^2 over [a, b] (infinite
    // for an unbounded interval): near 1, the density is nearly uniform.
    // Without a sampler (no atan2): for a caller that decides whether to
    // sample at all.
    static float falloffRange(const Vec3& o, const Vec3& d, const Vec3& c, float a, float b, float minDistance) {
        const Vec3 oc = c - o;
        const double delta = double(dot(oc, d));
        return falloffRange(delta, std::max(double(length(oc - d * float(delta))), double(minDistance)), a, b);
    }
    // The integral of 1 / r^2 over [a, b] (a point source's unoccluded
    // irradiance summed along the interval, per unit intensity).
    float inverseSquareIntegral() const { return mValid ? float((mThetaB - mThetaA) / mD) : 0.f; }
    // Density of sample() at t; 0 outside [a, b].
    float pdf(float t) const {
        if (!mValid || !(t >= mA && t <= mB)) return 0.f;
        const double x = double(t) - mDelta;
        return float(mD / ((mThetaB - mThetaA) * (mD * mD + x * x)));
    }

private:
    static float falloffRange(double delta, double D, float a, float b) {
        const double xa = std::fabs(double(a) - delta), xb = std::fabs(double(b) - delta);
        const double xMin = double(a) <= delta && delta <= double(b) ? 0.0 : std::min(xa, xb);
        const double xMax = std::max(xa, xb);
        return float((D * D + xMax * xMax) / (D * D + xMin * xMin));
    }
    double mDelta = 0, mD = 1, mThetaA = 0, mThetaB = 0;
    float mA = 0, mB = 0;
    bool mValid = false;
};

}  // namespace vdbmarch
