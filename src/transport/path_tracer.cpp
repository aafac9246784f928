#include "transport/path_tracer.h"

#include <algorithm>
#include <array>

#include "core/sampling.h"
#include "transport/beam_directions.h"
#include "transport/direct_light.h"
#include "transport/glass_splitting.h"
#include "transport/light_distance.h"
#include "transport/media_point.h"
#include "transport/roulette.h"
#include "transport/sphere_caustics.h"
#include "transport/surface_event.h"
#include "transport/tracking.h"

namespace vdbmarch {

namespace {

// Next-event estimation of the path: unbiased ray marching (transmittance.h);
// sphere lights are also hit by the path, a constant background only by the
// path, an environment map by both.
DirectLightOptions nextEventOptions(const PathState& st, const float* lightWeights = nullptr) {
    DirectLightOptions o{TransmittanceEstimator::UnbiasedMarching, true, false, st.pointLightsByPhotons, lightWeights};
    o.phaseRoulette = true;
    return o;
}

// A free flight in a region of constant media seldom goes far where they
// are dense (exp1_sphere's milk: a mean free path of 0.02 in a knot of size
// 1): the surface is looked for only within ProbeFreePaths mean free paths,
// where Embree prunes most of its tree, and a path that passes them without
// a collision goes on from there. Delta tracking is memoryless, so the cut
// changes no distribution; it is made only where nothing else reads the
// segment's end (no distance sampling towards lights).
constexpr float ProbeFreePaths = 3;
float probeLength(ThreadContext& ctx, int region, int channel, const PathState& st) {
    const Region& r = ctx.scene.regions[size_t(region)];
    if (!r.constant) return Infinity;
    const float sigmaT = trackedSigmaT(r.unboundedSigmaT, channel);
    if (!(sigmaT > 0) || regionHasLightDistances(ctx, region, st.pointLightsByPhotons)) return Infinity;
    return ProbeFreePaths / sigmaT;
}

// A new vertex at x from which the path samples its next direction: sphere
// caustic connections (made there when `caustics`) start a new pattern.
void startVertex(PathState& st, const Vec3& x, const Vec3& wi, float pdf, bool caustics) {
    st.lastPdf = pdf;
    st.lastDir = wi;
    st.specular = false;
    st.lastPoint = x;
    st.causticsAtLast = caustics;
    st.lensSphere = -1;
    st.lensRefractions = 0;
    st.mirrorCounted = false;
}

// Russian roulette on the throughput after RouletteMinDepth events.
bool roulette(Color& beta, const PathState& st, Rng& rng) {
    return st.depth < RouletteMinDepth || russianRoulette(beta, rng, ScatterRouletteThreshold, st.rouletteScale);
}

// The state after a reflection or refraction at surface `surface`.
void followSurfaceEvent(const Scene& scene, const SurfaceEvent& e, int surface, PathState& st) {
    if (e.straight) return;
    st.specular = true;  // next-event estimation cannot see through this
    // Refractions at one glass sphere keep the pattern of a sphere caustic
    // connection; anything else breaks it.
    followLensPattern(scene, e.kind == SurfaceEvent::Kind::Refract, surface, st.lensSphere, st.lensRefractions);
}

}  // namespace

bool hasChromaticExtinction(const Scene& scene) {
    for (const auto& m : scene.media) {
        const Color k = m->sigma_a + m->sigma_s;
        if (k.x != k.y || k.y != k.z) return true;
    }
    return false;
}

void scaleRoulette(PathState& st, const ScatterVertex& v, const Vec3& wi, float pdf) {
    const float pf = v.fPdf(wi);
    if (pf > 0 && pdf > 0) st.rouletteScale = std::min(st.rouletteScale * (pdf / pf), 1e20f);
}

PathRadiance tracePath(ThreadContext& ctx, Ray ray, int region, int channel, Rng& rng, PathState st) {
    const Scene& scene = ctx.scene;
    const int maxDepth = scene.desc.render.maxDepth;
    const int startDepth = st.depth;
    Color L(0), beta(1);
    // The "direct" part: what arrives after at most one scattering event in
    // all. `events` is the number of events the contribution has been
    // through (a next-event estimate at a vertex counts that vertex).
    Color direct(0);
    auto add = [&](const Color& c, int events) {
        L += c;
        if (events <= 1) direct += c;
    };
    // Emission and lights seen before any scattering event (PathRadiance::emitted).
    Color emitted(0);
    auto addEmitted = [&](const Color& c, int events) {
        add(c, events);
        if (events == 0) emitted += c;
    };
    auto result = [&](float transmittance) { return PathRadiance{L, transmittance, direct, emitted}; };
    MediumPoint mp;
    // Next-event estimation at a vertex of the path, and the connections to
    // sphere lights through glass spheres (sphere_caustics.h); true when
    // those were made (the path's own hits through a ball weigh against them).
    // `deltaWeight`: the share of the point-like and parallel lights'
    // connections left to the vertex by the distance sample near caustic
    // folds (light_distance.h).
    auto nextEvent = [&](const ScatterVertex& vertex, const float* lightWeights, float deltaWeight) {
        add(beta * directLight(ctx, region, vertex, rng, nextEventOptions(st, lightWeights)), st.depth);
        if (!sceneHasSphereCaustics(scene)) return false;
        add(beta * sphereCausticLight(ctx, region, vertex, rng, TransmittanceEstimator::UnbiasedMarching,
                                              {true, !st.pointLightsByPhotons, true, true, deltaWeight}),
            st.depth);
        return true;
    };
    while (true) {
        const RaySegment seg = nextRaySegment(scene, ray, probeLength(ctx, region, channel, st));
        const SurfaceHit& h = seg.surface;
        const bool hit = seg.hitSurface;
        const int light = seg.light;
        const float tEnd = seg.tEnd;

        // Distance sampling towards point, spot and sphere lights along the
        // segment, weighed against the collisions' next-event estimates by
        // MIS (light_distance.h).
        LightDistanceSegment lightDistances =
            st.depth < maxDepth ? prepareLightDistances(ctx, region, ray, tEnd, channel, st.pointLightsByPhotons)
                                : LightDistanceSegment{};
        if (lightDistances.active) add(beta * sampleLightDistances(ctx, lightDistances, rng), st.depth + 1);
        // And near the folds of caustics behind glass spheres that the
        // segment crosses, where connected light grows as 1 / sqrt(distance).
        FoldSampler folds;
        if (st.depth < maxDepth && prepareFoldDistances(ctx, region, ray, tEnd, folds))
            add(beta * sampleFoldDistances(ctx, lightDistances, folds, !st.pointLightsByPhotons, rng), st.depth + 1);

        // A real scattering event at x (media mp there): next-event
        // estimation, then the next direction.
        // False when max_depth ends the path.
        auto scatterAt = [&](Vec3 x, float t, const MediumPoint& mp) {
            if (++st.depth > maxDepth) {
                beta = Color(0);
                return false;
            }
            // A collision exactly on a fold's crossing moves to the next
            // float, as every sampler's draw does (FoldSampler::offCrossing).
            if (!folds.empty()) {
                const float moved = folds.offCrossing(t);
                if (moved != t) t = moved, x = ray.at(t);
            }
            ScatterVertex vertex = ScatterVertex::inMedium(x, ray.d, mp.phase);
            // A share of the directions towards spot and collimated beams
            // (beam_directions.h).
            BeamMixture beams{&ctx, region, &vertex};
            const bool beamDirections = beams.attach(vertex, st.pointLightsByPhotons);
            const float* weights = lightDistances.active ? trackingWeights(ctx, lightDistances, t, mp) : nullptr;
            const float deltaWeight = foldTrackingWeight(ctx, lightDistances, folds, t, mp);
            const bool caustics = nextEvent(vertex, weights, deltaWeight);
            if (st.firstVertexLight) {
                add(beta * st.firstVertexLight->at(x, region, -ray.d, mp.phase), st.depth);
                st.firstVertexLight = nullptr;
            }
            // The next direction: the beams' mixture or the phase's.
            float pdf = 0;
            Vec3 wi;
            if (beamDirections) {
                wi = beams.sample(rng, beta, pdf);
                scaleRoulette(st, vertex, wi, pdf);
            } else {
                const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                wi = mp.phase.sample(ray.d, u0, u1, u2, beta, pdf);
            }
            startVertex(st, x, wi, pdf, caustics);
            ray = Ray{x, wi};
            return true;
        };

        bool scattered = false;
        {
            // Delta tracking to the next real collision, or to tEnd; the
            // collision callback returns false once the path scattered or
            // was absorbed.
            deltaTrack(ctx, region, ray, tEnd, channel, rng, [&](const Vec3& x, float sigmaMaj) {
                evalMedia(ctx, region, x, mp);
                ++ctx.counters.marchSamples;
                // Emission: sigma_a L_e / sigma_maj at every tentative collision.
                if (!isBlack(mp.emission)) addEmitted(beta * mp.sigma_a * mp.emission / sigmaMaj, st.depth);
                float sa = trackedOrAverage(mp.sigma_a, channel), ss = trackedOrAverage(mp.sigma_s, channel);
                float u = rng.uniform() * sigmaMaj;
                if (u < sa) {
                    beta = Color(0);  // absorbed
                    return false;
                }
                if (u >= sa + ss) return true;  // null collision
                // Real scattering; weight sigma_s / (P_s sigma_maj) per channel.
                beta *= (channel < 0 ? mp.sigma_s / ss : Color(1));
                scattered = scatterAt(x, dot(x - ray.o, ray.d), mp);
                return false;
            });
        }
        if (isBlack(beta)) return result(0.f);
        if (scattered) {
            if (!roulette(beta, st, rng)) return result(0.f);
            continue;
        }
        // Reached tEnd without a real collision.
        if (seg.cut) {  // the end of the probed length: the same free flight goes on
            ray.o = ray.at(tEnd);
            continue;
        }
        if (light >= 0) {
            const Light& l = scene.lights[size_t(light)];
            float w = 1;
            if (!st.specular) {
                // pdf with which next-event estimation at lastPoint would pick this direction
                Vec3 to = l.desc().position - st.lastPoint;
                float d2 = lengthSquared(to), r2 = l.desc().radius * l.desc().radius;
                float sin2 = r2 / d2, cosMax = sin2 < 1e-6f ? 1 - 0.5f * sin2 : safeSqrt(1 - sin2);
                w = powerHeuristic(st.lastPdf, uniformConePdf(cosMax));
            } else if (st.causticsAtLast && st.lensRefractions >= 1) {
                // Through a glass sphere (or across its surface), which
                // sphere caustic connections at lastPoint also follow.
                w = sphereCausticPathWeight(scene, st.lensSphere, st.lensRefractions, light, st.lastPoint, st.lastDir,
                                            st.lastPdf, ray.at(tEnd));
            }
            if (!st.mirrorCounted) addEmitted(beta * l.emittedRadiance() * w, st.depth);
            return result(0.f);
        }
        if (!hit) {
            // An environment map was also sampled by next-event estimation
            // at the last vertex (direct_light.cpp): weigh the two by MIS.
            const Environment& env = scene.environment;
            const float w = !st.specular && env.hasMap() ? powerHeuristic(st.lastPdf, env.pdf(ray.d)) : 1.f;
            // A camera path that never scattered sees the map as a backdrop.
            if (!st.mirrorCounted)
                add(beta * (st.depth == 0 ? env.radianceSeen(ray.d) : env.radiance(ray.d)) * w, st.depth);
            return result(st.depth == startDepth && st.surfaceBounces == 0 ? average(beta) : 0.f);
        }
        ++ctx.counters.surfaceHits;
        if (++st.surfaceBounces > scene.desc.render.maxSurfaceBounces) return result(0.f);
        const float u[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
        // Glass may split a camera path, or count the light its reflection
        // sees (glass_splitting.h).
        const bool split = st.depth == 0 && st.glassSplits < SplitDielectricEvents;
        const PathSurfaceEvent pe = pathSurfaceEvent(ctx, h, ray.d, region, u, split, st.depth == 0, rng);
        add(beta * pe.light, st.depth);
        st.mirrorCounted = pe.mirrorCounted;
        if (pe.split) {
            ++st.glassSplits;
            PathState sr = st;
            followSurfaceEvent(scene, pe.mirror, h.surface, sr);
            const Color br = beta * pe.mirrorWeight;
            sr.rouletteScale = std::min(sr.rouletteScale * average(br), 1e20f);
            const PathRadiance pr = tracePath(ctx, pe.mirror.ray, pe.mirror.region, channel, rng, sr);
            L += br * pr.L;
            direct += br * pr.direct;
            emitted += br * pr.emitted;
        }
        const SurfaceEvent& e = pe.event;
        Color weight = pe.weight;
        Ray next = e.ray;
        if (e.kind == SurfaceEvent::Kind::Diffuse) {
            if (++st.depth > maxDepth) return result(0.f);
            const Color& albedo = scene.surfaces[size_t(h.surface)].material.albedo;
            ScatterVertex vertex = ScatterVertex::onSurface(h.p, ray.d, h.n, albedo);
            // A share of the directions towards spot and collimated beams
            // (beam_directions.h).
            BeamMixture beams{&ctx, region, &vertex};
            const bool beamDirections = beams.attach(vertex, st.pointLightsByPhotons);
            const bool caustics = nextEvent(vertex, nullptr, 1.f);
            float pdf = e.pdf;
            if (beamDirections) {
                weight = Color(1);
                next.d = beams.sample(rng, weight, pdf);
                if (isBlack(weight)) return result(0.f);  // a beam below the surface
                next.o = offsetRayOrigin(scene, h.p, vertex.arrivalNormal(), next.d);
                scaleRoulette(st, vertex, next.d, pdf);
            }
            startVertex(st, h.p, next.d, pdf, caustics);
        } else {
            followSurfaceEvent(scene, e, h.surface, st);
        }
        beta *= weight;
        ray = next;
        region = e.region;
        if (e.kind == SurfaceEvent::Kind::Diffuse && !roulette(beta, st, rng)) return result(0.f);
    }
}

}  // namespace vdbmarch
