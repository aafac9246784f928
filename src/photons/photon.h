// One stored photon, 32 bytes: position, travel direction (octahedral, 2 x 16
// bits), and its fluence weight. Photons are stored at every real collision
// in a medium (scattering or absorption) with the weight Phi / sigma_t(x_p):
// collisions happen at rate sigma_t times the radiance, so dividing by the
// extinction where the photon landed makes the sum over a volume an estimate
// of the integral of the radiance (docs/method.md, "Photon map").
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/math.h"

namespace vdbmarch {

// Octahedral encoding of a unit vector in 32 bits (max error ~3e-5 rad).
inline uint32_t encodeDirection(const Vec3& d) {
    float l1 = std::fabs(d.x) + std::fabs(d.y) + std::fabs(d.z);
    float u = d.x / l1, v = d.y / l1;
    if (d.z < 0) {
        float pu = (1 - std::fabs(v)) * (u >= 0 ? 1.f : -1.f);
        float pv = (1 - std::fabs(u)) * (v >= 0 ? 1.f : -1.f);
        u = pu;
        v = pv;
    }
    auto q = [](float x) {
        return uint32_t(std::lround(std::min(1.f, std::max(-1.f, x)) * 32767.f) + 32767);
    };
    return q(u) | (q(v) << 16);
}

inline Vec3 decodeDirection(uint32_t e) {
    float u = float(int(e & 0xffffu) - 32767) / 32767.f;
    float v = float(int(e >> 16) - 32767) / 32767.f;
    Vec3 d(u, v, 1 - std::fabs(u) - std::fabs(v));
    if (d.z < 0) {
        float du = (1 - std::fabs(v)) * (u >= 0 ? 1.f : -1.f);
        float dv = (1 - std::fabs(u)) * (v >= 0 ? 1.f : -1.f);
        d.x = du;
        d.y = dv;
    }
    return normalize(d);
}

struct Photon {
    enum Flags : uint32_t {
        Direct = 1u,   // straight from a light: shadow rays compute this light
        Caustic = 2u,  // from a delta light through a bending surface before any scattering:
                       // no path with next-event estimation finds this light; from a sphere
                       // light where Scene::sphereLightCausticPhotons leaves it to photons
        FromPointLight = 4u,  // emitted by a point or spot light
        // A caustic that sphere caustic connections find (Scene::deltaLightCaustics):
        // from a delta light through one glass sphere (in and out),
        // or across its surface once, with no other event before it landed.
        Connected = 8u,
    };
    Vec3 position;
    uint32_t direction;  // encodeDirection(travel direction)
    Color weight;        // Phi / sigma_t at the collision (W m), per channel
    uint32_t flags;      // bits 0-3: Flags; bits 4-15: region(); bits 16-31: the phase g there, as int16 / 32767

    Vec3 travelDirection() const { return decodeDirection(direction); }
    bool isDirect() const { return (flags & Direct) != 0; }
    bool isCaustic() const { return (flags & Caustic) != 0; }
    bool isFromPointLight() const { return (flags & FromPointLight) != 0; }
    bool isConnected() const { return (flags & Connected) != 0; }
    // Mean cosine of the phase function where the photon landed (the
    // sigma_s-weighted mean over the media there), for eq. 27's w'_l = g^l.
    float g() const { return float(int16_t(uint16_t(flags >> 16))) / 32767.f; }
    // The medium region (Scene::regions) it landed in, up to MaxRegion;
    // regions beyond it share MaxRegion.
    static constexpr int MaxRegion = 0xfff;
    static int storedRegion(int region) { return std::min(MaxRegion, std::max(0, region)); }
    int region() const { return int((flags >> 4) & 0xfffu); }
    // bits: Flags or-ed together.
    static uint32_t packFlags(uint32_t bits, float g, int region = 0) {
        int q = int(std::lround(std::min(1.f, std::max(-1.f, g)) * 32767.f));
        const uint32_t r = uint32_t(storedRegion(region));
        return (bits & 0xfu) | (r << 4) | (uint32_t(uint16_t(int16_t(q))) << 16);
    }
};
static_assert(sizeof(Photon) == 32, "photons are stored compactly");

}  // namespace vdbmarch
