#include "paths/first_event.h"

#include <algorithm>

#include "transport/tracking.h"

namespace vdbmarch {

FirstEventTracer::FirstEventTracer(const Scene& scene)
    : mScene(scene), mChromatic(hasChromaticExtinction(scene)), mPaths(scene, std::make_shared<StrategySet>(), [] {
          PathOptions o;
          o.maxDepth = 0;
          return o;
      }()) {}

FirstEvent FirstEventTracer::trace(ThreadContext& ctx, const Ray& cameraRay, Rng& rng) const {
    PathState start;
    start.spectral = startingHero(mChromatic, rng);
    const RenderCounters counters = ctx.counters;
    const FirstEvent e = mPaths.trace(ctx, cameraRay, regionAtRayStart(mScene, cameraRay), rng, start).first;
    ctx.counters = counters;
    return e;
}

}  // namespace vdbmarch
