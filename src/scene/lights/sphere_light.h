// A sphere light: a Lambertian sphere of total power P, radiance
// P / (4 pi^2 r^2) over its surface; the one area light, which paths hit.
#pragma once

#include "scene/lights.h"

namespace vdbmarch {

class SphereLight final : public Light {
public:
    explicit SphereLight(const LightDesc& d);
    // Uniform in the cone of directions that sees the sphere.
    bool sample(const Vec3& x, float u1, float u2, LightSample& s) const override;
    // Uniform over that cone, so the same for every direction that hits it.
    float directionPdf(const Vec3& x) const override;
    bool isDelta() const override { return false; }
    bool intersect(const Ray& r, float tMin, float tMax, float& t) const override;
    Color emittedRadiance() const override { return mRadiance; }
    bool emittingBall(Vec3& center, float& radius) const override {
        center = mSphere.center;
        radius = mSphere.radius;
        return true;
    }
    const LightSphere* sphere() const override { return &mSphere; }

protected:
    // Uniform on the surface, cosine-weighted about the normal; the photons
    // start exactly on the surface (the tracer should ignore the emitting
    // sphere at t = 0). Power is always the light's total power.
    std::unique_ptr<LightEmission> emissionTowards(const PhotonTarget& target) const override;

private:
    LightSphere mSphere;
    Color mRadiance;
};

}  // namespace vdbmarch
