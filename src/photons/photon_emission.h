// Emission sampling for the volume photon map (Jensen; the paper's eq. 4):
// each light, and the background or environment map, becomes an emitter that shoots
// photons only where they can reach the part of the scene that scatters.
//
// Contract. For an emitter e and N independent samples, give each photon
// out.power / N. Then for any region inside the target, the expected flux the
// photons carry across it equals the light's true flux across it (the light
// as Light::sample sees it, ignoring occlusion, which the tracer handles).
// power() is the exact expectation of out.power (a missed sample counts as
// zero; for a clipped spot it comes from a quadrature accurate to ~1e-10), so
// it can be used to share a photon budget among emitters. Photons that miss
// still count in N.
#pragma once

#include "core/math.h"
#include "scene/environment.h"
#include "scene/lights.h"

namespace vdbmarch {

// Where photons are useful: the bounding box of everything that can scatter
// or redirect light (scattering media, surfaces). `unbounded` = some
// scattering medium fills all space: the light-only emitters then aim
// everywhere, while the directional and environment emitters still need a
// finite box of the scene content in `bounds` (they start photons on a disc
// just outside its bounding sphere, so whatever lies upstream of that disc
// receives nothing from them).
// A bounded target whose box is empty means nothing can scatter: every
// emitter reports zero power. A box that is not finite counts as unbounded
// for the light-only emitters and gives the disc emitters zero power.
struct PhotonTarget {
    BBox bounds;
    bool unbounded = false;
};

struct EmittedPhoton {
    Ray ray;      // origin on the emitter (finite), unit direction of travel
    Color power;  // flux carried by this one sample (W), before dividing by the photon count
};

// Emission sampling of one light towards a target.
class PhotonEmitter {
public:
    // Light-only emitters.
    //  Point: uniform in the cone that subtends the target's bounding sphere
    //    (whole sphere when the light is inside it or the target is unbounded).
    //  Spot: uniform in the narrower of the spot cone and that target cone,
    //    weighted by intensity * falloff / pdf, zero outside the other cone.
    //  Directional: uniform on a disc perpendicular to the light, just
    //    upstream of the target's bounding sphere and covering it.
    //  CollimatedQuad: uniform on the quad; zero power when the beam misses
    //    the target box.
    //  Sphere: uniform on the surface, cosine-weighted about the normal; the
    //    photons start exactly on the surface (the tracer should ignore the
    //    emitting sphere at t = 0). Power is always the light's total power.
    static PhotonEmitter forLight(const Light& light, const PhotonTarget& target);
    // Constant environment radiance (the background), as seen from the
    // target: uniform direction, uniform on a disc perpendicular to it that
    // covers the target's bounding sphere.
    static PhotonEmitter forEnvironment(const Color& radiance, const PhotonTarget& target);
    // An environment (map or constant): a map's directions are drawn by its
    // texel power (Environment::sample); `env` must outlive the emitter.
    static PhotonEmitter forEnvironment(const Environment& env, const PhotonTarget& target);

    // Total flux this emitter sends towards the target (what the photons
    // carry on average); 0 if it cannot reach the target.
    Color power() const { return mPower; }
    // u: 4 uniform numbers in [0, 1). Returns false (and the photon carries
    // nothing) when the sample misses.
    bool sample(const float u[4], EmittedPhoton& out) const;

private:
    enum class Kind { None, Point, Spot, Disc, Environment, EnvironmentMap, Quad, Sphere };

    // Directional light (and, scaled, the environment): a disc covering the
    // target's bounding sphere; irradiance E perpendicular to dir.
    static PhotonEmitter forDisc(const Color& irradiance, const Vec3& dir, const PhotonTarget& target);
    // Direction uniform in the sampled cone around mAxis; returns its 1 - cos.
    Vec3 sampleCone(float u1, float u2, float& oneMinusCos) const;
    // Point on the disc of radius mRadius perpendicular to dir, centred mDiscDist upstream of mOrigin.
    Vec3 sampleDisc(const Vec3& dir, float u1, float u2) const;

    Kind mKind = Kind::None;
    Color mPower;   // power(): exact expectation of a sample's power
    Color mWeight;  // a sample's power (before the spot falloff and cone test)
    Vec3 mOrigin;   // point / spot / sphere light position, quad centre, or target centre (discs)
    Vec3 mAxis;     // sampled cone axis (point, spot) or direction of travel (directional, quad)
    float mOneMinusCos = 2;       // sampled cone: 1 - cos(half angle); 2 = whole sphere
    float mRadius = 0;            // disc radius (directional, environment), sphere light radius
    float mDiscDist = 0;          // disc centre distance upstream of the target centre
    Vec3 mU, mV;                  // quad edge vectors
    const Environment* mEnvironment = nullptr;  // environment maps
    // Spot only: the falloff as Light::sample evaluates it (its cosines as
    // 1 - cos), and the cone not sampled (directions outside it carry nothing).
    Vec3 mSpotAxis;
    float mOmcCone = 2, mOmcFalloffStart = 2;
    bool mSampleSpotCone = true;  // else the target cone is sampled
    bool mTestTargetCone = false;
    Vec3 mTargetAxis;
    float mTargetOneMinusCos = 2;
};

}  // namespace vdbmarch
