#include "photons/photon_emission.h"

#include "core/sampling.h"

namespace vdbmarch {

namespace {

// A constant environment: a uniform direction, then a point on the disc
// perpendicular to it; irradiance 4 pi L from the whole sky.
class EnvironmentEmission final : public DiscEmission {
public:
    bool sample(const float u[4], EmittedPhoton& out) const override {
        startPhoton(out);
        out.ray.d = sampleUniformSphere(u[2], u[3]);
        out.ray.o = sampleDisc(out.ray.d, u[0], u[1]);
        out.power = mWeight;
        return true;
    }
};

// An environment map: a sky direction w by texel power; the photon travels
// along -w and carries L(w) / pdf(w) x the disc's area.
class EnvironmentMapEmission final : public DiscEmission {
public:
    explicit EnvironmentMapEmission(const Environment& env) : mEnvironment(env) {}
    bool sample(const float u[4], EmittedPhoton& out) const override {
        startPhoton(out);
        Vec3 w;
        float pdf;
        Color radianceOverPdf;
        if (!mEnvironment.sample(u[2], u[3], w, pdf, radianceOverPdf)) return false;
        out.ray.d = -w;
        out.ray.o = sampleDisc(out.ray.d, u[0], u[1]);
        out.power = radianceOverPdf * (Pi * mRadius * mRadius);
        return isFinite(out.power);
    }

private:
    const Environment& mEnvironment;
};

}  // namespace

PhotonEmitter PhotonEmitter::forLight(const Light& light, const PhotonTarget& target) {
    return PhotonEmitter(light.photonEmission(target));
}

PhotonEmitter PhotonEmitter::forEnvironment(const Color& radiance, const PhotonTarget& target) {
    auto e = std::make_unique<EnvironmentEmission>();
    if (!e->aim(radiance * (4 * Pi), Vec3(0, 0, 1), target)) return PhotonEmitter();
    return PhotonEmitter(std::move(e));
}

PhotonEmitter PhotonEmitter::forEnvironment(const Environment& env, const PhotonTarget& target) {
    if (!env.hasMap()) return forEnvironment(env.radiance(Vec3(0, 1, 0)), target);
    // Expected power: the integral of L over the sphere x the disc's area.
    auto e = std::make_unique<EnvironmentMapEmission>(env);
    if (!e->aim(env.integral(), Vec3(0, 0, 1), target)) return PhotonEmitter();
    return PhotonEmitter(std::move(e));
}

}  // namespace vdbmarch
