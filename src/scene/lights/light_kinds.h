// The kinds of light behind scene/lights.h's interface, one class each;
// each class's code is in its file of this folder (point_light.cpp ...),
// and makeLight (scene/lights.cpp) builds them from the scene's description.
#pragma once

#include "scene/lights.h"

namespace vdbmarch {

// Direction and distance from x to a point source; false when x is on it.
bool towardsPoint(const Vec3& x, const Vec3& position, LightSample& s, float& d2);

// A point light: intensity I (W/sr) from one point, irradiance I / d^2.
class PointLight final : public Light {
public:
    explicit PointLight(const LightDesc& d) : Light(d) { setEmittingBall(d.position, 0); }
    bool sample(const Vec3& x, float u1, float u2, LightSample& s) const override;
    bool isPointLike() const override { return true; }

protected:
    // Uniform in the cone that subtends the target's bounding sphere (the
    // whole sphere when the light is inside it or the target is unbounded).
    std::unique_ptr<LightEmission> emissionTowards(const PhotonTarget& target) const override;
};

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

// A spot light: a point light whose intensity falls off towards the edge of
// a cone about its direction.
class SpotLight final : public Light {
public:
    explicit SpotLight(const LightDesc& d);
    bool sample(const Vec3& x, float u1, float u2, LightSample& s) const override;
    bool isPointLike() const override { return true; }
    // The cone (the hull of its two pieces when the cone is wider than a
    // hemisphere).
    bool reachInterval(const Ray& r, float& t0, float& t1) const override;
    const SpotCone* spotCone() const override { return &mCone; }

protected:
    // scene/lights/spot_emission.cpp.
    std::unique_ptr<LightEmission> emissionTowards(const PhotonTarget& target) const override;

private:
    SpotCone mCone;
};

// A directional light: irradiance E (W/m^2 perpendicular to it) arriving
// along one direction from infinitely far, like the sun.
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

// A collimated quad: a parallelogram that shines a beam of parallel light,
// irradiance E perpendicular to the beam, along one direction (a laser
// sheet, light through a window from a distant source).
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

// A sphere light: a Lambertian sphere of total power P, radiance
// P / (4 pi^2 r^2) over its surface; the one area light, which paths hit.
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
