// The unbiased reference: a volumetric path tracer.
//  - Free flights by delta tracking against local majorants from the VDB tree
//    (the maximum of each 8^3 block); in homogeneous media the majorant equals
//    the extinction, so this is analytic exponential sampling.
//  - Emission of eq. 1 collected at every tentative collision (sigma_a L_e /
//    sigma_maj), absorption / scattering / null chosen with their ratios.
//  - Next-event estimation to every light, transmittance by ratio tracking
//    (constant media exactly); sphere lights are also hit by paths and the two
//    strategies are combined with the power heuristic.
//  - Henyey-Greenstein phase sampling, smooth Fresnel dielectrics, diffuse
//    surfaces, interfaces; max_depth counts scattering events (media and
//    diffuse surfaces); Russian roulette after 3 events.
//  - Media whose extinction differs between RGB channels are tracked one
//    channel per path (three paths per sample), which keeps every estimator
//    unbiased; grey-extinction media share one path with RGB weights.
#include <algorithm>
#include <cmath>

#include "core/sampling.h"
#include "marchers/marcher.h"
#include "transport/direct_light.h"
#include "transport/media_point.h"
#include "transport/roulette.h"
#include "transport/surface_event.h"
#include "transport/tracking.h"

namespace vdbmarch {

namespace {

class ReferenceTracer final : public Marcher {
public:
    explicit ReferenceTracer(const Scene& s) : mScene(s) {
        for (const auto& m : s.media) {
            Color k = m->sigma_a + m->sigma_s;
            mChromatic = mChromatic || k.x != k.y || k.y != k.z;
        }
    }

    PathResult radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const override {
        ++ctx.counters.cameraRays;
        if (!mChromatic) return trace(cameraRay, rng, ctx, -1);
        PathResult out{Color(0), 0.f};
        for (int c = 0; c < 3; ++c) {
            PathResult p = trace(cameraRay, rng, ctx, c);
            out.L[c] = p.L[c];
            out.transmittance += p.transmittance / 3;
        }
        return out;
    }

private:
    PathResult trace(const Ray& cameraRay, Rng& rng, ThreadContext& ctx, int channel) const {
        const Scene& scene = mScene;
        const int maxDepth = scene.desc.render.maxDepth;
        Color L(0), beta(1);
        Ray ray = cameraRay;
        int region = regionAtRayStart(scene, ray);
        int depth = 0, surfaceBounces = 0;
        bool specular = true;       // last direction was not sampled from a density
        float lastPdf = 0;          // solid-angle pdf of the last sampled direction
        Vec3 lastPoint = ray.o;
        MediumPoint mp;
        while (true) {
            SurfaceHit h;
            bool hit = scene.surfaceSet->intersect(ray, 0.f, Infinity, h);
            float tLight = Infinity;
            int light = intersectSphereLights(scene, ray, 0.f, hit ? h.t : Infinity, tLight);
            float tEnd = light >= 0 ? tLight : (hit ? h.t : Infinity);

            // Delta tracking to the next real collision, or to tEnd; the
            // collision callback returns false once the path scattered or was absorbed.
            bool scattered = false;
            deltaTrack(ctx, region, ray, tEnd, channel, rng, [&](const Vec3& x, float sigmaMaj) {
                evalMedia(ctx, region, x, mp);
                ++ctx.counters.marchSamples;
                // Emission: sigma_a L_e / sigma_maj at every tentative collision.
                if (!isBlack(mp.emission)) L += beta * mp.sigma_a * mp.emission / sigmaMaj;
                float sa = trackedOrAverage(mp.sigma_a, channel), ss = trackedOrAverage(mp.sigma_s, channel);
                float u = rng.uniform() * sigmaMaj;
                if (u < sa) {
                    beta = Color(0);  // absorbed
                    return false;
                }
                if (u >= sa + ss) return true;  // null collision
                // Real scattering; weight sigma_s / (P_s sigma_maj) per channel.
                beta *= (channel < 0 ? mp.sigma_s / ss : Color(1));
                ++depth;
                if (depth > maxDepth) {
                    beta = Color(0);
                    return false;
                }
                L += beta * directLight(ctx, region, ScatterVertex{x, ray.d, &mp.phase}, rng, kNextEvent);
                float pdf;
                const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                Vec3 wi = mp.phase.sample(ray.d, u0, u1, u2, beta, pdf);
                lastPdf = pdf;
                specular = false;
                lastPoint = x;
                ray = Ray{x, wi};
                scattered = true;
                return false;
            });
            if (isBlack(beta)) return {channelOnly(L, channel), 0.f};
            if (scattered) {
                if (!roulette(beta, depth, rng)) return {channelOnly(L, channel), 0.f};
                continue;
            }
            // Reached tEnd without a real collision.
            if (light >= 0) {
                const Light& l = scene.lights[size_t(light)];
                float w = 1;
                if (!specular) {
                    // pdf with which next-event estimation at lastPoint would pick this direction
                    Vec3 to = l.desc().position - lastPoint;
                    float d2 = lengthSquared(to), r2 = l.desc().radius * l.desc().radius;
                    float sin2 = r2 / d2, cosMax = sin2 < 1e-6f ? 1 - 0.5f * sin2 : safeSqrt(1 - sin2);
                    w = powerHeuristic(lastPdf, uniformConePdf(cosMax));
                }
                L += beta * l.emittedRadiance() * w;
                return {channelOnly(L, channel), 0.f};
            }
            if (!hit) {
                L += beta * scene.background;
                return {channelOnly(L, channel), depth == 0 && surfaceBounces == 0 ? average(beta) : 0.f};
            }
            ++ctx.counters.surfaceHits;
            if (++surfaceBounces > scene.desc.render.maxSurfaceBounces) return {channelOnly(L, channel), 0.f};
            const float u[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
            const SurfaceEvent e = sampleSurfaceEvent(scene, h, ray.d, region, u, TransportMode::Radiance);
            if (e.kind == SurfaceEvent::Kind::Diffuse) {
                ++depth;
                if (depth > maxDepth) return {channelOnly(L, channel), 0.f};
                const Color& albedo = scene.surfaces[size_t(h.surface)].material.albedo;
                L += beta * directLight(ctx, region, ScatterVertex{h.p, ray.d, nullptr, h.n, albedo}, rng, kNextEvent);
                lastPdf = e.pdf;
                specular = false;
                lastPoint = h.p;
            } else if (!e.straight) {
                specular = true;  // next-event estimation cannot see through this
            }
            beta *= e.weight;
            ray = e.ray;
            region = e.region;
            if (e.kind == SurfaceEvent::Kind::Diffuse && !roulette(beta, depth, rng)) return {channelOnly(L, channel), 0.f};
        }
    }

    // Event probabilities: the tracked channel, or for grey extinction the
    // channel average (sigma_a + sigma_s sums to sigma_t either way), so a
    // chromatic albedo only changes the per-channel weights.
    static float trackedOrAverage(const Color& c, int channel) { return channel < 0 ? average(c) : c[channel]; }

    static Color channelOnly(const Color& L, int channel) {
        if (channel < 0) return L;
        Color out(0);
        out[channel] = L[channel];
        return out;
    }

    // Russian roulette on the throughput after RouletteMinDepth events.
    static bool roulette(Color& beta, int depth, Rng& rng) {
        return depth < RouletteMinDepth || russianRoulette(beta, rng, ScatterRouletteThreshold);
    }

    // Next-event estimation: ratio tracking; sphere lights are also hit by
    // the path, the background only by the path.
    static constexpr DirectLightOptions kNextEvent{TransmittanceEstimator::RatioTracking, true, false};

    const Scene& mScene;
    bool mChromatic = false;
};

}  // namespace

std::unique_ptr<Marcher> makeReferenceTracer(const Scene& scene, std::shared_ptr<const Illumination>) {
    return std::make_unique<ReferenceTracer>(scene);
}

}  // namespace vdbmarch
