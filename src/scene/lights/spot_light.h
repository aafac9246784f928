// A spot light: a point light whose intensity falls off towards the edge of
// a cone about its direction.
#pragma once

#include "scene/lights.h"

namespace vdbmarch {

// A spot light's falloff, written once for next-event estimation and photon
// emission: 1 inside the inner cone, a smoothstep to 0 at the cone's edge.
// In t = 1 - cos of the angle to the spot axis, with omcCone = 1 - cosCone
// and omcFalloff = 1 - cosFalloffStart (both exact in float), so that
// hair-thin cones keep their shape. omcFalloff >= omcCone: hard edge.
template <typename T>
T spotFalloff(T t, T omcCone, T omcFalloff) {
    if (t >= omcCone) return 0;
    if (t > omcFalloff) {
        T s = (omcCone - t) / (omcCone - omcFalloff);
        return s * s * (3 - 2 * s);  // smoothstep
    }
    return 1;
}

class SpotLight final : public Light {
public:
    explicit SpotLight(const LightDesc& d);
    bool sample(const Vec3& x, float u1, float u2, LightSample& s) const override;
    bool isPointLike() const override { return true; }
    // The cone (the hull of its two pieces when the cone is wider than a
    // hemisphere).
    bool reachInterval(const Ray& r, float& t0, float& t1) const override;
    bool emittingBall(Vec3& center, float& radius) const override {
        center = mDesc.position;
        radius = 0;
        return true;
    }
    const SpotCone* spotCone() const override { return &mCone; }

protected:
    // scene/lights/spot_emission.cpp.
    std::unique_ptr<LightEmission> emissionTowards(const PhotonTarget& target) const override;

private:
    SpotCone mCone;
};

}  // namespace vdbmarch
