// Photon tracing plus cache building, as `vdbmarch bake` runs them, with the
// timings and memory figures that the benchmarks report; and the check that
// a cache loaded from disk belongs to the scene it is used with.
#pragma once

#include <string>

#include "cache/cache_build.h"
#include "photons/photon_tracer.h"

namespace vdbmarch {

struct BakeResult {
    RadianceCache cache;
    std::unique_ptr<PhotonMap> photons;  // null when nothing scatters
    size_t paths = 0, directPhotons = 0;
    double traceSeconds = 0, treeSeconds = 0, topologySeconds = 0, estimateSeconds = 0, totalSeconds = 0;
    size_t photonBytes = 0, cacheBytes = 0;
};

// Throws InputError when no medium scatters light (there is nothing to cache).
BakeResult bakeRadianceCache(const Scene& scene, const PhotonSettings& photons, const CacheSettings& cache);

// Throws InputError naming the file when the cache was made for another
// scene (scene hash) unless `force`; warns when forced.
void checkCacheMatchesScene(const RadianceCache& cache, const Scene& scene, const std::string& file, bool force);

}  // namespace vdbmarch
