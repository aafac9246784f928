// A point light: intensity I (W/sr) from one point, irradiance I / d^2.
#pragma once

#include "scene/lights.h"

namespace vdbmarch {

// Direction and distance from x to a point source; false when x is on it.
bool towardsPoint(const Vec3& x, const Vec3& position, LightSample& s, float& d2);

class PointLight final : public Light {
public:
    explicit PointLight(const LightDesc& d) : Light(d) {}
    bool sample(const Vec3& x, float u1, float u2, LightSample& s) const override;
    bool isPointLike() const override { return true; }
    bool emittingBall(Vec3& center, float& radius) const override {
        center = mDesc.position;
        radius = 0;
        return true;
    }

protected:
    // Uniform in the cone that subtends the target's bounding sphere (the
    // whole sphere when the light is inside it or the target is unbounded).
    std::unique_ptr<LightEmission> emissionTowards(const PhotonTarget& target) const override;
};

}  // namespace vdbmarch
