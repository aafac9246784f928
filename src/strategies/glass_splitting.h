// Glass splitting (experiments.glass_splitting), a surface strategy: a small
// light mirrored in glass is a highlight a thousand times its surroundings'
// brightness, which the Fresnel choice (reflect with chance F, a few
// percent) finds in a few of a pixel's samples. So at a glass event
//  - a camera path's first SplitDielectricEvents glass events follow both
//    outcomes, weighted F and 1 - F (the caller traces the reflection);
//  - every other one counts what its reflection sees at the end of its first
//    segment (a sphere light or the background, times the transmittance)
//    weighted by F: where the reflection crosses no medium that is all it
//    brings, and the path goes on by refraction weighted 1 - F; else the
//    path makes the Fresnel choice and, taking the reflection, skips that
//    light.
// Both have the Fresnel choice's expectation (docs/method.md, "Glass
// highlights"). Other surfaces are left to their material's sampling.
#pragma once

#include "strategies/strategy.h"

namespace vdbmarch {

class GlassSplitting final : public SurfaceStrategy {
public:
    bool sample(ThreadContext& ctx, const SurfaceHit& hit, const Vec3& d, int region, const float u[3],
                const SurfaceRequest& request, Rng& rng, PathSurfaceEvent& out) const override;
};

// The event at `hit` by the material's own sampling (the Fresnel choice at
// glass): what a path meets where no surface strategy takes the hit.
PathSurfaceEvent materialSurfaceEvent(const Scene& scene, const SurfaceHit& hit, const Vec3& d, int region,
                                      const float u[3]);

}  // namespace vdbmarch
