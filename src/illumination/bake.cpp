#include "illumination/bake.h"

#include "core/error.h"
#include "photons/photon_tracer.h"

namespace vdbmarch {

BakeResult bakeRadianceCache(const Scene& scene, const PhotonSettings& ps, const CacheSettings& cs) {
    if (!sceneScatters(scene))
        throw InputError(str(scene.desc.file, ": no medium scatters light (every sigma_s is 0 or every density "
                                              "is 0): there is no in-scattered radiance to cache"));
    IlluminationRequest rq;
    rq.cache = true;
    rq.keepAllPhotons = true;
    rq.photons = ps;
    rq.cacheSettings = cs;
    rq.renderSeed = scene.desc.render.seed;
    Illumination il = buildIllumination(scene, rq);
    BakeResult r;
    r.cache = std::move(*il.cache);
    r.photons = std::move(il.all);
    const IlluminationStats& s = il.stats;
    r.paths = s.paths;
    r.directPhotons = s.directPhotons;
    r.traceSeconds = s.traceSeconds;
    r.treeSeconds = s.treeSeconds;
    r.topologySeconds = s.topologySeconds;
    r.estimateSeconds = s.estimateSeconds;
    r.totalSeconds = s.seconds;
    r.photonBytes = s.photonBytes;
    r.cacheBytes = s.cacheBytes;
    return r;
}

}  // namespace vdbmarch
