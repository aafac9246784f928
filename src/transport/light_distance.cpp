#include "transport/light_distance.h"

#include <algorithm>
#include <cmath>

#include "transport/direct_light.h"
#include "transport/path_tracer.h"
#include "transport/roulette.h"
#include "transport/sphere_caustics.h"
#include "transport/surface_event.h"
#include "transport/tracking.h"
#include "transport/transmittance.h"

namespace vdbmarch {

namespace {

// A ray through a point light's very position: keep the density finite.
float minDistance(const Scene& scene, const Light& light) {
    return light.isSphere() ? light.desc().radius : 1e-6f * scene.sceneScale;
}

// Distance sampling pays where its gain over tracking exceeds this (see
// prepareLightDistances). A sphere light's radiance is bounded (its solid
// angle, not 1/r^2, grows near it) and next-event estimation already meets
// the path's hits by MIS there: it needs a much larger gain (measured on
// exp1_sphere and fig4_caustic_sphere, BENCHMARKS.md).
float gainThreshold(const Light& light) { return light.isSphere() ? 64.f : 2.f; }

// The density with which delta tracking makes a scattering collision at t,
// for the weights only: sigma_s of the tracked channel times the
// transmittance of the region's constant media (gridded media count as
// clear: see the header).
float trackingDensity(ThreadContext& ctx, const LightDistanceSegment& seg, float t, const MediumPoint& mp) {
    float tau = 0;
    for (int mi : ctx.scene.regions[size_t(seg.region)].media) {
        float integral;
        if (!ctx.queries[size_t(mi)]->densityIntegral(seg.ray, 0.f, t, integral) || !(integral > 0)) continue;
        const Medium& m = *ctx.scene.media[size_t(mi)];
        tau += trackedSigmaT(m.sigma_a + m.sigma_s, seg.channel) * integral;
    }
    return trackedOrAverage(mp.sigma_s, seg.channel) * std::exp(-tau);
}

// The power heuristic between a distance sampler's density and the tracking one.
float distanceWeight(float pdfDistance, float pdfTracking) {
    if (!(pdfDistance > 0)) return 0.f;
    const double a = double(pdfDistance) * pdfDistance, b = double(pdfTracking) * pdfTracking;
    return float(a / (a + b));
}
float equiangularWeight(const LightDistanceSegment& seg, float pdfEquiangular, float pdfTracking) {
    if (!(pdfEquiangular > 0)) return 0.f;
    if (seg.equiangularOnly) return 1.f;
    return distanceWeight(pdfEquiangular, pdfTracking);
}

// Per (region, light) whether distance sampling can ever pay there: the light is
// point-like or a sphere; no surface that blocks shadow rays separates it
// from the region; and, for point and sphere lights (whose reach is the
// whole ray), the falloff range over the region's bounds, at most
// (farthest corner / nearest point)^2, can exceed the gain threshold.
void buildCandidates(ThreadContext& ctx) {
    const Scene& scene = ctx.scene;
    const size_t nLights = scene.lights.size();
    ctx.lightDistanceCandidate.assign(scene.regions.size() * nLights, 0);
    for (size_t r = 0; r < scene.regions.size(); ++r) {
        const BBox& hull = scatterBounds(ctx, int(r));
        if (hull.empty()) continue;
        for (size_t i = 0; i < nLights; ++i) {
            const Light& light = scene.lights[i];
            if (!(light.isPointLike() || light.isSphere())) continue;
            const Vec3& c = light.desc().position;
            if (!openToRegion(scene, c, int(r))) continue;
            bool mayPay = true;
            if (light.desc().type != LightDesc::Type::Spot && hull.isFinite()) {
                const Vec3 nearest = min(max(c, hull.lo), hull.hi);
                const Vec3 farthest = max(max(c - hull.lo, hull.lo - c), max(c - hull.hi, hull.hi - c));
                const float rMin = std::max(length(c - nearest), minDistance(scene, light));
                mayPay = lengthSquared(farthest) > gainThreshold(light) * rMin * rMin;
            }
            ctx.lightDistanceCandidate[r * nLights + i] = mayPay;
        }
    }
}

}  // namespace

const BBox& scatterBounds(ThreadContext& ctx, int region) {
    const Scene& scene = ctx.scene;
    if (ctx.scatterBounds.empty()) {
        ctx.scatterBounds.assign(scene.regions.size(), BBox{});
        for (size_t r = 0; r < scene.regions.size(); ++r)
            for (int mi : scene.regions[r].media) {
                const Medium& m = *scene.media[size_t(mi)];
                if (!isBlack(m.sigma_s) && !m.isVacuum()) ctx.scatterBounds[r].expand(m.worldBounds());
            }
    }
    return ctx.scatterBounds[size_t(region)];
}

bool openToRegion(const Scene& scene, const Vec3& position, int region) {
    for (const SurfaceInfo& surface : scene.surfaces)
        if (!crossedByShadowRays(surface.material))
            return regionAtRayStart(scene, Ray{position, Vec3(0, 0, 1)}) == region;
    return true;
}

bool regionHasLightDistances(ThreadContext& ctx, int region, bool skipPointLights) {
    const Scene& scene = ctx.scene;
    if (scene.desc.experiments.volumeSampling == VolumeSampling::Distance || scene.lights.empty()) return false;
    if (ctx.lightDistanceCandidate.empty()) buildCandidates(ctx);
    const size_t nLights = scene.lights.size();
    for (size_t i = 0; i < nLights; ++i)
        if (ctx.lightDistanceCandidate[size_t(region) * nLights + i] && !(skipPointLights && scene.lights[i].isPointLike()))
            return true;
    return false;
}

bool lightReach(ThreadContext& ctx, int light, const Ray& ray, float& t0, float& t1) {
    if (light >= ThreadContext::ReachMemoLights) return ctx.scene.lights[size_t(light)].reachInterval(ray, t0, t1);
    ThreadContext::ReachMemo& m = ctx.reachMemo[light];
    if (!(m.valid && m.o.x == ray.o.x && m.o.y == ray.o.y && m.o.z == ray.o.z && m.d.x == ray.d.x &&
          m.d.y == ray.d.y && m.d.z == ray.d.z)) {
        m.reaches = ctx.scene.lights[size_t(light)].reachInterval(ray, m.t0, m.t1);
        m.o = ray.o;
        m.d = ray.d;
        m.valid = true;
    }
    t0 = m.t0;
    t1 = m.t1;
    return m.reaches;
}

LightDistanceSegment prepareLightDistances(ThreadContext& ctx, int region, const Ray& ray, float tEnd, int channel,
                                           bool skipPointLights) {
    ctx.lightDistances.clear();
    const Scene& scene = ctx.scene;
    const VolumeSampling mode = scene.desc.experiments.volumeSampling;
    LightDistanceSegment seg{ray, region, channel, mode == VolumeSampling::Equiangular};
    seg.tEnd = tEnd;
    if (!regionHasLightDistances(ctx, region, skipPointLights)) return seg;
    const size_t nLights = scene.lights.size();
    const char* candidate = ctx.lightDistanceCandidate.data() + size_t(region) * nLights;
    auto eligible = [&](size_t i) { return candidate[i] && !(skipPointLights && scene.lights[i].isPointLike()); };
    // The segment's part in the region's scattering media.
    float a = 0, b = tEnd;
    if (!ctx.scatterBounds[size_t(region)].intersect(ray, a, b) || !(b > a)) return seg;
    for (size_t i = 0; i < nLights; ++i) {
        if (!eligible(i)) continue;
        const Light& light = scene.lights[i];
        float t0, t1;
        if (!lightReach(ctx, int(i), ray, t0, t1)) continue;
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        if (!(t1 > t0)) continue;
        // Worth its shadow ray only where the light's 1/r^2 varies along the
        // part it reaches (a light near the segment) or where that part is a
        // piece of the medium's span (a spot's beam): elsewhere delta
        // tracking spreads its collisions as evenly as the light does (a
        // light far above a fog layer). The gain over tracking is the
        // falloff range along the reach times the span it leaves out
        // (unbounded fog and an escaping ray: both infinite, nothing left
        // out). A function of the segment alone, so the tracking weight is 1
        // wherever this skips: still unbiased.
        const Vec3& c = light.desc().position;
        const float rMin = minDistance(scene, light);
        const float span = b - a, reach = t1 - t0, leftOut = span == reach ? 1.f : span / reach;
        const float gain = EquiangularSampler::falloffRange(ray.o, ray.d, c, t0, t1, rMin) * leftOut;
        if (!(gain > gainThreshold(light))) continue;
        EquiangularSampler s(ray.o, ray.d, c, t0, t1, rMin);
        if (s.valid()) ctx.lightDistances.push_back({int(i), s});
    }
    // Several lights: one distance sample per segment, for a light chosen
    // in proportion to its unoccluded single scattering along the segment
    // (intensity times the integral of 1/r^2), so that a scene with many
    // spots casts one shadow ray per segment, not one per spot.
    if (ctx.lightDistances.size() > 1) {
        double sum = 0;
        for (ThreadContext::LightDistance& ld : ctx.lightDistances) {
            const Light& light = scene.lights[size_t(ld.light)];
            const Color intensity = light.isSphere() ? light.desc().power * (1 / (4 * Pi)) : light.desc().intensity;
            ld.choice = std::max(average(intensity), 0.f) * ld.sampler.inverseSquareIntegral();
            sum += double(ld.choice);
        }
        for (ThreadContext::LightDistance& ld : ctx.lightDistances)
            ld.choice = sum > 0 ? float(double(ld.choice) / sum) : 1.f / float(ctx.lightDistances.size());
    }
    seg.active = !ctx.lightDistances.empty();
    return seg;
}

namespace {

// The light `estimate(vertex, mp)` scattered at t towards the segment's
// origin, drawn with density `pdf` and weighed against the tracking
// collisions by the power heuristic (`onlyDistance`: all of it here):
// T(t) sigma_s(t) L w / pdf.
template <typename Estimate>
Color scatteredAt(ThreadContext& ctx, const LightDistanceSegment& seg, float t, float pdf, bool onlyDistance, Rng& rng,
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

}  // namespace

Color sampleLightDistances(ThreadContext& ctx, const LightDistanceSegment& seg, Rng& rng) {
    const std::vector<ThreadContext::LightDistance>& samplers = ctx.lightDistances;
    if (samplers.empty()) return Color(0);
    // The segment's light (prepareLightDistances chose the odds).
    size_t k = 0;
    if (samplers.size() > 1) {
        const float u = rng.uniform();
        for (float cdf = samplers[0].choice; k + 1 < samplers.size() && !(u < cdf); cdf += samplers[++k].choice) {
        }
    }
    const ThreadContext::LightDistance& ld = samplers[k];
    const float t = ld.sampler.sample(rng.uniform());
    return scatteredAt(ctx, seg, t, ld.choice * ld.sampler.pdf(t), seg.equiangularOnly, rng, [&](const ScatterVertex& v) {
        DirectLightOptions o;
        o.transmittance = TransmittanceEstimator::UnbiasedMarching;
        o.misWithPathHits = true;  // a sphere light is also found by the phase-sampled path
        o.sampleBackground = false;
        o.onlyLight = ld.light;
        return directLight(ctx, seg.region, v, rng, o);
    });
}

Color sampleFoldDistances(ThreadContext& ctx, const LightDistanceSegment& seg, const FoldSampler& folds, bool pointLights,
                          Rng& rng) {
    if (folds.empty()) return Color(0);
    const float t = folds.sample(rng.uniform());
    if (!(t > 0 && t < seg.tEnd)) return Color(0);
    return scatteredAt(ctx, seg, t, float(folds.pdf(t)), false, rng, [&](const ScatterVertex& v) {
        return sphereCausticLight(ctx, seg.region, v, rng, TransmittanceEstimator::UnbiasedMarching,
                                  {false, pointLights, false, true});
    });
}

float foldTrackingWeight(ThreadContext& ctx, const LightDistanceSegment& seg, const FoldSampler& folds, float t,
                         const MediumPoint& mp) {
    if (folds.empty()) return 1.f;
    return 1 - distanceWeight(float(folds.pdf(t)), trackingDensity(ctx, seg, t, mp));
}

const float* trackingWeights(ThreadContext& ctx, const LightDistanceSegment& seg, float t, const MediumPoint& mp) {
    ctx.lightWeights.assign(ctx.scene.lights.size(), 1.f);
    const float pTrack = trackingDensity(ctx, seg, t, mp);
    for (const ThreadContext::LightDistance& ld : ctx.lightDistances)
        ctx.lightWeights[size_t(ld.light)] = 1 - equiangularWeight(seg, ld.choice * ld.sampler.pdf(t), pTrack);
    return ctx.lightWeights.data();
}

}  // namespace vdbmarch
