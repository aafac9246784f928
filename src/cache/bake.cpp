#include "cache/bake.h"

#include <chrono>

#include "core/error.h"

namespace vdbmarch {

BakeResult bakeRadianceCache(const Scene& scene, const PhotonSettings& ps, const CacheSettings& cs) {
    using Clock = std::chrono::steady_clock;
    auto start = Clock::now();
    if (!sceneScatters(scene))
        throw InputError(str(scene.desc.file, ": no medium scatters light (every sigma_s is 0 or every density "
                                              "is 0): there is no in-scattered radiance to cache"));
    BakeResult r;
    PhotonSet set = tracePhotons(scene, size_t(ps.count), ps.seedFor(scene.desc.render.seed));
    r.traceSeconds = set.seconds;
    r.paths = set.paths;
    r.directPhotons = set.directCount;
    auto treeStart = Clock::now();
    r.photons = std::make_unique<PhotonMap>(std::move(set.photons));
    r.treeSeconds = std::chrono::duration<double>(Clock::now() - treeStart).count();
    CacheBuildStats stats;
    r.cache = buildRadianceCache(scene, *r.photons, r.paths, cs, ps.k, &stats);
    r.cache.info.seed = ps.seedFor(scene.desc.render.seed);
    r.topologySeconds = stats.topologySeconds;
    r.estimateSeconds = stats.estimateSeconds;
    r.photonBytes = r.photons->memoryBytes();
    r.cacheBytes = r.cache.memoryBytes();
    r.totalSeconds = std::chrono::duration<double>(Clock::now() - start).count();
    r.cache.info.buildSeconds = r.totalSeconds;
    return r;
}

void checkCacheMatchesScene(const RadianceCache& cache, const Scene& scene, const std::string& file, bool force) {
    std::string expected = sceneHash(scene.desc);
    if (cache.info.sceneHash == expected) return;
    std::string msg = str(file, ": the cache was baked for another scene (scene_hash ", cache.info.sceneHash,
                          ", this scene has ", expected, "): media, lights, surfaces, background or max_depth differ");
    if (!force) throw InputError(msg + "; bake it again, or pass --force to use it anyway");
    warn(msg + "; used anyway (--force)");
}

}  // namespace vdbmarch
