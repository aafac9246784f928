#include "marchers/illumination.h"

#include <chrono>

#include "cache/bake.h"
#include "core/error.h"
#include "photons/photon_tracer.h"

namespace vdbmarch {

bool methodUsesCache(const std::string& method, const RenderSettings& render) {
    return method == "guided" || render.li == "cache";
}

Illumination prepareIllumination(const Scene& scene, const std::string& method, const IlluminationOptions& options) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    const RenderSettings& rs = scene.desc.render;
    Illumination il;
    il.k = scene.desc.photons.k;
    il.liFromCache = rs.li == "cache";
    if (method == "reference") {  // traces every path itself; render.li does not apply
        if (!options.cacheFile.empty()) warn(str(options.cacheFile, ": the reference tracer does not read a cache; ignored"));
        return il;
    }
    bool needCache = methodUsesCache(method, rs);
    if (!needCache && !options.cacheFile.empty())
        warn(str(options.cacheFile, ": method ", method, " with render.li = \"", rs.li,
                 "\" does not read the cache; ignored"));
    if (!sceneScatters(scene)) return il;  // no L_i anywhere: nothing to trace or cache
    if (needCache && !options.cacheFile.empty()) {
        RadianceCache c = RadianceCache::load(options.cacheFile);
        checkCacheMatchesScene(c, scene, options.cacheFile, options.force);
        il.cache = std::make_unique<RadianceCache>(std::move(c));
        needCache = false;
    }
    // Shadow rays compute the direct light; the photon map adds the rest,
    // which exists only when light may scatter before the last event.
    const bool needIndirect = !il.liFromCache && rs.maxDepth > 1;
    if (needCache || needIndirect) {
        PhotonSet set = tracePhotons(scene, size_t(scene.desc.photons.count), scene.desc.photons.seedFor(rs.seed));
        il.photons = set.photons.size();
        if (needIndirect && set.directCount < set.photons.size()) {
            std::vector<Photon> indirect;
            indirect.reserve(set.photons.size() - set.directCount);
            for (const Photon& p : set.photons)
                if (!p.isDirect()) indirect.push_back(p);
            il.indirect = std::make_unique<PhotonMap>(std::move(indirect));
        }
        if (needCache) {
            // The cache approximates all of L_i (direct and scattered), as
            // the pdf of eq. 16 needs.
            PhotonMap all(std::move(set.photons));
            il.cache = std::make_unique<RadianceCache>(
                buildRadianceCache(scene, all, set.paths, scene.desc.cache, il.k));
            il.cache->info.seed = scene.desc.photons.seedFor(rs.seed);
        }
    }
    il.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return il;
}

}  // namespace vdbmarch
