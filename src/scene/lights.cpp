#include "scene/lights.h"

#include "scene/lights/light_kinds.h"


namespace vdbmarch {

std::unique_ptr<const LightEmission> Light::photonEmission(const PhotonTarget& target) const {
    if (targetEmpty(target)) return nullptr;
    std::unique_ptr<LightEmission> e = emissionTowards(target);
    // Nothing to carry (an empty cone, a far-off speck of a target): no emitter.
    if (!e || isBlack(e->power()) || !isFinite(e->power())) return nullptr;
    return e;
}

std::unique_ptr<Light> makeLight(const LightDesc& d) {
    switch (d.type) {
        case LightDesc::Type::Point:
            return std::make_unique<PointLight>(d);
        case LightDesc::Type::Spot:
            return std::make_unique<SpotLight>(d);
        case LightDesc::Type::Directional:
            return std::make_unique<DirectionalLight>(d);
        case LightDesc::Type::CollimatedQuad:
            return std::make_unique<CollimatedQuadLight>(d);
        case LightDesc::Type::Sphere:
            return std::make_unique<SphereLight>(d);
    }
    return nullptr;
}

}  // namespace vdbmarch
