#include "paths/path_tracer.h"

#include <algorithm>

#include "transport/media_point.h"
#include "transport/roulette.h"
#include "transport/surface_event.h"
#include "transport/tracking.h"

namespace vdbmarch {

namespace {

// A free flight in a region of constant media seldom goes far where they
// are dense (milk sealed in glass: mean free paths far shorter than the
// glass): the surface is looked for only within ProbeFreePaths mean free
// paths, where Embree prunes most of its tree, and a path that passes them
// without a collision goes on from there. Delta tracking is memoryless, so
// the cut changes no distribution; it is made only where no distance
// strategy reads the segment's end.
constexpr float ProbeFreePaths = 3;

// A new vertex at x from which the path samples its next direction: its
// connections (made there when `connected`) start a new specular chain.
void startVertex(PathState& st, const Vec3& x, const Vec3& wi, float pdf, bool connected) {
    st.lastPdf = pdf;
    st.lastDir = wi;
    st.specular = false;
    st.lastPoint = x;
    st.connectedAtLast = connected;
    st.chain.clear();
    st.mirrorCounted = false;
}


// sigma_s / sigma_t per channel (0 where sigma_t is).
Color singleScatteringAlbedo(const MediumPoint& mp) {
    Color a(0);
    for (int c = 0; c < 3; ++c) a[c] = mp.sigma_t[c] > 0 ? mp.sigma_s[c] / mp.sigma_t[c] : 0.f;
    return a;
}

// The state after a reflection or refraction at surface `surface`.
void followSurfaceEvent(const SurfaceEvent& e, int surface, PathState& st) {
    if (e.straight) return;
    st.specular = true;  // next-event estimation cannot see through this
    st.chain.add(surface, e.kind == SurfaceEvent::Kind::Refract);
}

}  // namespace

// One path through the loop: its state, throughput and sums, and the
// events of PathTracer::trace.
class PathWalk {
public:
    PathWalk(const PathTracer& t, ThreadContext& c, Ray r, int reg, Rng& g, PathState s, const Color& b)
        : tracer(t), scene(t.mScene), strategies(*t.mStrategies), ctx(c), rng(g), ray(r), region(reg), st(s), startDepth(s.depth),
          maxDepth(t.mOptions.maxDepth >= 0 ? t.mOptions.maxDepth : t.mScene.desc.render.maxDepth), beta(b) {}

    // Adds c, after `events` scattering events, to L (and to the direct part).
    void add(const Color& c, int events) {
        L += c;
        if (events <= 1) direct += c;
    }
    // Emission and lights seen before any scattering event, too.
    void addEmitted(const Color& c, int events) {
        add(c, events);
        if (events == 0) emitted += c;
    }
    // transmittance: of the background the path ends on.
    PathRadiance result(float transmittance) const {
        return PathRadiance{L, transmittance + through, direct, emitted, first};
    }

    // The first event (FirstEvent): a point met, and where the first
    // non-specular event gives albedo and normal.
    void meet(const Vec3& p) {
        if (!first.hasDepth) first.depthPoint = p;
        first.hasDepth = true;
    }
    void firstEventAt(const Vec3& p, const Color& albedo, const Vec3& normal) {
        meet(p);
        if (first.done) return;
        first.albedo = beta * albedo;
        first.normal = normal;
        first.done = true;
    }

    // How the path crossed a segment's media.
    enum class Crossing { Reached, Scattered, Ended };
    float probeLength() const;
    Crossing cross(const RaySegment& seg);
    void hitLight(int light, float tEnd);
    float hitBackground();
    bool surfaceEvent(const SurfaceHit& h);
    // The caustic photons gave the sphere lights this path meets through
    // bending glass (PathState::causticPhotonsGathered).
    bool leavesSphereLightsToPhotons() const { return st.causticPhotonsGathered && scene.sphereLightCausticPhotons; }
    // Russian roulette on the throughput after PathOptions::rouletteMinDepth events.
    bool roulette() {
        const PathOptions& o = tracer.mOptions;
        return st.depth < o.rouletteMinDepth || russianRoulette(beta, rng, o.rouletteThreshold, st.rouletteScale);
    }

    const PathTracer& tracer;
    const Scene& scene;
    const StrategySet& strategies;
    ThreadContext& ctx;
    Rng& rng;
    Ray ray;
    int region;
    PathState st;
    const int startDepth, maxDepth;
    Color beta;
    Color L{0}, direct{0}, emitted{0};
    // The background seen through glass reflections counted whole
    // (PathSurfaceEvent::backgroundSeen) and through split glass events.
    float through = 0;
    FirstEvent first;
    unsigned prepared = 0;  // bit i: distance strategy i prepared the current segment

private:
    void sampleDistances(const PathSegment& seg);
    Crossing track(const RaySegment& seg);
    bool scatterAt(Vec3 x, float t, const MediumPoint& mp, const PathSegment& seg);
    bool nextEvent(const ScatterVertex& vertex, const CollisionWeights& w);
    void split(const PathSurfaceEvent& pe, int surface);
};

float PathWalk::probeLength() const {
    if (tracer.mOptions.march) return Infinity;  // a march reads the whole segment
    const Region& r = scene.regions[size_t(region)];
    if (!r.constant) return Infinity;
    const float sigmaT = majorantSigmaT(r.unboundedSigmaT);
    if (!(sigmaT > 0) || strategies.needsSegmentEnd(region, tracer.mOptions.pointLightsByPhotons)) return Infinity;
    return ProbeFreePaths / sigmaT;
}

// The distance strategies' samples along the segment, each weighed against
// the tracking collisions by MIS.
void PathWalk::sampleDistances(const PathSegment& seg) {
    prepared = 0;
    if (st.depth >= maxDepth) return;
    const auto& distances = strategies.distances();
    for (size_t i = 0; i < distances.size(); ++i) {
        if (!distances[i]->prepare(ctx, seg)) continue;
        prepared |= 1u << i;
        add(beta * distances[i]->sample(ctx, seg, rng), st.depth + 1);
    }
}

// Next-event estimation at a vertex of the path, then the connections
// through specular surfaces; true when some connection was made (the
// path's own light hits through such surfaces weigh against it).
bool PathWalk::nextEvent(const ScatterVertex& vertex, const CollisionWeights& w) {
    const bool byPhotons = tracer.mOptions.pointLightsByPhotons;
    DirectLightOptions o{TransmittanceEstimator::UnbiasedMarching, true, false, byPhotons, w.lightWeights};
    o.phaseRoulette = true;
    add(beta * directLight(ctx, region, vertex, rng, o), st.depth);
    bool connected;
    const Color Lc = strategies.connect(ctx, region, vertex, rng, {true, !byPhotons, true, true, w.connectionWeight},
                                        connected);
    if (connected) add(beta * Lc, st.depth);
    return connected;
}

// A real scattering event at x (media mp there): next-event estimation,
// then the next direction. False when max_depth ends the path.
bool PathWalk::scatterAt(Vec3 x, float t, const MediumPoint& mp, const PathSegment& seg) {
    if (++st.depth > maxDepth) {
        beta = Color(0);
        return false;
    }
    const auto& distances = strategies.distances();
    CollisionWeights weights;
    for (size_t i = 0; i < distances.size(); ++i) {
        if (!(prepared >> i & 1u)) continue;
        const float moved = distances[i]->collisionAt(ctx, t);  // off a singular point
        if (moved != t) t = moved, x = ray.at(t);
    }
    ScatterVertex vertex = ScatterVertex::inMedium(x, ray.d, mp.phase);
    const DirectionStrategy* directions = tracer.attachDirections(ctx, region, vertex);
    for (size_t i = 0; i < distances.size(); ++i)
        if (prepared >> i & 1u) distances[i]->weighCollision(ctx, seg, t, mp, weights);
    const bool connected = nextEvent(vertex, weights);
    if (tracer.mOptions.firstVertexLight && st.firstVertexPending) {
        add(beta * tracer.mOptions.firstVertexLight->at(x, region, -ray.d, mp.phase), st.depth);
        st.firstVertexPending = false;
        st.causticPhotonsGathered = true;
    }
    float pdf = 0;
    Vec3 wi;
    if (directions) {
        wi = directions->sample(ctx, rng, beta, pdf);
        scaleRoulette(st, vertex, wi, pdf);
    } else {
        const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        wi = mp.phase.sample(ray.d, u0, u1, u2, beta, pdf);
    }
    startVertex(st, x, wi, pdf, connected);
    ray = Ray{x, wi};
    return true;
}

// The path hit sphere light `light` at tEnd: its emission, weighed against
// the next-event estimate at the last vertex (a sampled direction) or
// against the connections through the specular chain since (power heuristic).
void PathWalk::hitLight(int light, float tEnd) {
    meet(ray.at(tEnd));
    if (st.specular && leavesSphereLightsToPhotons()) return;  // a caustic the photons gave
    const Light& l = scene.lights[size_t(light)];
    float w = 1;
    if (!st.specular) {
        w = powerHeuristic(st.lastPdf, l.directionPdf(st.lastPoint));
    } else if (st.connectedAtLast) {
        w = strategies.pathHitWeight(st.chain, light, st.lastPoint, st.lastDir, st.lastPdf, ray.at(tEnd));
    }
    if (!st.mirrorCounted) addEmitted(beta * l.emittedRadiance() * w, st.depth);
}

// Both outcomes of a split glass event, each followed by a path of its
// own: the reflection, then the refraction.
void PathWalk::split(const PathSurfaceEvent& pe, int surface) {
    ++st.glassSplits;
    PathState sr = st, sT = st;
    followSurfaceEvent(pe.mirror, surface, sr);
    followSurfaceEvent(pe.event, surface, sT);
    const PathRadiance r = tracer.walk(ctx, pe.mirror.ray, pe.mirror.region, rng, sr, beta * pe.mirrorWeight);
    const PathRadiance t = tracer.walk(ctx, pe.event.ray, pe.event.region, rng, sT, beta * pe.weight);
    L = L + r.L + t.L;
    direct = direct + r.direct + t.direct;
    emitted = emitted + r.emitted + t.emitted;
    through = through + r.transmittance + t.transmittance;
}

// The shared surface event at h; false when the path ends there.
bool PathWalk::surfaceEvent(const SurfaceHit& h) {
    ++ctx.counters.surfaceHits;
    if (++st.surfaceBounces > scene.desc.render.maxSurfaceBounces) return false;
    const float u[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
    // A surface strategy may split a camera path at glass, or count the
    // light its reflection sees (strategies/glass_splitting.h).
    const SurfaceRequest request{st.depth == 0 && st.glassSplits < SplitDielectricEvents, st.depth == 0,
                                 leavesSphereLightsToPhotons()};
    const PathSurfaceEvent pe = strategies.surfaceEvent(ctx, h, ray.d, region, u, request, rng);
    add(beta * pe.light, st.depth);
    if (st.depth == startDepth) through += average(beta) * pe.backgroundSeen;
    st.mirrorCounted = pe.mirrorCounted;
    if (pe.split) {
        split(pe, h.surface);
        return false;
    }
    const SurfaceEvent& e = pe.event;
    Color weight = pe.weight;
    Ray next = e.ray;
    const bool diffuse = e.kind == SurfaceEvent::Kind::Diffuse;
    if (!e.straight) meet(h.p);  // interfaces and index-matched glass are invisible
    if (diffuse) {
        const Color& albedo = scene.surfaces[size_t(h.surface)].material.albedo;
        firstEventAt(h.p, albedo, dot(h.ns, ray.d) > 0 ? -h.ns : h.ns);
        if (++st.depth > maxDepth) return false;
        ScatterVertex vertex = ScatterVertex::onSurface(h.p, ray.d, h.n, albedo);
        const DirectionStrategy* directions = tracer.attachDirections(ctx, region, vertex);
        const bool connected = nextEvent(vertex, CollisionWeights{});
        float pdf = e.pdf;
        if (directions) {
            weight = Color(1);
            next.d = directions->sample(ctx, rng, weight, pdf);
            if (isBlack(weight)) return false;  // a direction below the surface
            next.o = offsetRayOrigin(scene, h.p, vertex.arrivalNormal(), next.d);
            scaleRoulette(st, vertex, next.d, pdf);
        }
        startVertex(st, h.p, next.d, pdf, connected);
    } else {
        followSurfaceEvent(e, h.surface, st);
    }
    beta *= weight;
    ray = next;
    region = e.region;
    return !diffuse || roulette();
}

// The path left the scene: the background, weighed against next-event
// estimation's samples of an environment map at the last vertex (MIS).
// Returns the transmittance to it (camera paths that never scattered).
float PathWalk::hitBackground() {
    const Environment& env = scene.environment;
    const float mis = !st.specular && env.hasMap() ? powerHeuristic(st.lastPdf, env.pdf(ray.d)) : 1.f;
    // A camera path that never scattered sees the map as a backdrop.
    if (!st.mirrorCounted) add(beta * (st.depth == 0 ? env.radianceSeen(ray.d) : env.radiance(ray.d)) * mis, st.depth);
    return st.depth == startDepth ? average(beta) : 0.f;
}

// Delta tracking to the next real collision, or to the segment's end.
PathWalk::Crossing PathWalk::track(const RaySegment& seg) {
    const PathSegment path{ray, region, st.spectral, seg.tEnd, tracer.mOptions.pointLightsByPhotons};
    sampleDistances(path);
    // The collision callback returns false once the path scattered or was
    // absorbed.
    bool scattered = false;
    MediumPoint mp;
    HeroChannel& spectral = st.spectral;
    deltaTrack(ctx, region, ray, seg.tEnd, rng, [&](const Vec3& x, float sigmaMaj) {
        evalMedia(ctx, region, x, mp);
        ++ctx.counters.marchSamples;
        // Emission: sigma_a L_e / sigma_maj at every tentative collision.
        if (!isBlack(mp.emission)) addEmitted(beta * mp.sigma_a * mp.emission / sigmaMaj, st.depth);
        const float sa = spectral.of(mp.sigma_a), ss = spectral.of(mp.sigma_s);
        const float u = rng.uniform() * sigmaMaj;
        if (u < sa + ss && !first.done) firstEventAt(x, singleScatteringAlbedo(mp), -ray.d);  // a real collision
        if (u < sa) {
            beta = Color(0);  // absorbed
            return false;
        }
        if (u >= sa + ss) return spectral.null(mp.sigma_t, sigmaMaj, scene.regions[size_t(region)].coefficients, beta);
        spectral.scatter(mp.sigma_s, beta);  // real scattering
        scattered = scatterAt(x, dot(x - ray.o, ray.d), mp, path);
        return false;
    });
    if (isBlack(beta)) return Crossing::Ended;
    if (scattered) return roulette() ? Crossing::Scattered : Crossing::Ended;
    return Crossing::Reached;
}

PathWalk::Crossing PathWalk::cross(const RaySegment& seg) {
    if (const SegmentMarch* m = tracer.mOptions.march)
        return m->march(ctx, region, ray, seg.tEnd, st.depth, rng, L, beta) ? Crossing::Reached : Crossing::Ended;
    return track(seg);
}

PathTracer::PathTracer(const Scene& scene, std::shared_ptr<const StrategySet> strategies, PathOptions options)
    : mScene(scene), mStrategies(std::move(strategies)), mOptions(options) {}

const DirectionStrategy* PathTracer::attachDirections(ThreadContext& ctx, int region, ScatterVertex& v) const {
    for (const DirectionStrategy* d : mStrategies->directions())
        if (d->attach(ctx, region, v, mOptions.pointLightsByPhotons)) return d;
    return nullptr;
}

void scaleRoulette(PathState& st, const ScatterVertex& v, const Vec3& wi, float pdf) {
    const float pf = v.fPdf(wi);
    if (pf > 0 && pdf > 0) st.rouletteScale = std::min(st.rouletteScale * (pdf / pf), 1e20f);
}

PathRadiance PathTracer::trace(ThreadContext& ctx, Ray ray, int region, Rng& rng, PathState state) const {
    return walk(ctx, ray, region, rng, state, Color(1));
}

PathRadiance PathTracer::walk(ThreadContext& ctx, Ray ray, int region, Rng& rng, PathState state,
                              const Color& beta) const {
    PathWalk w(*this, ctx, ray, region, rng, state, beta);
    while (true) {
        const RaySegment seg = nextRaySegment(mScene, w.ray, w.probeLength());
        const PathWalk::Crossing c = w.cross(seg);
        if (c == PathWalk::Crossing::Ended) return w.result(0.f);
        if (c == PathWalk::Crossing::Scattered) continue;
        // Reached tEnd without a real collision.
        if (seg.cut) {  // the end of the probed length: the same free flight goes on
            w.ray.o = w.ray.at(seg.tEnd);
            continue;
        }
        if (seg.light >= 0) {
            w.hitLight(seg.light, seg.tEnd);
            return w.result(0.f);
        }
        if (!seg.hitSurface) return w.result(w.hitBackground());
        if (!w.surfaceEvent(seg.surface)) return w.result(0.f);
    }
}

}  // namespace vdbmarch
