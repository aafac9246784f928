// What a render precomputes, for render and bake alike: photons -> kd-tree
// -> radiance cache, in one path. The marchers estimate L_i at their samples
// from it: the photon map of non-direct photons (the light that shadow rays
// cannot follow: multiple scattering and caustics through glass, eq. 4) and
// the radiance cache (the guided marcher's pdf, or L_i itself with
// render.li = "cache").
#pragma once

#include <memory>
#include <string>

#include "cache/radiance_cache.h"
#include "photons/photon_map.h"
#include "scene/scene.h"

namespace vdbmarch {

// What to build, and from which settings.
struct IlluminationRequest {
    bool indirect = false;     // the map of photons for L_i beside shadow rays (and paths)
    // render.li = "path": only the caustic photons, and the non-direct ones
    // of point and spot lights.
    bool causticsOnly = false;
    bool cache = false;        // the radiance cache
    bool keepAllPhotons = false;  // keep the map of every photon (bake, tests)
    PhotonSettings photons;
    CacheSettings cacheSettings;
    uint64_t renderSeed = 0;  // photons.seed falls back to it
    std::string cacheFile;    // load the cache from here instead of building it
    bool force = false;       // use a cache baked for another scene
    bool pointLightsByPhotons = false;  // see Illumination
};

struct IlluminationStats {
    size_t paths = 0, photons = 0, directPhotons = 0;
    double traceSeconds = 0, treeSeconds = 0, topologySeconds = 0, estimateSeconds = 0;
    double seconds = 0;  // all of it
    size_t photonBytes = 0, cacheBytes = 0;
};

struct Illumination {
    // The photons L_i takes beside shadow rays: the non-direct ones
    // (render.li = "photons"), or the caustic ones (render.li = "path"); null
    // when none can exist.
    std::unique_ptr<PhotonMap> indirect;
    std::unique_ptr<PhotonMap> all;        // every photon, only with keepAllPhotons
    std::unique_ptr<RadianceCache> cache;  // null unless requested
    int k = 50;                            // photons per estimate
    bool pointLightsByPhotons = false;     // "path": indirect carries point and spot lights' scattered light
    LiSource li = LiSource::Photons;
    IlluminationStats stats;
};

// The one path: traces photons when anything needs them, builds the kd-trees
// and the cache (or loads it, checked against the scene). Nothing is traced
// when no medium scatters.
Illumination buildIllumination(const Scene& scene, const IlluminationRequest& request);

// What `method` and render.li need (nothing for the reference tracer).
struct IlluminationOptions {
    std::string cacheFile;  // a baked cache to use (render --cache)
    bool force = false;
};
IlluminationRequest illuminationRequest(const Scene& scene, Method method, const IlluminationOptions& options = {});
Illumination prepareIllumination(const Scene& scene, Method method, const IlluminationOptions& options = {});

// True when `method` or render.li reads the cache.
bool methodUsesCache(Method method, const RenderSettings& render);

// Throws InputError naming the file when the cache was made for another
// scene (scene hash) unless `force`; warns when forced.
void checkCacheMatchesScene(const RadianceCache& cache, const Scene& scene, const std::string& file, bool force);

}  // namespace vdbmarch
