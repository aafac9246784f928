// A collimated quad: a parallelogram that shines a beam of parallel light,
// irradiance E perpendicular to the beam, along one direction (a laser
// sheet, light through a window from a distant source).
#pragma once

#include "scene/lights.h"

namespace vdbmarch {

class CollimatedQuadLight final : public Light {
public:
    explicit CollimatedQuadLight(const LightDesc& d);
    bool sample(const Vec3& x, float u1, float u2, LightSample& s) const override;
    const CollimatedQuad* collimatedQuad() const override { return &mQuad; }

protected:
    // Uniform on the quad; none when the beam misses the target box.
    std::unique_ptr<LightEmission> emissionTowards(const PhotonTarget& target) const override;

private:
    CollimatedQuad mQuad;
    Vec3 mQuadNormal, mDualU, mDualV;  // the quad's plane and dual basis
};

}  // namespace vdbmarch
