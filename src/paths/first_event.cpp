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
    const int channel = mChromatic ? std::min(2, int(rng.uniform() * 3)) : -1;
    const RenderCounters counters = ctx.counters;
    const FirstEvent e = mPaths.trace(ctx, cameraRay, regionAtRayStart(mScene, cameraRay), channel, rng, PathState{}).first;
    ctx.counters = counters;
    return e;
}

}  // namespace vdbmarch
