// Pieces every marcher shares: per-thread medium queries, the media of a
// region at a point, the union of active intervals along a ray (empty space
// skipping), shadow-ray transmittance, and direct lighting (next-event
// estimation to every light, plus the background as a constant environment).
#pragma once

#include <cmath>
#include <memory>
#include <vector>

#include "core/math.h"
#include "core/rng.h"
#include "cache/cache_lookup.h"
#include "core/stats.h"
#include "marchers/ray_pdf.h"
#include "scene/scene.h"

namespace vdbmarch {

constexpr int MaxMediaPerPoint = 8;

struct ThreadContext {
    explicit ThreadContext(const Scene& s);
    const Scene& scene;
    std::vector<std::unique_ptr<MediumQuery>> queries;  // one per medium
    std::vector<Interval> intervals, shadowIntervals, scratch;
    std::vector<MajorantSegment> majorants, scratchSegments;
    RenderCounters counters;
    // The sampled marchers' per-ray histogram: steps, their media, the cache.
    std::vector<PdfStep> pdfSteps;
    std::vector<Color> stepSigmaS, stepKappa, stepT;
    std::vector<float> stepH;
    RayPdf rayPdf;
    std::unique_ptr<CacheLookup> cacheLookup;  // made on first use
    // The guided marcher's pre-pass (eq. 17's scale): march without sampling
    // and sum each segment's throughput times its histogram integral.
    bool measureOnly = false;
    double measuredGuided = 0;
    size_t measuredSegments = 0;  // segments through scattering media
};

// Coefficients of all media of a region at one point. Each medium's
// coefficients are clamped to MaxCoefficient so sums stay finite.
constexpr float MaxCoefficient = 1e30f;

struct MediumPoint {
    Color sigma_a, sigma_s, sigma_t;
    Color emission;  // L_e averaged with weights sigma_a,i (sigma_a L_e / sigma_a)
    int count = 0;   // media that scatter here, for the phase mixture
    Color sigmaS[MaxMediaPerPoint];
    float g[MaxMediaPerPoint];
};

void evalMedia(ThreadContext& ctx, int region, const Vec3& p, MediumPoint& mp);

// Sorted, merged union of the active intervals of the region's media within
// [tMin, tMax].
void regionIntervals(ThreadContext& ctx, int region, const Ray& r, float tMin, float tMax,
                     std::vector<Interval>& out);

// Phase function of the mixture at a point: sum_i sigma_s,i p_i(cos) / sigma_s
// per channel; cos is between the light's travel direction and the scattered
// direction. Normalised so that huge coefficients cannot overflow.
Color phaseMixture(const MediumPoint& mp, float cosTheta);

// Extinction used for tracking: channel c, or (grey media, channel < 0) channel 0.
inline float trackedSigmaT(const Color& sigmaT, int channel) { return sigmaT[channel < 0 ? 0 : channel]; }

// One medium's majorant segments along [0, tEnd): local (per VDB block) by
// default; with render.global_majorant, the grid's maximum over its bounding
// box (the classic baseline the local majorants are benchmarked against).
void mediumMajorants(ThreadContext& ctx, int medium, const Ray& r, float tEnd, std::vector<MajorantSegment>& out);

// Combined extinction majorant of the region's media along [0, tEnd) for the
// tracked `channel` (delta tracking of paths and photons).
void regionMajorants(ThreadContext& ctx, int region, const Ray& r, float tEnd, int channel,
                     std::vector<MajorantSegment>& out);

// Smooth dielectric with outward normal n: reflects with the Fresnel
// probability, else refracts (the weights cancel). Returns the new unit
// direction; `refracted` says whether it crossed to the other side.
Vec3 sampleDielectric(const Vec3& d, const Vec3& n, float ior, float u, bool& refracted);

// Samples the phase mixture at a scattering point (a medium by sigma_s, then
// its HG lobe) around the travel direction d. Multiplies `weight` by f / pdf
// per channel (1 for a single medium) and sets the direction's pdf.
Vec3 samplePhaseMixture(const MediumPoint& mp, const Vec3& d, Rng& rng, Color& weight, float& pdf);

// Delta tracking along [0, tEnd) of `ray` in `region`: tentative collisions
// are drawn at rate sigma_maj against the local majorants (walked lazily for
// a single medium, so blocks past the first real collision are never
// visited), and collide(x, sigmaMaj) is called at each until it returns false.
template <typename Collide>
void deltaTrack(ThreadContext& ctx, int region, const Ray ray, float tEnd, int channel, Rng& rng, Collide&& collide) {
    // `ray` is a copy: collide() may replace the caller's ray when it scatters.
    auto track = [&](const MajorantSegment& seg) {
        const float sigmaMaj = seg.maxDensity;
        if (!(sigmaMaj > 0)) return true;
        double t = seg.t0;
        while (true) {
            t -= std::log(1 - double(rng.uniform())) / sigmaMaj;
            if (t >= seg.t1) return true;
            if (!collide(ray.at(t), sigmaMaj)) return false;
        }
    };
    const auto& media = ctx.scene.regions[size_t(region)].media;
    if (media.size() == 1 && !ctx.scene.desc.render.globalMajorant) {
        const Medium& m = *ctx.scene.media[size_t(media[0])];
        const float k = trackedSigmaT(m.sigma_a + m.sigma_s, channel);
        ctx.queries[size_t(media[0])]->forEachMajorant(ray, 0.f, tEnd, [&](const MajorantSegment& s) {
            return track({s.t0, s.t1, s.maxDensity * k});
        });
    } else if (!media.empty()) {
        regionMajorants(ctx, region, ray, tEnd, channel, ctx.majorants);
        for (const auto& seg : ctx.majorants)
            if (!track(seg)) break;
    }
}

// Transmittance from p along direction wi over distance `dist` (Infinity for
// the environment/directional lights), starting in `region`. Interfaces are
// crossed (the region changes), every other surface and sphere lights block.
// Optical depth by uniform steps with a random offset.
Color shadowTransmittance(ThreadContext& ctx, int region, const Vec3& p, const Vec3& wi, float dist, Rng& rng);

// In-scattered radiance L_i (eq. 3) at p towards -rayDir from light that
// arrives unscattered: next-event estimation to every light, and one
// phase-sampled direction for the background environment.
Color directInScattering(ThreadContext& ctx, int region, const Vec3& p, const Vec3& rayDir, const MediumPoint& mp,
                         Rng& rng);

// Radiance leaving a diffuse surface at hit towards -rayDir, from direct light.
Color directDiffuse(ThreadContext& ctx, int region, const Vec3& p, const Vec3& n, const Vec3& rayDir,
                    const Color& albedo, Rng& rng);

// Offset origin for a ray leaving a surface at p in direction d.
Vec3 offsetRayOrigin(const Scene& scene, const Vec3& p, const Vec3& n, const Vec3& d);

// Region that a ray starting at r.o is in, from the first surface it meets.
int regionAtRayStart(const Scene& scene, const Ray& r);

// Closest sphere light hit in (tMin, tMax); returns the light index or -1.
int intersectSphereLights(const Scene& scene, const Ray& r, float tMin, float tMax, float& t);

// Walks a shadow ray from r.o over distance `dist` (Infinity: to the
// environment), starting in `region`: calls segment(region, ray, tEnd) for
// each piece between surfaces; interfaces and index-matched glass are crossed
// (the region changes), any other surface or a sphere light blocks. Returns false when blocked or
// when `segment` returned false.
template <typename Segment>
bool walkShadowRay(const Scene& scene, int region, Ray r, float dist, Segment&& segment) {
    float remaining = dist;
    for (int crossing = 0; crossing <= scene.desc.render.maxSurfaceBounces; ++crossing) {
        // A target sphere light sits at `remaining`; stop just short of it.
        float tLimit = std::isfinite(remaining) ? remaining * (1 - 1e-4f) : Infinity;
        SurfaceHit h;
        bool hit = scene.surfaceSet->intersect(r, 0.f, tLimit, h);
        float tLight;
        if (intersectSphereLights(scene, r, 1e-4f * scene.sceneScale, hit ? h.t : tLimit, tLight) >= 0) return false;
        if (!segment(region, r, hit ? h.t : remaining)) return false;
        if (!hit) return true;
        const SurfaceInfo& s = scene.surfaces[size_t(h.surface)];
        // Refracting glass bends the path and diffuse surfaces are opaque: a
        // straight shadow ray cannot pass them. Index-matched glass (ior 1)
        // neither reflects nor bends, so it is crossed like an interface.
        bool straight = s.material.type == MaterialDesc::Type::Interface ||
                        (s.material.type == MaterialDesc::Type::Dielectric && s.material.ior == 1.f);
        if (!straight) return false;
        region = dot(r.d, h.n) < 0 ? s.interiorRegion : s.exteriorRegion;
        r.o = offsetRayOrigin(scene, h.p, h.n, r.d);
        if (std::isfinite(remaining)) remaining -= h.t;
    }
    return false;
}

}  // namespace vdbmarch
