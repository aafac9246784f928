#include "estimators/segment_marcher.h"

#include <cmath>

#include "core/error.h"
#include "transport/direct_light.h"
#include "paths/path_tracer.h"
#include "transport/roulette.h"
#include "transport/surface_event.h"
#include "transport/tracking.h"
#include "transport/transmittance.h"

namespace vdbmarch {

SegmentMarcher::SegmentMarcher(const EstimatorInputs& in)
    : mScene(in.scene), mIllumination(in.illumination), mChromatic(hasChromaticExtinction(in.scene)),
      mTallyDirect(in.scene.desc.render.aovs.splitDirect()),
      mPaths(in.scene, in.strategies, PathOptions{mIllumination && mIllumination->pointLightsByPhotons, nullptr}),
      // The camera path's vertices are on surfaces, where no photons are
      // gathered: next-event estimation there takes every light. Roulette
      // only ends paths of negligible throughput (they march every segment).
      mCameraPaths(in.scene, in.strategies, PathOptions{false, nullptr, this, 0, RouletteThreshold}) {
    const Scene& scene = in.scene;
    // Without emissive media or refracting glass, the light arriving at a
    // sample straight from its first direction is what next-event estimation
    // samples (lights and the background).
    mLastEventByNextEvent = !hasBendingGlass(scene);
    for (const auto& m : scene.media) mLastEventByNextEvent = mLastEventByNextEvent && !m->hasEmission;
    if (!mIllumination) throw std::logic_error("SegmentMarcher needs an Illumination");
}

// The marchers' tallies of the direct and emitted parts (tallyEmission,
// tallyInScattered) join what the loop counts at surfaces and lights.
PathRadiance SegmentMarcher::radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const {
    ++ctx.counters.cameraRays;
    MarcherScratch& m = scratch(ctx);
    m.direct = Color(0);
    m.emitted = Color(0);
    PathRadiance r = mCameraPaths.trace(ctx, cameraRay, regionAtRayStart(mScene, cameraRay), rng, PathState{});
    r.direct = mTallyDirect ? r.direct + m.direct : Color(0);
    r.emitted += m.emitted;
    return r;
}

bool SegmentMarcher::march(ThreadContext& ctx, int region, const Ray& ray, float tEnd, int depth, Rng& rng, Color& L,
                           Color& beta) const {
    scratch(ctx).pathDepth = depth;
    // Past max_depth a march adds emission only: where the region emits
    // none, the path needs just the segment's transmittance.
    if (!scatters(ctx) && !mScene.regions[size_t(region)].emits) {
        beta *= regionTransmittance(ctx, region, ray, tEnd, rng);
        return true;
    }
    return marchSegment(ctx, region, ray, tEnd, rng, L, beta);
}

CacheLookup& MarcherScratch::lookup(const RadianceCache& cache) {
    if (!cacheLookup) cacheLookup = std::make_unique<CacheLookup>(cache);
    return *cacheLookup;
}

Color SegmentMarcher::inScattered(ThreadContext& ctx, int region, const Vec3& x, const Vec3& rayDir,
                                  const MediumPoint& mp, Rng& rng, float pathProbability, float photonWeight) const {
    // The direct AOV: light scattered here once, when this is the camera
    // path's first event; photons and the cache count as indirect.
    MarcherScratch& m = scratch(ctx);
    if (mTallyDirect) m.liDirect = Color(0);
    const bool tallyHere = mTallyDirect && m.pathDepth == 0;
    if (!mp.scatters() || !scatters(ctx)) return Color(0);
    ++ctx.counters.liSamples;
    const Illumination& il = *mIllumination;
    if (il.li == LiSource::Cache) {
        if (!il.cache) return Color(0);  // nothing scatters anywhere
        CacheLookup& c = cacheLookup(ctx);
        c.setDirection(-rayDir);
        return Color(c.at(x));
    }
    const ScatterVertex vertex = ScatterVertex::inMedium(x, rayDir, mp.phase);
    // Eq. 4 over the photons the L_i source keeps (none: no photon map),
    // gathered within this photon pass's radius.
    auto photons = [&] { return photonWeight > 0 ? photonWeight * il.photonLi(mScene, x, region, -rayDir, mp.phase) : Color(0); };
    auto direct = [&](const Color& Ld) {
        if (tallyHere) m.liDirect = Ld;
        return Ld;
    };
    if (il.li == LiSource::Photons) return direct(directLight(ctx, region, vertex, rng, {})) + photons();
    // A continuation path: next-event estimation here (weighed by MIS
    // against the path's own sphere-light hits), then a phase-sampled
    // direction followed by the path tracer from this vertex. Unbiased for
    // all the light a path can reach; the caustic photons add the rest.
    const int depth = m.pathDepth + 1;  // this sample's scattering event
    if (depth >= mScene.desc.render.maxDepth && mLastEventByNextEvent) {
        // The last event max_depth allows: a path from here could only find
        // lights and the background straight along its first direction,
        // which next-event estimation samples directly (no path needed).
        static constexpr DirectLightOptions kLastEvent{TransmittanceEstimator::UnbiasedMarching, false, true};
        return direct(directLight(ctx, region, vertex, rng, kLastEvent)) + photons();
    }
    static constexpr DirectLightOptions kNextEvent{TransmittanceEstimator::UnbiasedMarching, true, false};
    // The continuation's direction: as at the path tracer's vertices, a
    // share of the directions towards spot and collimated beams
    // (strategies/beam_directions.h), else the phase. Next-event estimation
    // weighs its sphere-light samples against that same density (MIS).
    ScatterVertex nextEventVertex = vertex;
    const DirectionStrategy* directions = mPaths.attachDirections(ctx, region, nextEventVertex);
    Color Li = direct(directLight(ctx, region, nextEventVertex, rng, kNextEvent));
    // Light through specular surfaces too (the connection strategies),
    // weighed against the continuation's own hits: sphere lights, and point
    // and spot lights, whose photons then leave these caustics out
    // (strategies/sphere_caustics.h, Photon::Connected).
    bool connected;
    const Color Lc = mPaths.strategies().connect(ctx, region, nextEventVertex, rng, {}, connected);
    if (connected) {
        Li += Lc;
        if (tallyHere) m.liDirect += Lc;
    }
    const bool tracePathHere = pathProbability >= 1 || rng.uniform() < pathProbability;
    const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    if (tracePathHere) {
        Color weight(1 / std::min(1.f, pathProbability));
        float pdf = 0;
        Vec3 wi;
        if (directions) {
            wi = directions->sample(ctx, rng, weight, pdf);
        } else {
            wi = mp.phase.sample(rayDir, u0, u1, u2, weight, pdf);
        }
        PathState state;
        if (directions) scaleRoulette(state, nextEventVertex, wi, pdf);
        state.depth = depth;
        state.specular = false;
        state.lastPdf = pdf;
        state.lastPoint = x;
        state.connectedAtLast = connected;
        state.lastDir = wi;
        state.causticPhotonsGathered = il.causticsOnly;  // photons() below
        if (pdf > 0) {
            state.spectral = startingHero(mChromatic, rng);
            const PathRadiance p = mPaths.trace(ctx, Ray{x, wi}, region, rng, state);
            Li += weight * p.L;
            if (tallyHere) m.liDirect += weight * p.direct;
        }
    }
    return Li + photons();
}

namespace {

// Skipped = the part of [0, end) outside active intervals, where `end` is the
// segment end or, for rays to infinity, the end of the last interval.
void addLengths(ThreadContext& ctx, float tEnd, const std::vector<Interval>& intervals) {
    double active = 0;
    for (const Interval& iv : intervals) active += double(std::min(iv.t1, 1e30f) - iv.t0);
    ctx.counters.marchedLength += active;
    double end = std::isfinite(tEnd) ? double(tEnd)
                                     : (intervals.empty() ? 0.0 : double(std::min(intervals.back().t1, 1e30f)));
    ctx.counters.skippedLength += std::max(0.0, end - active);
}

}  // namespace

bool SegmentMarcher::activeIntervals(ThreadContext& ctx, int region, const Ray& ray, float tEnd,
                                     bool& infiniteTail) const {
    infiniteTail = false;
    if (mScene.regions[size_t(region)].media.empty()) return false;
    // Past the scene's finite content unbounded fog is homogeneous: march
    // until its transmittance is below e^-20 (at most 1e5 steps).
    const Color& K = mScene.regions[size_t(region)].unboundedSigmaT;
    infiniteTail = !std::isfinite(tEnd) && !isBlack(K);
    float tLimit = tEnd;
    if (infiniteTail) {
        float kMin = Infinity;
        for (int c = 0; c < 3; ++c)
            if (K[c] > 0) kMin = std::min(kMin, K[c]);
        tLimit = length(ray.o) + 2 * mScene.sceneScale + std::min(20.f / kMin, 1e5f * mScene.step);
    }
    regionIntervals(ctx, region, ray, 0.f, tLimit, ctx.intervals);
    addLengths(ctx, tEnd, ctx.intervals);
    return true;
}

void SegmentMarcher::applyInfiniteTail(int region, Color& beta) const {
    const Color& K = mScene.regions[size_t(region)].unboundedSigmaT;
    for (int c = 0; c < 3; ++c)
        if (K[c] > 0) beta[c] = 0;
}

namespace {

// e^{-tau} and 1 - e^{-tau} from one exp: above tau = 1e-2, 1 - T loses at
// most 6e-6 of its value to rounding; below, the series keeps it exact to
// tau^3 / 24 < 5e-8 relative (no expm1: the walk's hottest line).
inline void extinction(float tau, float& T, float& oneMinusT) {
    T = std::exp(-tau);
    oneMinusT = tau > 1e-2f ? 1 - T : tau * (1 - tau * (0.5f - tau * (1.f / 6)));
}

}  // namespace

StepTerms stepTerms(const MediumPoint& mp, float dx) {
    StepTerms s;
    // Grey extinction (the common case): one exp and one reciprocal.
    if (mp.sigma_t[0] == mp.sigma_t[1] && mp.sigma_t[1] == mp.sigma_t[2]) {
        const float kappa = mp.sigma_t[0];
        float T, oneMinusT;
        extinction(kappa * dx, T, oneMinusT);
        const float f = kappa > 0 ? oneMinusT / kappa : 0.f;
        s.T = Color(T);
        s.absorbedA = mp.sigma_a * f;
        s.absorbedS = mp.sigma_s * f;
        return s;
    }
    for (int c = 0; c < 3; ++c) {
        const float kappa = mp.sigma_t[c];
        float oneMinusT;
        extinction(kappa * dx, s.T[c], oneMinusT);
        const float f = kappa > 0 ? oneMinusT / kappa : 0.f;
        s.absorbedA[c] = mp.sigma_a[c] * f;
        s.absorbedS[c] = mp.sigma_s[c] * f;
    }
    return s;
}

}  // namespace vdbmarch
