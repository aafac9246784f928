// Guided path tracing's guide (path_guide.h) from the paper's radiance
// cache: eq. 16 applied to every path segment instead of the camera ray
// alone, and the cached incident radiance for directions.
//
// Free flights. The segment's active part is cut into bins of the cache's
// finest cell (at most MaxFlightBins); per bin the media at its midpoint
// give kappa and sigma_s, and the bins' product of e^{-kappa len} an
// approximate transmittance T~ (exact in constant media). The scattering
// collision is drawn from
//
//   p(t) = eps p_T(t) + (1 - eps) p_T(t) h(t) / E[h],   p_T ~ sigma_s T~  (eq. 16),
//
// h the cached in-scattered radiance towards the ray's origin in the bin
// (CacheLookup), a truncated exponential inside the bin, with probability
// P_s = 1 - T~(tEnd) (the analog probability of a collision; at most
// 1 - MinPassThrough); else the path passes to tEnd. A small floor on every bin's
// weight keeps the support whole where a midpoint misses a gridded
// medium's density. The weights use the true sigma_s at the collision and
// T by ratio tracking, so the estimator is unbiased for any cache, in
// heterogeneous VDB media too (docs/method.md). Renders sample guided flights
// only in regions of one homogeneous medium, where T~ is exact: in a VDB
// cloud the ratio of T to T~ at the collision (ratio-tracked T, midpoint
// bins) made the MSE 36x that of delta tracking on cloud_sun at 16 spp, and
// still 3.6x with bins of half a voxel, no cache share and T by unbiased ray
// marching (BENCHMARKS.md), so gridded media keep delta tracking.
//
// Roulette (render.guided_roulette). The camera path's first segment through
// media gives the pixel's estimate, int sigma_s T~ h dt plus the background
// seen through T~; at every medium vertex the path's expected contribution is
// its throughput times the cached L_i(x, -ray.d) (transport/roulette.h).
//
// Directions. Phase x the cell's non-direct incident light (a few von
// Mises-Fisher lobes fitted to the photons) with a defensive phase share
// (ProductDirectionSampler), when the cache holds lobes
// (render.product_sampling).
#pragma once

#include <memory>

#include "cache/radiance_cache.h"
#include "scene/scene.h"
#include "transport/path_guide.h"

namespace vdbmarch {

std::unique_ptr<PathGuide> makeCachePathGuide(const Scene& scene, const RadianceCache& cache);

}  // namespace vdbmarch
