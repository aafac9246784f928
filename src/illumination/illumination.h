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
#include "transport/phase.h"

namespace vdbmarch {

// What to build, and from which settings.
struct IlluminationRequest {
    bool indirect = false;     // the map of photons for L_i beside shadow rays (and paths)
    // render.li = "path": only the caustic photons, and the non-direct ones
    // of point and spot lights; without those sphere caustic connections
    // find at the marchers' L_i samples (Photon::Connected) when
    // exceptConnected.
    bool causticsOnly = false;
    bool exceptConnected = false;
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
    int batches = 1;     // photon batches traced (progressive passes)
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
    // indirect holds only caustic photons (and those of pointLightsByPhotons):
    // a path tracer adds them at its first medium vertex.
    bool causticsOnly = false;
    LiSource li = LiSource::Photons;
    bool cacheLoaded = false;  // from a baked file: never refined
    // Progressive photon pass the map belongs to, and its gather radius
    // relative to the k-nearest sphere (PhotonPasses).
    int photonPass = 0;
    float radiusScale = 1;
    IlluminationStats stats;

    // Eq. 4 at x (in medium region `region`) towards wo over the current
    // pass's map `indirect`, its k nearest photons of that region gathered
    // within the pass's radius, over the part of the sphere in the region
    // (photons/kernel_volume.h); 0 without a map.
    Color photonLi(const Scene& scene, const Vec3& x, int region, const Vec3& wo, const PhaseMixture& phase) const;
};

// The one path: traces photons when anything needs them, builds the kd-trees
// and the cache (or loads it, checked against the scene). Nothing is traced
// when no medium scatters.
Illumination buildIllumination(const Scene& scene, const IlluminationRequest& request);

// Progressive photon mapping (Knaus & Zwicker 2011, "Progressive photon
// mapping: a probabilistic approach"): camera samples [j B, (j + 1) B) use
// photon pass j, B = samplesPerPass(). Each pass traces an independent batch
// (its own seed), so the average over passes of the photon estimates is an
// average of independent estimates; the gather radius of pass j is
// progressiveRadiusScale(j) times the k-nearest radius, shrinking as
// r_j^3 = r_{j-1}^3 (j + alpha) / (j + 1), so that bias and variance of the
// average both go to zero (the variance of pass j grows as 1 / r_j^3, the
// sum grows slower than passes^2). The radiance cache is refined, not
// rebuilt, at passes 1, 3, 7, ...: the guide improves with time at a
// logarithmic cost. The image depends only on the sample count.
double progressiveRadiusScale(int pass, double alpha);

class PhotonPasses {
public:
    PhotonPasses(const Scene& scene, const IlluminationRequest& request, int pixels);
    bool progressive() const { return mProgressive; }
    int samplesPerPass() const { return mSamplesPerPass; }
    int passOf(int sample) const { return mProgressive ? sample / mSamplesPerPass : 0; }
    int firstSampleOf(int pass) const { return pass * mSamplesPerPass; }
    // True when moving to `pass` traces photons (a new map or a refinement).
    bool needsWork(int pass) const;
    // Brings `il` (built by buildIllumination from the same request) to
    // `pass`: its radius, its own batch and map, and the cache refinements
    // up to it (those of skipped passes too).
    // Returns true when the cache changed (what a guided marcher measured
    // from it must be measured again); the map and radius are read live.
    bool advance(const Scene& scene, int pass, Illumination& il) const;

private:
    // Traces pass `pass`'s batch when it makes the map (`makeMap`) or
    // refines the cache; true when the cache changed.
    bool tracePass(const Scene& scene, int pass, bool makeMap, Illumination& il) const;
    IlluminationRequest mRequest;
    bool mProgressive = false;
    int mSamplesPerPass = 1;
};

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
