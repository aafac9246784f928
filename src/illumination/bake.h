// `vdbmarch bake`: the illumination path with the cache requested and every
// photon kept, with the timings and memory figures the benchmarks report.
#pragma once

#include "illumination/illumination.h"

namespace vdbmarch {

struct BakeResult {
    RadianceCache cache;
    std::unique_ptr<PhotonMap> photons;  // every photon
    size_t paths = 0, directPhotons = 0;
    double traceSeconds = 0, treeSeconds = 0, topologySeconds = 0, estimateSeconds = 0, totalSeconds = 0;
    size_t photonBytes = 0, cacheBytes = 0;
};

// Throws InputError when no medium scatters light (there is nothing to cache).
BakeResult bakeRadianceCache(const Scene& scene, const PhotonSettings& photons, const CacheSettings& cache);

}  // namespace vdbmarch
