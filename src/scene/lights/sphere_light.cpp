#include "scene/lights/light_kinds.h"

#include <cmath>

#include "core/sampling.h"

namespace vdbmarch {

SphereLight::SphereLight(const LightDesc& d) : Light(d) {
    mSphere = {d.position, d.radius};
    setEmittingBall(mSphere.center, mSphere.radius);
    mRadiance = d.power / (4 * Pi * Pi * d.radius * d.radius);
}

bool SphereLight::sample(const Vec3& x, float u1, float u2, LightSample& s) const {
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

float SphereLight::directionPdf(const Vec3& x) const {
    const Vec3 to = mDesc.position - x;
    const float d2 = lengthSquared(to), r2 = mDesc.radius * mDesc.radius;
    if (d2 <= r2 * 1.0001f) return 0;
    const float sin2 = r2 / d2, cosMax = sin2 < 1e-6f ? 1 - 0.5f * sin2 : safeSqrt(1 - sin2);
    return uniformConePdf(cosMax);
}

bool SphereLight::intersect(const Ray& r, float tMin, float tMax, float& t) const {
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

namespace {

// A Lambertian emitter: a point uniform on the surface, a direction
// cosine-weighted about its outward normal; every photon carries P.
class SphereEmission final : public LightEmission {
public:
    explicit SphereEmission(const LightDesc& d) {
        mOrigin = d.position;
        mRadius = std::fabs(d.radius);
        mWeight = d.power;
        mPower = d.power;
    }
    bool sample(const float u[4], EmittedPhoton& out) const override {
        startPhoton(out);
        Vec3 n = sampleUniformSphere(u[0], u[1]);
        out.ray.o = mOrigin + n * mRadius;
        // cos = sqrt(1 - u) > 0, so no photon leaves tangentially.
        out.ray.d = directionAround(n, std::sqrt(1 - u[2]), u[3]);
        out.power = mWeight;
        return true;
    }

private:
    float mRadius = 0;
};

}  // namespace

std::unique_ptr<LightEmission> SphereLight::emissionTowards(const PhotonTarget& target) const {
    if (isBlack(mDesc.power)) return nullptr;
    return std::make_unique<SphereEmission>(mDesc);
}

}  // namespace vdbmarch
