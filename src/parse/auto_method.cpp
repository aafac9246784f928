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
    // A path tracer finds a delta light through refracting glass only
    // through glass spheres (sphere caustic connections), and there the
    // marcher measured better (fig4_caustic: 0.17-0.20x the path tracer's
    // MSE at 4 and 16 s; glass.json 0.17x at 16 s): its photons carry the
    // caustics, or their multiply scattered light.
    if (deltaLight && bendingGlass) {
        why = "a point, spot, directional or collimated light seen through glass (photons carry its caustics)";
        return Method::Guided;
    }
    // Media inside glass: shadow rays from every march sample reach the light
    // through the interface; guided measured 0.63-0.78x the path tracer's
    // MSE at equal time on exp1_sphere.
    if (glassWithMedium) {
        why = "media inside glass";
        return Method::Guided;
    }
    // Single scattering: the marchers integrate transmittance along the
    // camera ray and estimate L_i at several samples per ray; guided puts
    // them where the light is (0.70x transmittance's MSE on fig3b_spots).
    if (d.render.maxDepth <= 1) {
        why = "single scattering (max_depth 1)";
        return Method::Guided;
    }
    // Multiple scattering in open media: the path tracer measured as good
    // as or better than the marchers at equal time (cloud_sun: guided 1.09x
    // its MSE; fig3b_spots 1.69x; fig4_caustic_sphere 1.88x).
    why = "multiple scattering in open media";
    return Method::Reference;
}

}  // namespace vdbmarch
