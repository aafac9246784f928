// The unbiased reference: the volumetric path tracer of
// paths/path_tracer.h from the camera (delta tracking against local
// majorants, emission at tentative collisions, next-event estimation with
// MIS for sphere lights, the shared surface event). Media whose extinction
// differs between RGB channels are tracked with spectral MIS from a hero
// channel (HeroChannel): one path per sample carries all three.
//
// A path cannot find a delta light through refracting glass (shadow rays
// cannot bend): where a scene has such caustics, the photons flagged
// caustic give them at the camera path's first medium vertex (eq. 4, the
// progressive passes' radius), as they do at the guided marcher's L_i
// samples; the paths give all the rest. Sphere lights stay with the paths
// unless those photons carry them too (Scene::sphereLightCausticPhotons).
#include "illumination/illumination.h"
#include "estimators/estimator.h"
#include "paths/path_tracer.h"
#include "transport/surface_event.h"
#include "transport/tracking.h"

namespace vdbmarch {

namespace {

// L_caustic of eq. 4 over the current photon pass's caustic photons.
class CausticPhotons final : public InScatteredLight {
public:
    CausticPhotons(const Scene& scene, const Illumination& il) : mScene(scene), mIl(il) {}
    Color at(const Vec3& x, int region, const Vec3& wo, const PhaseMixture& phase) const override {
        return mIl.photonLi(mScene, x, region, wo, phase);
    }

private:
    const Scene& mScene;
    const Illumination& mIl;
};

class ReferenceTracer final : public Estimator {
public:
    explicit ReferenceTracer(const EstimatorInputs& in)
        : mScene(in.scene), mChromatic(hasChromaticExtinction(in.scene)), mIllumination(in.illumination),
          mCaustics(mIllumination && mIllumination->causticsOnly ? std::make_unique<CausticPhotons>(in.scene, *mIllumination)
                                                                 : nullptr),
          mPaths(in.scene, in.strategies, PathOptions{false, mCaustics.get()}) {}

    PathRadiance radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const override {
        ++ctx.counters.cameraRays;
        const int region = regionAtRayStart(mScene, cameraRay);
        PathState start;
        start.spectral = startingHero(mChromatic, rng);
        return mPaths.trace(ctx, cameraRay, region, rng, start);
    }

private:
    const Scene& mScene;
    const bool mChromatic;
    std::shared_ptr<const Illumination> mIllumination;  // keeps the caustic photons alive
    std::unique_ptr<InScatteredLight> mCaustics;  // null where no caustic photons are traced
    PathTracer mPaths;
};

}  // namespace

std::unique_ptr<Estimator> makeReferenceTracer(const EstimatorInputs& in) { return std::make_unique<ReferenceTracer>(in); }

}  // namespace vdbmarch
