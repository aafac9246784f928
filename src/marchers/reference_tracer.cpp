// The unbiased reference: the volumetric path tracer of
// transport/path_tracer.h from the camera (delta tracking against local
// majorants, emission at tentative collisions, next-event estimation with
// MIS for sphere lights, the shared surface event). Media whose extinction
// differs between RGB channels are tracked one channel per path (three
// paths per sample).
#include "marchers/marcher.h"
#include "transport/path_tracer.h"
#include "transport/surface_event.h"

namespace vdbmarch {

namespace {

class ReferenceTracer final : public Marcher {
public:
    explicit ReferenceTracer(const Scene& s) : mScene(s), mChromatic(hasChromaticExtinction(s)) {}

    PathResult radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const override {
        ++ctx.counters.cameraRays;
        const int region = regionAtRayStart(mScene, cameraRay);
        if (!mChromatic) {
            PathRadiance p = tracePath(ctx, cameraRay, region, -1, rng, {});
            return {p.L, p.transmittance, p.direct};
        }
        PathResult out{Color(0), 0.f};
        for (int c = 0; c < 3; ++c) {
            PathRadiance p = tracePath(ctx, cameraRay, region, c, rng, {});
            out.L[c] = p.L[c];
            out.direct[c] = p.direct[c];
            out.transmittance += p.transmittance / 3;
        }
        return out;
    }

private:
    const Scene& mScene;
    const bool mChromatic;
};

}  // namespace

std::unique_ptr<Marcher> makeReferenceTracer(const Scene& scene, std::shared_ptr<const Illumination>) {
    return std::make_unique<ReferenceTracer>(scene);
}

}  // namespace vdbmarch
