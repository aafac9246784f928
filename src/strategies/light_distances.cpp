#include "strategies/light_distances.h"

#include <algorithm>
#include <cmath>

#include "transport/direct_light.h"

namespace vdbmarch {

namespace {

// A ray through a point light's very position: keep the density finite.
float minDistance(const Scene& scene, const Light& light) {
    const LightSphere* sphere = light.sphere();
    return sphere ? sphere->radius : 1e-6f * scene.sceneScale;
}

// Distance sampling pays where its gain over tracking exceeds this (see
// prepare). A sphere light's radiance is bounded (its solid angle, not
// 1/r^2, grows near it) and next-event estimation already meets the path's
// hits by MIS there: it needs a much larger gain (docs/method.md).
float gainThreshold(const Light& light) { return light.sphere() ? 64.f : 2.f; }

}  // namespace

// A (region, light) pair is a candidate when the light is point-like or a
// sphere; no surface that blocks shadow rays separates it from the region;
// and, for point and sphere lights (whose reach is the whole ray), the
// falloff range over the region's bounds, at most (farthest corner /
// nearest point)^2, can exceed the gain threshold.
LightDistances::LightDistances(const Scene& scene, size_t slot)
    : mScene(scene), mSlot(slot), mLights(scene.lights.size()),
      mEquiangularOnly(scene.desc.experiments.volumeSampling == VolumeSampling::Equiangular),
      mOff(scene.desc.experiments.volumeSampling == VolumeSampling::Distance),
      mScatterBounds(scatterBoundsOf(scene)), mCandidate(scene.regions.size() * mLights, 0) {
    for (size_t r = 0; r < scene.regions.size(); ++r) {
        const BBox& hull = mScatterBounds[r];
        if (hull.empty()) continue;
        for (size_t i = 0; i < mLights; ++i) {
            const Light& light = scene.lights[i];
            if (!(light.isPointLike() || light.sphere())) continue;
            const Vec3& c = light.desc().position;
            if (!openToRegion(scene, c, int(r))) continue;
            bool mayPay = true;
            if (!light.spotCone() && hull.isFinite()) {
                const Vec3 nearest = min(max(c, hull.lo), hull.hi);
                const Vec3 farthest = max(max(c - hull.lo, hull.lo - c), max(c - hull.hi, hull.hi - c));
                const float rMin = std::max(length(c - nearest), minDistance(scene, light));
                mayPay = lengthSquared(farthest) > gainThreshold(light) * rMin * rMin;
            }
            mCandidate[r * mLights + i] = mayPay;
        }
    }
}

bool LightDistances::regionHasCandidates(int region, bool skipPointLights) const {
    if (mOff) return false;
    for (size_t i = 0; i < mLights; ++i)
        if (mCandidate[size_t(region) * mLights + i] && !(skipPointLights && mScene.lights[i].isPointLike()))
            return true;
    return false;
}

bool LightDistances::prepare(ThreadContext& ctx, const PathSegment& seg) const {
    std::vector<LightDistance>& lights = scratch(ctx).lights;
    lights.clear();
    if (!regionHasCandidates(seg.region, seg.skipPointLights)) return false;
    const Ray& ray = seg.ray;
    // The segment's part in the region's scattering media.
    float a = 0, b = seg.tEnd;
    if (!mScatterBounds[size_t(seg.region)].intersect(ray, a, b) || !(b > a)) return false;
    for (size_t i = 0; i < mLights; ++i) {
        if (!candidate(seg.region, int(i)) || (seg.skipPointLights && mScene.lights[i].isPointLike())) continue;
        const Light& light = mScene.lights[i];
        float t0, t1;
        if (!ctx.lightReach(int(i), ray, t0, t1)) continue;
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        if (!(t1 > t0)) continue;
        // Worth its shadow ray only where the light's 1/r^2 varies along the
        // part it reaches (a light near the segment) or where that part is a
        // piece of the medium's span (a spot's beam): elsewhere delta
        // tracking spreads its collisions as evenly as the light does. The
        // gain over tracking is the falloff range along the reach times the
        // span it leaves out; a function of the segment alone, so the
        // tracking weight is 1 wherever this skips: still unbiased.
        const Vec3& c = light.desc().position;
        const float rMin = minDistance(mScene, light);
        const float span = b - a, reach = t1 - t0, leftOut = span == reach ? 1.f : span / reach;
        const float gain = EquiangularSampler::falloffRange(ray.o, ray.d, c, t0, t1, rMin) * leftOut;
        if (!(gain > gainThreshold(light))) continue;
        EquiangularSampler s(ray.o, ray.d, c, t0, t1, rMin);
        if (s.valid()) lights.push_back({int(i), s});
    }
    // Several lights: one distance sample per segment, for a light chosen
    // in proportion to its unoccluded single scattering along the segment
    // (intensity times the integral of 1/r^2), so that a scene with many
    // spots casts one shadow ray per segment, not one per spot.
    if (lights.size() > 1) {
        double sum = 0;
        for (LightDistance& ld : lights) {
            const Light& light = mScene.lights[size_t(ld.light)];
            const Color intensity = light.sphere() ? light.desc().power * (1 / (4 * Pi)) : light.desc().intensity;
            ld.choice = std::max(average(intensity), 0.f) * ld.sampler.inverseSquareIntegral();
            sum += double(ld.choice);
        }
        for (LightDistance& ld : lights)
            ld.choice = sum > 0 ? float(double(ld.choice) / sum) : 1.f / float(lights.size());
    }
    return !lights.empty();
}

Color LightDistances::sample(ThreadContext& ctx, const PathSegment& seg, Rng& rng) const {
    const std::vector<LightDistance>& samplers = scratch(ctx).lights;
    if (samplers.empty()) return Color(0);
    // The segment's light (prepare chose the odds).
    size_t k = 0;
    if (samplers.size() > 1) {
        const float u = rng.uniform();
        for (float cdf = samplers[0].choice; k + 1 < samplers.size() && !(u < cdf); cdf += samplers[++k].choice) {
        }
    }
    const LightDistance& ld = samplers[k];
    const float t = ld.sampler.sample(rng.uniform());
    return scatteredAt(ctx, seg, t, ld.choice * ld.sampler.pdf(t), mEquiangularOnly, rng, [&](const ScatterVertex& v) {
        DirectLightOptions o;
        o.transmittance = TransmittanceEstimator::UnbiasedMarching;
        o.misWithPathHits = true;  // a sphere light is also found by the phase-sampled path
        o.sampleBackground = false;
        o.onlyLight = ld.light;
        return directLight(ctx, seg.region, v, rng, o);
    });
}

void LightDistances::weighCollision(ThreadContext& ctx, const PathSegment& seg, float t, const MediumPoint& mp,
                                    CollisionWeights& w) const {
    Scratch& s = scratch(ctx);
    s.weights.assign(mLights, 1.f);
    const float pTrack = trackingDensity(ctx, seg, t, mp);
    for (const LightDistance& ld : s.lights) {
        const float pdf = ld.choice * ld.sampler.pdf(t);
        const float taken = !(pdf > 0) ? 0.f : mEquiangularOnly ? 1.f : distanceWeight(pdf, pTrack);
        s.weights[size_t(ld.light)] = 1 - taken;
    }
    w.lightWeights = s.weights.data();
}

}  // namespace vdbmarch
