#include "parse/auto_method.h"

namespace vdbmarch {

Method chooseMethod(const SceneDesc& d, std::string& why) {
    bool deltaLight = false, bendingGlass = false, glassWithMedium = false;
    for (const auto& l : d.lights) deltaLight = deltaLight || l.type != LightDesc::Type::Sphere;
    for (const auto& s : d.surfaces) {
        const bool bends = s.material.type == MaterialDesc::Type::Dielectric && s.material.ior != 1.f;
        bendingGlass = bendingGlass || bends;
        glassWithMedium = glassWithMedium || (bends && !s.interior.empty());
    }
    // The rule picks the method that did best at equal time on each class of
    // scene; the figures are in docs/method.md, "The automatic method".
    //
    // Delta lights through refracting glass: a path tracer reaches them only
    // through glass spheres; the marcher's photons carry the caustics.
    if (deltaLight && bendingGlass) {
        why = "a point, spot, directional or collimated light seen through glass (photons carry its caustics)";
        return Method::Guided;
    }
    // Media inside glass: shadow rays from every march sample reach the light
    // through the interface.
    if (glassWithMedium) {
        why = "media inside glass";
        return Method::Guided;
    }
    // Single scattering: the marchers integrate transmittance along the
    // camera ray and estimate L_i at several samples per ray; guided puts
    // them where the light is.
    if (d.render.maxDepth <= 1) {
        why = "single scattering (max_depth 1)";
        return Method::Guided;
    }
    // Multiple scattering in open media: the path tracer does as well as or
    // better than the marchers.
    why = "multiple scattering in open media";
    return Method::Reference;
}

}  // namespace vdbmarch
