// What the marchers share to estimate in-scattered radiance L_i at their
// sample points, prepared once per render: the photon map of non-direct
// photons (the light that shadow rays cannot follow: multiple scattering and
// caustics through glass, eq. 4) and the radiance cache (the guided
// marcher's pdf, or L_i itself with render.li = "cache").
#pragma once

#include <memory>
#include <string>

#include "cache/radiance_cache.h"
#include "photons/photon_map.h"
#include "scene/scene.h"

namespace vdbmarch {

struct Illumination {
    std::unique_ptr<PhotonMap> indirect;   // non-direct photons; null when none can exist
    std::unique_ptr<RadianceCache> cache;  // null unless the method or render.li needs it
    int k = 50;                            // photons per estimate
    bool liFromCache = false;              // render.li = "cache"
    size_t photons = 0;                    // photons stored (statistics)
    double seconds = 0;                    // photon tracing, kd-trees and cache build
};

struct IlluminationOptions {
    std::string cacheFile;  // load the cache from here instead of building it
    bool force = false;     // use a cache baked for another scene
};

// Traces photons and builds what `method` and render.li need (nothing for the
// reference tracer, nor when no medium scatters). Throws InputError for a
// cache file that is damaged or belongs to another scene (unless forced).
Illumination prepareIllumination(const Scene& scene, const std::string& method,
                                 const IlluminationOptions& options = {});

// True when `method` or render.li reads the cache.
bool methodUsesCache(const std::string& method, const RenderSettings& render);

}  // namespace vdbmarch
