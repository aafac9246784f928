#include "scene/lights/light_kinds.h"

#include <cmath>

namespace vdbmarch {

bool towardsPoint(const Vec3& x, const Vec3& position, LightSample& s, float& d2) {
    Vec3 to = position - x;
    d2 = lengthSquared(to);
    if (!(d2 > 0)) return false;
    s.dist = std::sqrt(d2);
    s.wi = to / s.dist;
    return true;
}

bool PointLight::sample(const Vec3& x, float u1, float u2, LightSample& s) const {
    float d2;
    if (!towardsPoint(x, mDesc.position, s, d2)) return false;
    s.L = mDesc.intensity / d2;
    return true;
}

namespace {

// Every photon carries the same power: I times the sampled cone's solid angle.
class PointEmission final : public ConeEmission {
public:
    PointEmission(const LightDesc& d, const PhotonTarget& target) {
        mOrigin = d.position;
        mAxis = Vec3(0, 0, 1);
        TargetCone c;
        if (targetCone(target, d.position, c)) {
            mAxis = c.axis;
            mOneMinusCos = c.oneMinusCos;
        }
        mWeight = d.intensity * (2 * Pi * mOneMinusCos);
        mPower = mWeight;
    }
    bool sample(const float u[4], EmittedPhoton& out) const override {
        startPhoton(out);
        float t;
        out.ray.d = sampleCone(u[0], u[1], t);
        out.power = mWeight;
        return true;
    }
};

}  // namespace

std::unique_ptr<LightEmission> PointLight::emissionTowards(const PhotonTarget& target) const {
    if (isBlack(mDesc.intensity)) return nullptr;
    return std::make_unique<PointEmission>(mDesc, target);
}

}  // namespace vdbmarch
