#include "illumination/illumination.h"

#include <chrono>

#include "cache/cache_build.h"
#include "core/error.h"
#include "photons/photon_tracer.h"
#include "transport/surface_event.h"

namespace vdbmarch {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
}  // namespace

bool methodUsesCache(Method method, const RenderSettings& render) {
    return method == Method::Guided || render.li == LiSource::Cache;
}

void checkCacheMatchesScene(const RadianceCache& cache, const Scene& scene, const std::string& file, bool force) {
    std::string expected = sceneHash(scene.desc);
    if (cache.info.sceneHash == expected) return;
    std::string msg = str(file, ": the cache was baked for another scene (scene_hash ", cache.info.sceneHash,
                          ", this scene has ", expected, "): media, lights, surfaces, background or max_depth differ");
    if (!force) throw InputError(msg + "; bake it again, or pass --force to use it anyway");
    warn(msg + "; used anyway (--force)");
}

Illumination buildIllumination(const Scene& scene, const IlluminationRequest& rq) {
    const auto start = Clock::now();
    Illumination il;
    il.k = rq.photons.k;
    il.li = scene.desc.render.li;
    il.pointLightsByPhotons = rq.pointLightsByPhotons;
    if (!sceneScatters(scene)) return il;  // no L_i anywhere: nothing to trace or cache
    bool needCache = rq.cache;
    if (needCache && !rq.cacheFile.empty()) {
        RadianceCache c = RadianceCache::load(rq.cacheFile);
        checkCacheMatchesScene(c, scene, rq.cacheFile, rq.force);
        il.cache = std::make_unique<RadianceCache>(std::move(c));
        needCache = false;
    }
    if (needCache || rq.indirect || rq.keepAllPhotons) {
        const uint64_t seed = rq.photons.seedFor(rq.renderSeed);
        PhotonSet set = tracePhotons(scene, size_t(rq.photons.count), seed);
        IlluminationStats& st = il.stats;
        st.traceSeconds = set.seconds;
        st.paths = set.paths;
        st.photons = set.photons.size();
        st.directPhotons = set.directCount;
        const auto treeStart = Clock::now();
        auto wanted = [&](const Photon& p) {
            return rq.causticsOnly ? p.isCaustic() || (p.isFromPointLight() && !p.isDirect()) : !p.isDirect();
        };
        size_t count = 0;
        for (const Photon& p : set.photons) count += wanted(p);
        if (rq.indirect && count > 0) {
            std::vector<Photon> indirect;
            indirect.reserve(count);
            for (const Photon& p : set.photons)
                if (wanted(p)) indirect.push_back(p);
            il.indirect = std::make_unique<PhotonMap>(std::move(indirect));
            st.photonBytes += il.indirect->memoryBytes();
        }
        if (needCache || rq.keepAllPhotons) {
            // The cache approximates all of L_i (direct and scattered), as
            // the pdf of eq. 16 needs.
            auto all = std::make_unique<PhotonMap>(std::move(set.photons));
            st.treeSeconds = secondsSince(treeStart);
            st.photonBytes += all->memoryBytes();
            if (needCache) {
                CacheBuildStats cs;
                il.cache = std::make_unique<RadianceCache>(
                    buildRadianceCache(scene, *all, set.paths, rq.cacheSettings, rq.photons.k, &cs));
                il.cache->info.seed = seed;
                st.topologySeconds = cs.topologySeconds;
                st.estimateSeconds = cs.estimateSeconds;
            }
            if (rq.keepAllPhotons) il.all = std::move(all);
        } else {
            st.treeSeconds = secondsSince(treeStart);
        }
    }
    if (il.cache) il.stats.cacheBytes = il.cache->memoryBytes();
    il.stats.seconds = secondsSince(start);
    if (il.cache && needCache) il.cache->info.buildSeconds = il.stats.seconds;
    return il;
}

IlluminationRequest illuminationRequest(const Scene& scene, Method method, const IlluminationOptions& options) {
    const RenderSettings& rs = scene.desc.render;
    IlluminationRequest rq;
    rq.photons = scene.desc.photons;
    rq.cacheSettings = scene.desc.cache;
    rq.renderSeed = rs.seed;
    rq.force = options.force;
    if (method == Method::Reference) {  // traces every path itself; render.li does not apply
        if (!options.cacheFile.empty()) warn(str(options.cacheFile, ": the reference tracer does not read a cache; ignored"));
        return rq;
    }
    rq.cache = methodUsesCache(method, rs);
    if (rq.cache) rq.cacheFile = options.cacheFile;
    else if (!options.cacheFile.empty())
        warn(str(options.cacheFile, ": method ", methodName(method), " with render.li = \"", liSourceName(rs.li),
                 "\" does not read the cache; ignored"));
    // Shadow rays compute the direct light. With photons, the photon map
    // adds the rest, which exists when light may scatter before the last
    // event, or pass refracting glass (a caustic, even for single
    // scattering). With paths, photons add only the caustics of delta
    // lights, which no path can find.
    // Point and spot lights are the exception: next-event estimation at
    // path vertices near them has unbounded variance (1/d^2), so photons
    // carry their multiply scattered light too.
    const bool bendingGlass = hasBendingGlass(scene);
    bool deltaLight = false, pointLight = false;
    for (const Light& l : scene.lights) {
        deltaLight = deltaLight || l.isDelta();
        pointLight = pointLight || l.isPointLike();
    }
    if (rs.li == LiSource::Photons) rq.indirect = rs.maxDepth > 1 || bendingGlass;
    if (rs.li == LiSource::Path) {
        rq.indirect = (bendingGlass && deltaLight) || (pointLight && rs.maxDepth > 1);
        rq.causticsOnly = true;
        rq.pointLightsByPhotons = pointLight && rq.indirect;
    }
    return rq;
}

Illumination prepareIllumination(const Scene& scene, Method method, const IlluminationOptions& options) {
    return buildIllumination(scene, illuminationRequest(scene, method, options));
}

}  // namespace vdbmarch
