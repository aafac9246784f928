// A directional light: irradiance E (W/m^2 perpendicular to it) arriving
// along one direction from infinitely far, like the sun.
#pragma once

#include "scene/lights.h"

namespace vdbmarch {

class DirectionalLight final : public Light {
public:
    explicit DirectionalLight(const LightDesc& d) : Light(d) {}
    bool sample(const Vec3& x, float u1, float u2, LightSample& s) const override;
    bool atInfinity() const override { return true; }

protected:
    // Uniform on a disc perpendicular to the light, just upstream of the
    // target's bounding sphere and covering it.
    std::unique_ptr<LightEmission> emissionTowards(const PhotonTarget& target) const override;
};

}  // namespace vdbmarch
