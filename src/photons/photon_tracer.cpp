#include "photons/photon_tracer.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/memory.h"
#include "core/sampling.h"
#include "transport/media_point.h"
#include "transport/roulette.h"
#include "strategies/sphere_caustics.h"
#include "transport/surface_event.h"
#include "transport/tracking.h"

namespace vdbmarch {

namespace {

// A light, the background or an emissive medium. sample() gives a photon
// whose power is an unbiased estimate of the source's total power.
struct PhotonSource {
    PhotonEmitter emitter;                    // lights and the background
    std::unique_ptr<EmissionSampler> volume;  // emissive media
    int medium = -1;
    Color power{0, 0, 0};  // allocation weight
    bool deltaLight = false;  // a point, spot, directional or collimated light
    // Its light bent by glass before any scattering is a caustic photon:
    // delta lights always, sphere lights where Scene::sphereLightCausticPhotons.
    bool causticsByPhotons = false;
    bool pointLight = false;  // a point or spot light
    size_t first = 0, count = 0;  // its range of path indices
};

bool scatters(const Medium& m) { return !m.isVacuum() && !isBlack(m.sigma_s); }

// Paths are cut into fixed chunks so the photon order (and the per-path
// random streams) do not depend on how TBB schedules them.
constexpr size_t ChunkPaths = 2048;

class PhotonTracer {
public:
    PhotonTracer(const Scene& scene, uint64_t seed)
        : mScene(scene), mSeed(seed), mChromatic(hasChromaticExtinction(scene)) {}

    // Traces path `index` of `source`, appending its photons.
    void tracePath(ThreadContext& ctx, const PhotonSource& src, size_t index, std::vector<Photon>& out) const {
        Rng rng(hashValues(mSeed, 0x70686f746f6e73ULL, index));
        float u[4] = {rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()};
        EmittedPhoton ep;
        Color power;
        if (src.volume) {
            Vec3 p;
            float pdf;
            src.volume->sample(u, p, pdf);
            if (!(pdf > 0)) return;
            const Medium& m = *mScene.media[size_t(src.medium)];
            float rho = ctx.queries[size_t(src.medium)]->density(p);
            float e = ctx.queries[size_t(src.medium)]->emission(p);
            if (!(rho > 0 && e > 0)) return;
            // Isotropic emission: 4 pi sigma_a rho L_e per unit volume.
            ep.power = m.blackbody ? m.sigma_a * m.emitted(e) * (4 * Pi * rho / pdf)
                                   : m.sigma_a * m.emissionColor * (4 * Pi * rho * e / pdf);
            ep.ray = Ray{p, sampleUniformSphere(rng.uniform(), rng.uniform())};
        } else if (!src.emitter.sample(u, ep)) {
            return;
        }
        power = ep.power / float(src.count);
        if (!(maxComponent(power) > 0) || !std::isfinite(maxComponent(power))) return;
        // Chromatic extinction: spectral MIS from a hero channel, as the paths'.
        const HeroChannel spectral = startingHero(mChromatic, rng);
        // Light emitted inside a medium is never direct: no shadow ray samples it.
        follow(ctx, ep.ray, power, spectral, !src.volume, src, rng, out);
    }

private:
    // Follows a photon of power `power` from ray.o: stored at every real
    // collision in a medium (eq. 4), absorbed or scattered by the albedo,
    // surfaces by the shared surface event (importance transport).
    void follow(ThreadContext& ctx, Ray ray, const Color& power, HeroChannel spectral, bool direct, const PhotonSource& src,
                Rng& rng, std::vector<Photon>& out) const {
        const Scene& scene = mScene;
        const int maxDepth = scene.desc.render.maxDepth;
        int region = regionAtRayStart(scene, ray);
        int depth = 0, surfaceBounces = 0;
        bool caustic = false;  // bent before its first scattering event (PhotonSource::causticsByPhotons)
        // The events since emission while nothing scattered the photon:
        // refractions at one glass sphere (Photon::Connected after one,
        // across its surface, or two, through it), -1 once anything else
        // happened.
        int lensSphere = -1, lensRefractions = mScene.deltaLightCaustics && src.deltaLight ? 0 : -1;
        Color beta(1);  // throughput relative to the emitted power
        MediumPoint mp;
        while (true) {
            const RaySegment seg = nextRaySegment(scene, ray);
            const SurfaceHit& h = seg.surface;
            const bool hit = seg.hitSurface;
            const int light = seg.light;
            const float tEnd = seg.tEnd;

            // Delta tracking to the next real collision; the photon is stored
            // there, then scatters with probability albedo.
            bool scattered = false, ended = false;
            deltaTrack(ctx, region, ray, tEnd, rng, [&](const Vec3& x, float sigmaMaj) {
                evalMedia(ctx, region, x, mp);
                const float sa = spectral.of(mp.sigma_a), ss = spectral.of(mp.sigma_s);
                if (rng.uniform() * sigmaMaj >= sa + ss)  // null collision
                    return spectral.null(mp.sigma_t, sigmaMaj, scene.regions[size_t(region)].coefficients, beta);
                const float st = sa + ss;
                Photon ph;
                ph.position = x;
                ph.direction = encodeDirection(ray.d);
                // Phi / sigma_t: grey extinction's is the same in every
                // channel; a chromatic one's is the channels' mixture.
                ph.weight = power * beta / (spectral.channel < 0 ? st : spectral.mixed(mp.sigma_t));
                float w[2];
                mp.phase.legendreWeights(1, w);
                ph.flags = Photon::packFlags((direct ? Photon::Direct : 0u) | (caustic ? Photon::Caustic : 0u) |
                                                 (src.pointLight ? Photon::FromPointLight : 0u) |
                                                 (lensRefractions >= 1 ? Photon::Connected : 0u),
                                             w[1], region);
                out.push_back(ph);
                if (!(rng.uniform() * st < ss) || ++depth >= maxDepth) {
                    ended = true;
                    return false;
                }
                spectral.scatter(mp.sigma_s, beta);
                float pdf;
                const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                ray = Ray{x, mp.phase.sample(ray.d, u0, u1, u2, beta, pdf)};
                direct = false;
                lensRefractions = -1;
                scattered = true;
                return false;
            });
            if (ended) return;
            if (scattered) {
                if (!isFinite(beta) || !russianRoulette(beta, rng, ScatterRouletteThreshold)) return;
                continue;
            }
            if (light >= 0 || !hit) return;  // absorbed by a light, or escaped
            if (++surfaceBounces > scene.desc.render.maxSurfaceBounces) return;
            const float u[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
            const SurfaceEvent e = sampleSurfaceEvent(scene, h, ray.d, region, u, TransportMode::Importance);
            if (e.kind == SurfaceEvent::Kind::Diffuse && ++depth >= maxDepth) return;
            beta *= e.weight;
            // Index-matched glass is crossed straight, as shadow rays cross
            // it, so such photons stay direct.
            if (!e.straight) {
                // Paths find a delta light only by next-event estimation at a
                // scattering vertex, through straight shadow rays; sphere
                // lights' caustics are left to photons where the scene says.
                if (direct && src.causticsByPhotons && e.kind != SurfaceEvent::Kind::Diffuse) caustic = true;
                direct = false;
                followLensPattern(scene, e.kind == SurfaceEvent::Kind::Refract, h.surface, lensSphere, lensRefractions);
            }
            if (!russianRoulette(beta, rng, ScatterRouletteThreshold)) return;
            ray = e.ray;
            region = e.region;
        }
    }

    const Scene& mScene;
    uint64_t mSeed;
    const bool mChromatic;
};

}  // namespace

bool sceneScatters(const Scene& scene) {
    for (const auto& m : scene.media)
        if (scatters(*m)) return true;
    return false;
}

PhotonTarget photonTarget(const Scene& scene) {
    PhotonTarget t;
    BBox finite;
    for (const auto& m : scene.media) {
        if (m->isVacuum()) continue;
        BBox b = m->worldBounds();
        if (!b.isFinite()) {
            if (scatters(*m)) t.unbounded = true;
            continue;
        }
        if (scatters(*m)) t.bounds.expand(b);
        finite.expand(b);
    }
    BBox surfaces = scene.surfaceSet->bounds();
    if (!surfaces.empty()) {
        t.bounds.expand(surfaces);
        finite.expand(surfaces);
    }
    if (t.unbounded) {
        // Fog fills all space: cover what the scene has that is finite.
        for (const Light& l : scene.lights) {
            Vec3 center;
            float radius;
            if (l.emittingBall(center, radius)) finite.expand(center);
            if (const CollimatedQuad* quad = l.collimatedQuad()) finite.expand(quad->center);
        }
        finite.expand(scene.desc.camera.position);
        finite.expand(scene.desc.camera.lookAt);
        Vec3 pad = (finite.hi - finite.lo) * 0.05f + Vec3(1e-3f * std::max(1.f, scene.sceneScale));
        finite.lo -= pad;
        finite.hi += pad;
        t.bounds = finite;
    }
    return t;
}

PhotonSet tracePhotons(const Scene& scene, size_t paths, uint64_t seed) {
    auto start = std::chrono::steady_clock::now();
    PhotonSet set;
    if (paths == 0 || !sceneScatters(scene)) return set;
    // About one stored photon per path, 44 bytes each with its kd-tree share
    // (measured: docs/benchmarks/history.md, "Photon map and radiance cache
    // build").
    checkMemory(uint64_t(paths) * 44, str("photons.count = ", paths, " (about 44 bytes per stored photon)"));
    const PhotonTarget target = photonTarget(scene);
    if (target.bounds.empty()) return set;

    std::vector<PhotonSource> sources;
    for (const Light& l : scene.lights) {
        PhotonSource s{PhotonEmitter::forLight(l, target), nullptr, -1, Color(0), false, false, false, 0, 0};
        s.power = s.emitter.power();
        s.deltaLight = l.isDelta();
        s.causticsByPhotons = s.deltaLight || (l.sphere() && scene.sphereLightCausticPhotons);
        s.pointLight = l.isPointLike();
        if (maxComponent(s.power) > 0) sources.push_back(std::move(s));
    }
    if (!scene.environment.isBlack()) {
        PhotonSource s{PhotonEmitter::forEnvironment(scene.environment, target), nullptr, -1, Color(0), false, false, false, 0, 0};
        s.power = s.emitter.power();
        if (maxComponent(s.power) > 0) sources.push_back(std::move(s));
    }
    for (size_t mi = 0; mi < scene.media.size(); ++mi) {
        const Medium& m = *scene.media[mi];
        if (!m.hasEmission) continue;
        auto sampler = m.makeEmissionSampler();
        if (!sampler) continue;
        PhotonSource s{PhotonEmitter::forEnvironment(Color(0), target), nullptr, int(mi), Color(0), false, false, false, 0, 0};
        s.power = m.blackbody ? m.sigma_a * m.emissionColor * sampler->blackbodyIntegral() * (4 * Pi)
                              : m.sigma_a * m.emissionColor * (4 * Pi * sampler->integralEstimate());
        s.volume = std::move(sampler);
        if (maxComponent(s.power) > 0) sources.push_back(std::move(s));
    }
    if (sources.empty()) return set;

    // Paths per source in proportion to power (every source that can reach
    // the target gets at least one), as contiguous index ranges.
    double total = 0;
    for (const auto& s : sources) total += average(s.power);
    size_t assigned = 0;
    for (size_t i = 0; i < sources.size(); ++i) {
        double share = average(sources[i].power) / total * double(paths);
        sources[i].count = std::max<size_t>(1, size_t(std::llround(share)));
        assigned += sources[i].count;
    }
    // Fix rounding on the largest source so the total is exactly `paths`.
    size_t largest = 0;
    for (size_t i = 1; i < sources.size(); ++i)
        if (sources[i].count > sources[largest].count) largest = i;
    if (assigned > paths && sources[largest].count > assigned - paths) sources[largest].count -= assigned - paths;
    else if (assigned < paths) sources[largest].count += paths - assigned;
    size_t first = 0;
    for (auto& s : sources) {
        s.first = first;
        first += s.count;
        set.emittedPower += s.power;
    }
    set.paths = first;

    PhotonTracer tracer(scene, seed);
    const size_t chunks = (set.paths + ChunkPaths - 1) / ChunkPaths;
    std::vector<std::vector<Photon>> perChunk(chunks);
    tbb::enumerable_thread_specific<ThreadContext> contexts([&] { return ThreadContext(scene); });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1), [&](const tbb::blocked_range<size_t>& r) {
        ThreadContext& ctx = contexts.local();
        for (size_t c = r.begin(); c < r.end(); ++c) {
            size_t begin = c * ChunkPaths, end = std::min(set.paths, begin + ChunkPaths);
            auto& out = perChunk[c];
            out.reserve((end - begin) * 2);
            size_t si = 0;
            for (size_t i = begin; i < end; ++i) {
                while (i >= sources[si].first + sources[si].count) ++si;
                tracer.tracePath(ctx, sources[si], i, out);
            }
        }
    });
    size_t n = 0;
    for (const auto& v : perChunk) n += v.size();
    set.photons.reserve(n);
    for (auto& v : perChunk) {
        set.photons.insert(set.photons.end(), v.begin(), v.end());
        std::vector<Photon>().swap(v);
    }
    for (const Photon& p : set.photons) {
        set.directCount += p.isDirect();
        set.causticCount += p.isCaustic();
    }
    set.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return set;
}

}  // namespace vdbmarch
