#include "illumination/illumination.h"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "cache/cache_build.h"
#include "core/error.h"
#include "core/rng.h"
#include "photons/kernel_volume.h"
#include "photons/photon_tracer.h"
#include "transport/surface_event.h"

namespace vdbmarch {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
}  // namespace

bool methodUsesCache(Method method, const RenderSettings& render) {
    return method == Method::Guided ||
           (render.li == LiSource::Cache && !isPathTracer(method));
}

void checkCacheMatchesScene(const RadianceCache& cache, const Scene& scene, const std::string& file, bool force) {
    std::string expected = sceneHash(scene.desc);
    if (cache.info.sceneHash == expected) return;
    std::string msg = str(file, ": the cache was baked for another scene (scene_hash ", cache.info.sceneHash,
                          ", this scene has ", expected, "): media, lights, surfaces, background or max_depth differ");
    if (!force) throw InputError(msg + "; bake it again, or pass --force to use it anyway");
    warn(msg + "; used anyway (--force)");
}

namespace {

// The photons L_i takes beside shadow rays (see IlluminationRequest).
bool wantedInMap(const Photon& p, const IlluminationRequest& rq) {
    if (rq.exceptConnected && p.isConnected()) return false;
    return rq.causticsOnly ? p.isCaustic() || (rq.pointLightsByPhotons && p.isFromPointLight() && !p.isDirect())
                           : !p.isDirect();
}

std::unique_ptr<PhotonMap> indirectMap(const std::vector<Photon>& photons, const IlluminationRequest& rq) {
    size_t count = 0;
    for (const Photon& p : photons) count += wantedInMap(p, rq);
    if (count == 0) return nullptr;
    std::vector<Photon> kept;
    kept.reserve(count);
    for (const Photon& p : photons)
        if (wantedInMap(p, rq)) kept.push_back(p);
    return std::make_unique<PhotonMap>(std::move(kept), PhotonMap::Search::ByRegion);
}

// Photon pass `pass`'s batch: pass 0 takes the photon seed itself (so a
// single-pass render is what it always was), later passes independent
// streams from it.
uint64_t batchSeed(const IlluminationRequest& rq, int pass) {
    const uint64_t seed = rq.photons.seedFor(rq.renderSeed);
    return pass == 0 ? seed : hashValues(seed, 0x70617373ull, uint64_t(pass));
}

bool refinesCacheAt(int pass) { return pass > 0 && ((pass + 1) & pass) == 0; }  // passes 1, 3, 7, 15, ...

}  // namespace

Color Illumination::photonLi(const Scene& scene, const Vec3& x, int region, const Vec3& wo,
                             const PhaseMixture& phase) const {
    if (!indirect) return Color(0);
    float radius = 0;
    const Color L = indirect->estimateLi(x, wo, size_t(k), [&](float c) { return phase.eval(c); }, &radius,
                                         radiusScale, region);
    return isBlack(L) ? L : L / kernelFractionInside(scene, x, radius);
}

Illumination buildIllumination(const Scene& scene, const IlluminationRequest& rq) {
    const auto start = Clock::now();
    Illumination il;
    il.k = rq.photons.k;
    il.li = scene.desc.render.li;
    il.pointLightsByPhotons = rq.pointLightsByPhotons;
    il.causticsOnly = rq.indirect && rq.causticsOnly;
    if (!sceneScatters(scene)) return il;  // no L_i anywhere: nothing to trace or cache
    bool needCache = rq.cache;
    if (needCache && !rq.cacheFile.empty()) {
        RadianceCache c = RadianceCache::load(rq.cacheFile);
        checkCacheMatchesScene(c, scene, rq.cacheFile, rq.force);
        il.cache = std::make_unique<RadianceCache>(std::move(c));
        il.cacheLoaded = true;
        needCache = false;
    }
    if (needCache || rq.indirect || rq.keepAllPhotons) {
        const uint64_t seed = batchSeed(rq, 0);
        PhotonSet set = tracePhotons(scene, size_t(rq.photons.count), seed);
        IlluminationStats& st = il.stats;
        st.traceSeconds = set.seconds;
        st.paths = set.paths;
        st.photons = set.photons.size();
        st.directPhotons = set.directCount;
        const auto treeStart = Clock::now();
        if (rq.indirect) {
            il.indirect = indirectMap(set.photons, rq);
            if (il.indirect) st.photonBytes += il.indirect->memoryBytes();
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

double progressiveRadiusScale(int pass, double alpha) {
    // r_j^3 / r_0^3 = prod_{i=1}^{j} (i + alpha) / (i + 1)
    //             = Gamma(j + 1 + alpha) / (Gamma(1 + alpha) Gamma(j + 2)).
    if (pass <= 0) return 1;
    const double j = double(pass);
    return std::exp((std::lgamma(j + 1 + alpha) - std::lgamma(1 + alpha) - std::lgamma(j + 2)) / 3);
}

PhotonPasses::PhotonPasses(const Scene& scene, const IlluminationRequest& rq, int pixels) : mRequest(rq) {
    const bool buildsCache = rq.cache && rq.cacheFile.empty();
    mProgressive = rq.photons.progressive && sceneScatters(scene) && rq.photons.count > 0 && (rq.indirect || buildsCache);
    mSamplesPerPass = rq.photons.sppPerPass > 0
                          ? rq.photons.sppPerPass
                          : int(std::max<int64_t>(1, (rq.photons.count + 4 * int64_t(std::max(1, pixels)) - 1) /
                                                             (4 * int64_t(std::max(1, pixels)))));
}

bool PhotonPasses::needsWork(int pass) const {
    return mProgressive && pass > 0 && (mRequest.indirect || (refinesCacheAt(pass) && mRequest.cache));
}

bool PhotonPasses::advance(const Scene& scene, int pass, Illumination& il) const {
    if (pass == il.photonPass) return false;
    if (pass < il.photonPass) throw std::logic_error("PhotonPasses::advance: passes only go forward");
    // A jump over passes (a render of a later range of passes, render
    // --passes) still makes the cache refinements of the passes it skips,
    // from their own batches, so the cache of pass j is the same whichever
    // pass a render started from.
    bool changed = false;
    for (int k = il.photonPass + 1; k < pass; ++k)
        if (refinesCacheAt(k) && il.cache && !il.cacheLoaded) changed |= tracePass(scene, k, false, il);
    il.photonPass = pass;
    il.radiusScale = float(progressiveRadiusScale(pass, mRequest.photons.alpha));
    return tracePass(scene, pass, mRequest.indirect, il) || changed;
}

bool PhotonPasses::tracePass(const Scene& scene, int pass, bool makeMap, Illumination& il) const {
    const bool refine = refinesCacheAt(pass) && il.cache && !il.cacheLoaded;
    if (!makeMap && !refine) return false;
    const auto start = Clock::now();
    PhotonSet set = tracePhotons(scene, size_t(mRequest.photons.count), batchSeed(mRequest, pass));
    IlluminationStats& st = il.stats;
    st.traceSeconds += set.seconds;
    st.paths += set.paths;
    st.photons += set.photons.size();
    st.directPhotons += set.directCount;
    ++st.batches;
    if (makeMap) il.indirect = indirectMap(set.photons, mRequest);
    if (refine) {
        const auto estimateStart = Clock::now();
        PhotonMap all(std::move(set.photons));
        refineRadianceCache(scene, all, set.paths, mRequest.photons.k, *il.cache);
        st.estimateSeconds += secondsSince(estimateStart);
    }
    st.seconds += secondsSince(start);
    return refine;
}

IlluminationRequest illuminationRequest(const Scene& scene, Method method, const IlluminationOptions& options) {
    const RenderSettings& rs = scene.desc.render;
    IlluminationRequest rq;
    rq.photons = scene.desc.photons;
    rq.cacheSettings = scene.desc.cache;
    rq.renderSeed = rs.seed;
    rq.force = options.force;
    const bool bendingGlass = hasBendingGlass(scene);
    bool deltaLight = false, pointLight = false;
    for (const Light& l : scene.lights) {
        deltaLight = deltaLight || l.isDelta();
        pointLight = pointLight || l.isPointLike();
    }
    // Caustics of delta lights through refracting glass, which no path can
    // find, come from the caustic photons; through glass spheres, sphere
    // caustic connections find them where Scene::deltaLightCaustics holds.
    // So do sphere lights' where Scene::sphereLightCausticPhotons holds, for
    // the marchers: the reference keeps its paths for them (unbiased, and
    // photon passes every few samples hold back its timed adaptive sampling
    // where most pixels see no glass; docs/method.md).
    auto requestCaustics = [&](bool sphereLights) {
        rq.indirect = (bendingGlass && deltaLight && !scene.deltaLightCaustics) ||
                      (sphereLights && scene.sphereLightCausticPhotons);
        rq.causticsOnly = true;
        rq.exceptConnected = scene.deltaLightCaustics;
    };
    if (method == Method::Reference) {  // paths, and photons for what they cannot find; render.li does not apply
        if (!options.cacheFile.empty()) warn(str(options.cacheFile, ": the reference tracer does not read a cache; ignored"));
        requestCaustics(false);
        return rq;
    }
    rq.cache = methodUsesCache(method, rs);
    if (rq.cache) rq.cacheFile = options.cacheFile;
    // A cache file that this method and render.li leave unread is named.
    if (!rq.cache && !options.cacheFile.empty())
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
    if (rs.li == LiSource::Photons) rq.indirect = rs.maxDepth > 1 || bendingGlass;
    if (rs.li == LiSource::Path) {
        requestCaustics(true);
        rq.indirect = rq.indirect || (pointLight && rs.maxDepth > 1);
        rq.pointLightsByPhotons = pointLight && rq.indirect;
    }
    return rq;
}

Illumination prepareIllumination(const Scene& scene, Method method, const IlluminationOptions& options) {
    return buildIllumination(scene, illuminationRequest(scene, method, options));
}

}  // namespace vdbmarch
