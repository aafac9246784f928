#include "scene/lights/light_kinds.h"

namespace vdbmarch {

bool DirectionalLight::sample(const Vec3& x, float u1, float u2, LightSample& s) const {
    s.wi = -mDesc.direction;
    s.dist = Infinity;
    s.L = mDesc.irradiance;
    return true;
}

std::unique_ptr<LightEmission> DirectionalLight::emissionTowards(const PhotonTarget& target) const {
    auto e = std::make_unique<DiscEmission>();
    if (!e->aim(mDesc.irradiance, unitOr(mDesc.direction, Vec3(0, -1, 0)), target)) return nullptr;
    return e;
}

}  // namespace vdbmarch
