// Photon emission from a light towards the part of the scene that scatters
// (Jensen's volume photon map; the paper's eq. 4): the per-light half of
// pbrt-v4's Light::SampleLe, prepared once per target. Each light class
// builds its own LightEmission (Light::photonEmission); photons/photon_emission.h
// wraps it, with the environment's, as a PhotonEmitter.
//
// Contract. For an emission e and N independent samples, give each photon
// out.power / N. Then for any region inside the target, the expected flux the
// photons carry across it equals the light's true flux across it (the light
// as Light::sample sees it, ignoring occlusion, which the tracer handles).
// power() is the exact expectation of out.power (a missed sample counts as
// zero; for a clipped spot it comes from a quadrature accurate to ~1e-10), so
// it can be used to share a photon budget among emitters. Photons that miss
// still count in N.
#pragma once

#include <memory>

#include "core/math.h"

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
class LightEmission {
public:
    virtual ~LightEmission() = default;
    // Total flux sent towards the target (what the photons carry on average).
    Color power() const { return mPower; }
    // u: 4 uniform numbers in [0, 1). Returns false (and the photon carries
    // nothing) when the sample misses.
    virtual bool sample(const float u[4], EmittedPhoton& out) const = 0;

protected:
    // out.ray starts as (mOrigin, mAxis) and out.power as 0: each sample()
    // replaces what it draws.
    void startPhoton(EmittedPhoton& out) const {
        out.power = Color(0);
        out.ray = Ray{mOrigin, mAxis};
    }

    Color mPower;   // power(): exact expectation of a sample's power
    Color mWeight;  // a sample's power (before any falloff or cone test)
    Vec3 mOrigin;   // where photons start (a light's position, a quad's centre, the target's centre)
    Vec3 mAxis;     // the sampled cone's axis or the direction of travel
};

// ---------------------------------------------------------------------------
// Target geometry, for the emissions' set-up

bool finiteBox(const BBox& b);
// Nothing can scatter: no emitter has anything to do.
bool targetEmpty(const PhotonTarget& t);
// Bounding sphere of the target box, 1% larger so rounding never leaves a
// point of the box outside it. False when the box is empty or not finite.
bool targetSphere(const PhotonTarget& t, Vec3& center, float& radius);

// Cone of directions from p that can reach the target's bounding sphere.
struct TargetCone {
    Vec3 axis;
    float oneMinusCos = 2;  // 1 - cos(half angle), accurate for tiny cones
    double halfAngle = PiD;
};
// False when every direction may reach the target (p inside the bounding
// sphere, or the target unbounded / not finite).
bool targetCone(const PhotonTarget& t, const Vec3& p, TargetCone& c);

// Direction at 1 - cos(theta) = t about `axis` and azimuth 2 pi u; sin(theta)
// from t so that tiny cones (distant targets) keep their spread.
Vec3 coneDirection(const Vec3& axis, float t, float u);
// v / |v|, or `fallback` when v has no finite direction.
Vec3 unitOr(const Vec3& v, const Vec3& fallback);

// ---------------------------------------------------------------------------
// Emissions that more than one source shares

// Uniform in a cone about mAxis (a point light's, or a spot's before its
// falloff): mOneMinusCos = 1 - cos(half angle), 2 = the whole sphere.
class ConeEmission : public LightEmission {
protected:
    // Direction uniform in the sampled cone; returns its 1 - cos.
    Vec3 sampleCone(float u1, float u2, float& oneMinusCos) const;
    float mOneMinusCos = 2;
};

// A directional light (and, scaled, the environment): a disc of radius R
// (the bounding sphere's, already 1% larger) perpendicular to the travel
// direction, centred 1.01 R upstream of the sphere's centre, so every photon
// starts outside the sphere and the beam covers all of it.
class DiscEmission : public LightEmission {
public:
    // Irradiance E perpendicular to the unit travel direction dir. False
    // when the disc would carry nothing (black, no finite target) or its
    // power is not finite.
    bool aim(const Color& irradiance, const Vec3& dir, const PhotonTarget& target);
    bool sample(const float u[4], EmittedPhoton& out) const override;

protected:
    // Point on the disc perpendicular to dir, centred mDiscDist upstream of mOrigin.
    Vec3 sampleDisc(const Vec3& dir, float u1, float u2) const;
    float mRadius = 0;    // disc radius
    float mDiscDist = 0;  // disc centre distance upstream of the target centre
};

}  // namespace vdbmarch
