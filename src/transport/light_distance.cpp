#include "transport/light_distance.h"

#include <cmath>

#include "transport/direct_light.h"
#include "transport/path_tracer.h"
#include "transport/tracking.h"
#include "transport/transmittance.h"

namespace vdbmarch {

namespace {

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

// The power heuristic between the equiangular density and the tracking one.
float equiangularWeight(const LightDistanceSegment& seg, float pdfEquiangular, float pdfTracking) {
    if (!(pdfEquiangular > 0)) return 0.f;
    if (seg.equiangularOnly) return 1.f;
    const double a = double(pdfEquiangular) * pdfEquiangular, b = double(pdfTracking) * pdfTracking;
    return float(a / (a + b));
}

}  // namespace

LightDistanceSegment prepareLightDistances(ThreadContext& ctx, int region, const Ray& ray, float tEnd, int channel,
                                           bool skipPointLights) {
    ctx.lightDistances.clear();
    const Scene& scene = ctx.scene;
    const VolumeSampling mode = scene.desc.render.volumeSampling;
    LightDistanceSegment seg{ray, region, channel, mode == VolumeSampling::Equiangular};
    if (mode == VolumeSampling::Distance) return seg;
    // Point-like and sphere lights that shadow rays from this region can see.
    auto eligible = [&](size_t i) {
        const Light& light = scene.lights[i];
        return (light.isSphere() || (light.isPointLike() && !skipPointLights)) &&
               !(ctx.blockingSurfaces && ctx.lightRegions[i] != region);
    };
    bool any = false;
    for (size_t i = 0; i < scene.lights.size() && !any; ++i) any = eligible(i);
    if (!any) return seg;
    // The hull of the scattering media's bounds along the segment.
    float a = Infinity, b = -Infinity;
    for (int mi : scene.regions[size_t(region)].media) {
        const Medium& m = *scene.media[size_t(mi)];
        if (isBlack(m.sigma_s) || m.isVacuum()) continue;
        float t0 = 0, t1 = tEnd;
        if (!m.worldBounds().intersect(ray, t0, t1)) continue;
        a = std::min(a, t0);
        b = std::max(b, t1);
    }
    if (!(b > a)) return seg;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        if (!eligible(i)) continue;
        const Light& light = scene.lights[i];
        float t0, t1;
        if (!light.reachInterval(ray, t0, t1)) continue;
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        if (!(t1 > t0)) continue;
        // A ray through a point light's very position: keep the density finite.
        const float minDistance = light.isSphere() ? light.desc().radius : 1e-6f * scene.sceneScale;
        // Worth its shadow ray only where the light's 1/r^2 varies along the
        // part it reaches (a light near the segment) or where that part is a
        // piece of the medium's span (a spot's beam): elsewhere delta
        // tracking spreads its collisions as evenly as the light does (a
        // light far above a fog layer). A function of the segment alone, so
        // the tracking weight is 1 wherever this skips: still unbiased.
        // A sphere light's radiance is bounded (its solid angle, not 1/r^2,
        // grows near it) and next-event estimation already meets the path's
        // hits by MIS there: it needs a much larger gain to pay (measured
        // on exp1_sphere and fig4_caustic_sphere, BENCHMARKS.md).
        const Vec3& c = light.desc().position;
        // The gain over tracking: how much the light's falloff varies along
        // its reach, times how much of the medium's span it leaves out.
        // (Unbounded fog and an escaping ray: both spans infinite, nothing left out.)
        const float span = b - a, reach = t1 - t0, leftOut = span == reach ? 1.f : span / reach;
        const float gain = EquiangularSampler::falloffRange(ray.o, ray.d, c, t0, t1, minDistance) * leftOut;
        if (!(gain > (light.isSphere() ? 64.f : 2.f))) continue;
        EquiangularSampler s(ray.o, ray.d, c, t0, t1, minDistance);
        if (s.valid()) ctx.lightDistances.push_back({int(i), s});
    }
    seg.active = !ctx.lightDistances.empty();
    return seg;
}

Color sampleLightDistances(ThreadContext& ctx, const LightDistanceSegment& seg, Rng& rng) {
    Color L(0);
    MediumPoint mp;
    for (const ThreadContext::LightDistance& ld : ctx.lightDistances) {
        const float u = rng.uniform();
        const float t = ld.sampler.sample(u);
        const float pdf = ld.sampler.pdf(t);
        if (!(pdf > 0)) continue;
        const Vec3 x = seg.ray.at(t);
        evalMedia(ctx, seg.region, x, mp);
        if (!mp.scatters()) continue;
        float w = equiangularWeight(seg, pdf, trackingDensity(ctx, seg, t, mp));
        if (!(w > 0) || !rouletteOnWeight(w, rng)) continue;
        const Color T = regionTransmittance(ctx, seg.region, seg.ray, t, rng);
        if (isBlack(T)) continue;
        DirectLightOptions o;
        o.transmittance = TransmittanceEstimator::RatioTracking;
        o.misWithPathHits = true;  // a sphere light is also found by the phase-sampled path
        o.sampleBackground = false;
        o.onlyLight = ld.light;
        const Color nee = directLight(ctx, seg.region, ScatterVertex::inMedium(x, seg.ray.d, mp.phase), rng, o);
        L += T * mp.sigma_s * nee * (w / pdf);
    }
    return L;
}

const float* trackingWeights(ThreadContext& ctx, const LightDistanceSegment& seg, float t, const MediumPoint& mp) {
    ctx.lightWeights.assign(ctx.scene.lights.size(), 1.f);
    const float pTrack = trackingDensity(ctx, seg, t, mp);
    for (const ThreadContext::LightDistance& ld : ctx.lightDistances)
        ctx.lightWeights[size_t(ld.light)] = 1 - equiangularWeight(seg, ld.sampler.pdf(t), pTrack);
    return ctx.lightWeights.data();
}

}  // namespace vdbmarch
