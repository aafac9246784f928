// Light sources: the interface the renderer asks of a light (Mitsuba 3's
// Emitter, pbrt-v4's Light), one class per kind in scene/lights/. A sample
// gives the direction to the light, the distance to it, and the incident
// quantity: irradiance (W/m^2 at the point, perpendicular to wi) for delta
// lights, radiance / pdf for area lights; either way in-scattered radiance
// is sigma_s * phase * L * T.
//
// A new kind of light is a new subclass (and its entry in the parser and in
// makeLight): next-event estimation, MIS, photon emission and scene set-up
// only call the virtuals below; the strategies that exploit one kind's
// geometry ask for it by spotCone(), sphere() or collimatedQuad().
#pragma once

#include <memory>
#include <vector>

#include "core/math.h"
#include "parse/scene_desc.h"
#include "scene/lights/light_emission.h"

namespace vdbmarch {

struct LightSample {
    Vec3 wi;     // unit, from the shaded point towards the light
    float dist;  // distance to the light along wi (Infinity: directional)
    Color L;
    float pdf = 0;  // solid-angle pdf of wi for area lights; 0 for delta lights
};

// A spot light's cone (Light::spotCone), with its falloff's cosines as
// spotFalloff (scene/lights/light_kinds.h) takes them.
struct SpotCone {
    Vec3 apex, axis;  // the light's position and unit direction
    float coneDeg = 30, falloffDeg = 5;
    float cosCone = -1, cosFalloffStart = -1;
    float omcCone = 2, omcFalloffStart = 2;  // 1 - those cosines
};

// A sphere light's surface (Light::sphere).
struct LightSphere {
    Vec3 center;
    float radius = 1;
};

// A collimated quad (Light::collimatedQuad): the parallelogram
// center + a u + b v, |a|, |b| <= 1/2, shining along the unit `direction`.
struct CollimatedQuad {
    Vec3 center, u, v, direction;
};

class Light {
public:
    virtual ~Light() = default;
    Light(const Light&) = delete;
    Light& operator=(const Light&) = delete;

    // --- Next-event estimation and MIS
    // False when the light cannot illuminate x (outside a spot cone, beside a
    // collimated quad, inside a sphere light).
    virtual bool sample(const Vec3& x, float u1, float u2, LightSample& s) const = 0;
    // The solid-angle density with which sample() at x draws a direction
    // that hits the light. 0 for delta lights and where sample() cannot
    // draw. The path loops weigh a path's own light hits against
    // next-event estimation by it (MIS).
    virtual float directionPdf(const Vec3& x) const { return 0; }
    // A delta light: no path can hit it, only next-event estimation sees it.
    virtual bool isDelta() const { return true; }
    // A point or spot light: its irradiance grows as 1/d^2 close to it, so
    // next-event estimation at scattering vertices around it has unbounded variance.
    virtual bool isPointLike() const { return false; }
    // The part [t0, t1] of the ray r (t >= 0) that the light can reach (a
    // spot's cone); false when the ray never enters it. Distance sampling
    // towards the light only draws points there. All of the ray by default.
    virtual bool reachInterval(const Ray& r, float& t0, float& t1) const {
        t0 = 0;
        t1 = Infinity;
        return true;
    }
    // Lights a path can hit (not delta): nearest hit in (tMin, tMax).
    virtual bool intersect(const Ray& r, float tMin, float tMax, float& t) const { return false; }
    // Radiance leaving the light's surface towards a path that hits it.
    virtual Color emittedRadiance() const { return Color(); }

    // --- Photon emission
    // Emission sampling towards `target`; null when nothing reaches it.
    std::unique_ptr<const LightEmission> photonEmission(const PhotonTarget& target) const;

    // --- Scene set-up
    // Infinitely far (a directional light): outside every closed surface.
    virtual bool atInfinity() const { return false; }
    // The ball that holds the points the light emits from and its shadow
    // rays end on, where the scene set-up tracks it: a point or spot light's
    // position (radius 0), a sphere light's sphere. False elsewhere (the
    // light may then be anywhere: a shadow ray from inside closed surfaces
    // may reach it).
    bool emittingBall(Vec3& center, float& radius) const {
        if (!(mBallRadius >= 0)) return false;
        center = mBallCenter;
        radius = mBallRadius;
        return true;
    }

    // --- One kind's geometry, for the strategies built on it (null for other kinds)
    virtual const SpotCone* spotCone() const { return nullptr; }
    virtual const LightSphere* sphere() const { return nullptr; }
    virtual const CollimatedQuad* collimatedQuad() const { return nullptr; }

    // The parameters the scene file gave.
    const LightDesc& desc() const { return mDesc; }

protected:
    explicit Light(const LightDesc& d) : mDesc(d) {}
    // photonEmission before its common checks (an empty target, no power).
    virtual std::unique_ptr<LightEmission> emissionTowards(const PhotonTarget& target) const = 0;
    // Sets emittingBall's answer (a kind that sets none answers false).
    void setEmittingBall(const Vec3& center, float radius) {
        mBallCenter = center;
        mBallRadius = radius;
    }

    LightDesc mDesc;

private:
    Vec3 mBallCenter{0, 0, 0};
    float mBallRadius = -1;  // < 0: no ball
};

// The light a description asks for.
std::unique_ptr<Light> makeLight(const LightDesc& d);

// The scene's lights, owned, indexed and iterated as `const Light&`.
class LightList {
public:
    using Owned = std::vector<std::unique_ptr<Light>>;
    class Iterator {
    public:
        explicit Iterator(Owned::const_iterator it) : mIt(it) {}
        const Light& operator*() const { return **mIt; }
        Iterator& operator++() {
            ++mIt;
            return *this;
        }
        bool operator!=(const Iterator& o) const { return mIt != o.mIt; }

    private:
        Owned::const_iterator mIt;
    };

    void add(std::unique_ptr<Light> light) { mLights.push_back(std::move(light)); }
    size_t size() const { return mLights.size(); }
    bool empty() const { return mLights.empty(); }
    const Light& operator[](size_t i) const { return *mLights[i]; }
    const Light& at(size_t i) const { return *mLights.at(i); }
    Iterator begin() const { return Iterator(mLights.begin()); }
    Iterator end() const { return Iterator(mLights.end()); }

private:
    Owned mLights;
};

}  // namespace vdbmarch
