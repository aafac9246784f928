// The feature AOVs (render.aovs depth, albedo, normal; docs/aovs.md): a path
// of the one loop (path_tracer.h) that ends at its first scattering event
// (max_depth 0), with no sampling strategies, glass followed by the
// material's own choice, on a random stream of its own so that the beauty
// never changes. The same for every method.
#pragma once

#include "paths/path_tracer.h"

namespace vdbmarch {

class FirstEventTracer {
public:
    explicit FirstEventTracer(const Scene& scene);
    // Chromatic extinction: spectral MIS from a hero channel picked
    // uniformly, as the reference's paths. Not counted in the render's
    // statistics.
    FirstEvent trace(ThreadContext& ctx, const Ray& cameraRay, Rng& rng) const;

private:
    const Scene& mScene;
    const bool mChromatic;
    PathTracer mPaths;
};

}  // namespace vdbmarch
