// Emission sampling for the volume photon map (Jensen; the paper's eq. 4):
// each light, and the background or environment map, becomes an emitter that
// shoots photons only where they can reach the part of the scene that
// scatters. A light's own emission lives with its class
// (Light::photonEmission, scene/lights/); the environment's is here. The
// contract every emitter keeps is in scene/lights/light_emission.h.
#pragma once

#include <memory>

#include "core/math.h"
#include "scene/environment.h"
#include "scene/lights.h"

namespace vdbmarch {

// Emission sampling of one light (or the environment) towards a target; an
// emitter with nothing to carry has zero power and misses every sample.
class PhotonEmitter {
public:
    PhotonEmitter() = default;
    // Light::photonEmission: per kind of light, scene/lights/light_kinds.h.
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
    Color power() const { return mEmission ? mEmission->power() : Color(); }
    // u: 4 uniform numbers in [0, 1). Returns false (and the photon carries
    // nothing) when the sample misses.
    bool sample(const float u[4], EmittedPhoton& out) const {
        if (mEmission) return mEmission->sample(u, out);
        out.power = Color(0);
        out.ray = Ray{};
        return false;
    }

private:
    explicit PhotonEmitter(std::unique_ptr<const LightEmission> emission) : mEmission(std::move(emission)) {}
    std::unique_ptr<const LightEmission> mEmission;  // null: nothing to carry
};

}  // namespace vdbmarch
