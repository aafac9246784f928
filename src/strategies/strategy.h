// The sampling strategies a path can use besides delta tracking and f's own
// direction sampling, as four small interfaces that every path loop
// iterates (paths/path_tracer.h, the marchers' L_i samples):
//  - a DistanceStrategy draws positions along a path segment, towards
//    where light concentrates, and weighs them against the tracking
//    collisions by MIS (pbrt-v4's SampleT_maj callbacks; equiangular
//    sampling, the folds of sphere caustics);
//  - a DirectionStrategy draws a vertex's next direction from a mixture with
//    f's own sampling and tells next-event estimation its density (Mitsuba
//    3's pdf_direction; directions towards beams);
//  - a ConnectionStrategy brings light through specular surfaces that
//    shadow rays cannot follow, with the MIS weight a path that reaches the
//    light through the same surfaces gets (sphere caustics);
//  - a SurfaceStrategy decides a radiance path's event at a surface in
//    place of the material's own sampling (glass splitting).
// Each is built once per render from the scene (strategy_set.h) with its
// tables; per-segment and per-vertex state lives in the thread context's
// extension slot the set gives it.
#pragma once

#include "core/rng.h"
#include "transport/direct_light.h"
#include "transport/media_point.h"
#include "transport/roulette.h"
#include "transport/surface_event.h"
#include "transport/thread_context.h"
#include "transport/tracking.h"
#include "transport/transmittance.h"

namespace vdbmarch {

// One path segment [0, tEnd) of `ray` in `region`.
struct PathSegment {
    Ray ray;
    int region = 0;
    HeroChannel spectral;   // the path's spectral MIS state (channel < 0: grey extinction)
    float tEnd = 0;
    bool skipPointLights = false;  // photons carry point and spot lights' light (next-event estimation leaves them out)
};

// What a tracking collision leaves to next-event estimation and to the
// connections, after the distance strategies of its segment took their share.
struct CollisionWeights {
    const float* lightWeights = nullptr;  // per scene light (DirectLightOptions::lightWeights); null: all 1
    float connectionWeight = 1;           // of the point-like and parallel lights' connections
};

// Which lights a connection brings, and whether the path goes on from the
// vertex (its own light hits then weigh against the connections).
struct ConnectionRequest {
    bool areaLights = true;
    bool pointLights = true;
    bool pathFollows = true;
    bool parallelLights = true;
    float deltaWeight = 1;  // CollisionWeights::connectionWeight
};

// The specular surface events of a path since its last sampled vertex, as
// connection strategies need them to recognise their own patterns.
struct SpecularChain {
    static constexpr int MaxEvents = 2;
    int surface[MaxEvents] = {-1, -1};
    bool refracted[MaxEvents] = {false, false};
    int length = 0;  // events (those past MaxEvents are counted, not kept)
    void clear() { length = 0; }
    void add(int s, bool refraction) {
        if (length < MaxEvents) surface[length] = s, refracted[length] = refraction;
        ++length;
    }
};

class DistanceStrategy {
public:
    virtual ~DistanceStrategy() = default;
    // True when segments in `region` must run to their true end (no probe
    // cut, paths/path_tracer.cpp) for this strategy's densities.
    virtual bool needsSegmentEnd(int region, bool skipPointLights) const { return false; }
    // Sets up the segment's samplers in this thread's scratch; false: none.
    virtual bool prepare(ThreadContext& ctx, const PathSegment& seg) const = 0;
    // One position on the prepared segment: its MIS-weighted estimate of the
    // light scattered there towards the segment's origin (times the path's
    // throughput by the caller).
    virtual Color sample(ThreadContext& ctx, const PathSegment& seg, Rng& rng) const = 0;
    // Where a tracking collision at t is taken instead (off singular points).
    virtual float collisionAt(ThreadContext& ctx, float t) const { return t; }
    // The collision's share of what this strategy samples, into `w`.
    virtual void weighCollision(ThreadContext& ctx, const PathSegment& seg, float t, const MediumPoint& mp,
                                CollisionWeights& w) const = 0;
};

class DirectionStrategy {
public:
    virtual ~DirectionStrategy() = default;
    // Takes vertex `v` in `region` when it draws directions there: points
    // v's pathPdf at its mixture, so next-event estimation meets it by MIS.
    virtual bool attach(ThreadContext& ctx, int region, ScatterVertex& v, bool skipPointLights) const = 0;
    // Draws from the attached vertex's mixture: wi, weight *= f / pdf, pdf.
    // pdf 0 (weight 0): no direction.
    virtual Vec3 sample(ThreadContext& ctx, Rng& rng, Color& weight, float& pdf) const = 0;
};

class ConnectionStrategy {
public:
    virtual ~ConnectionStrategy() = default;
    // True when the scene has connections for this strategy: every vertex
    // then makes them, so a path's light hits know what its last vertex did.
    virtual bool active() const = 0;
    // The light vertex v (in `region`) receives through the connections.
    virtual Color connect(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng,
                          const ConnectionRequest& request) const = 0;
    // The MIS weight of a path that left x along w (density pathPdf), went
    // through `chain` and hit light `light` at y; 1 where this strategy
    // makes no connection of that pattern.
    virtual float pathHitWeight(const SpecularChain& chain, int light, const Vec3& x, const Vec3& w, float pathPdf,
                                const Vec3& y) const = 0;
};

// A radiance path's event at a surface, as the path loops take it.
struct PathSurfaceEvent {
    SurfaceEvent event;  // the outcome the path goes on with
    Color weight;        // its weight
    // The reflection to trace beside it, weighted mirrorWeight (split).
    bool split = false;
    SurfaceEvent mirror;
    Color mirrorWeight;
    // Light counted at the event, to be multiplied by the path's throughput:
    // what the reflection sees, with MIS weight 1 (a light hit after a
    // reflection breaks every sphere caustic pattern).
    Color light;
    // The part of `light`'s weight that is the background seen through
    // (alpha: a camera path that sees the background in glass).
    float backgroundSeen = 0;
    // The path took a reflection whose light was counted: it must not count
    // the light or background its next segment ends on.
    bool mirrorCounted = false;
};

// What the path loop tells a surface strategy about the path.
struct SurfaceRequest {
    bool split = false;           // the path may follow both outcomes here (a camera path's first glass events)
    bool seenFromCamera = false;  // the path has not scattered yet (it sees the environment map as a backdrop)
    bool sphereLightsByPhotons = false;  // caustic photons gave the sphere lights glass shows this path
};

class SurfaceStrategy {
public:
    virtual ~SurfaceStrategy() = default;
    // True when this strategy decides the event at `hit` for a path
    // travelling along d in `region` (and fills `out`); u: three uniforms
    // (the Fresnel choice, then the diffuse direction).
    virtual bool sample(ThreadContext& ctx, const SurfaceHit& hit, const Vec3& d, int region, const float u[3],
                        const SurfaceRequest& request, Rng& rng, PathSurfaceEvent& out) const = 0;
};

// The density with which delta tracking makes a scattering collision at t,
// for MIS weights only: sigma_s times the transmittance of the region's
// constant media, mixed over the channels as spectral MIS mixes the
// path's densities (HeroChannel) (gridded media count as
// clear: an estimate of T is random, and a weight must be a function of t).
float trackingDensity(ThreadContext& ctx, const PathSegment& seg, float t, const MediumPoint& mp);

// The power heuristic between a distance sampler's density and tracking's.
float distanceWeight(float pdfDistance, float pdfTracking);

// A distance sample at t drawn with density `pdf` on segment `seg`, weighed
// against the tracking collisions by the power heuristic (all of it when
// `onlyDistance`): T(t) sigma_s(t) L w / pdf, L = estimate(vertex at t).
template <typename Estimate>
Color scatteredAt(ThreadContext& ctx, const PathSegment& seg, float t, float pdf, bool onlyDistance, Rng& rng,
                  Estimate&& estimate) {
    if (!(pdf > 0)) return Color(0);
    const Vec3 x = seg.ray.at(t);
    MediumPoint mp;
    evalMedia(ctx, seg.region, x, mp);
    if (!mp.scatters()) return Color(0);
    const float pTrack = trackingDensity(ctx, seg, t, mp);
    float w = onlyDistance ? 1.f : distanceWeight(pdf, pTrack);
    if (!(w > 0) || !russianRoulette(w, rng, MisWeightRouletteThreshold)) return Color(0);
    // Light that ends here: the quiet unbiased estimator (transmittance.h).
    const Color T = regionTransmittance(ctx, seg.region, seg.ray, t, rng, TransmittanceEstimator::UnbiasedMarching);
    if (isBlack(T)) return Color(0);
    const Color L = estimate(ScatterVertex::inMedium(x, seg.ray.d, mp.phase));
    return T * mp.sigma_s * L * (w / pdf);
}

// The hull of the bounds of each region's scattering media.
std::vector<BBox> scatterBoundsOf(const Scene& scene);

// Whether a light at `position` sees `region` with no surface that blocks
// shadow rays between: in a scene with such surfaces, the light must lie in
// the region (a conservative test; one without them sees every region).
bool openToRegion(const Scene& scene, const Vec3& position, int region);

}  // namespace vdbmarch

