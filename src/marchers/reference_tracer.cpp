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
#include "scene/scene.h"

namespace vdbmarch {

namespace {

float powerHeuristic(float a, float b) {
    float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.f;
}

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
    // Ratio-tracking transmittance along a shadow ray through the region's
    // media over [0, dist); constant media exactly. Crosses interfaces,
    // stops at any other surface or a sphere light.
    Color transmittance(ThreadContext& ctx, int region, Ray r, float dist, Rng& rng) const {
        ++ctx.counters.shadowRays;
        Color T(1);
        bool reached = walkShadowRay(mScene, region, r, dist, [&](int reg, const Ray& seg, float tEnd) {
            T *= segmentTransmittance(ctx, reg, seg, tEnd, rng);
            return !isBlack(T);
        });
        return reached ? T : Color(0);
    }

    Color segmentTransmittance(ThreadContext& ctx, int region, const Ray& r, float tEnd, Rng& rng) const {
        Color T(1);
        const auto& media = mScene.regions[size_t(region)].media;
        if (media.empty()) return T;
        // Constant media: exact. Gridded media: ratio tracking with their
        // local majorants (max over channels, so weights stay in [0, 1]).
        for (int mi : media) {
            const Medium& m = *mScene.media[size_t(mi)];
            const Color k = m.sigma_a + m.sigma_s;
            MediumQuery& q = *ctx.queries[size_t(mi)];
            float integral;
            if (q.densityIntegral(r, 0.f, tEnd, integral)) {
                for (int c = 0; c < 3; ++c)
                    if (integral > 0 && k[c] > 0) T[c] *= std::exp(-k[c] * integral);
                continue;
            }
            float kMax = maxComponent(k);
            if (!(kMax > 0)) continue;
            ctx.scratchSegments.clear();
            mediumMajorants(ctx, mi, r, tEnd, ctx.scratchSegments);
            for (const auto& seg : ctx.scratchSegments) {
                float sigmaMaj = seg.maxDensity * kMax;
                if (!(sigmaMaj > 0)) continue;
                double t = seg.t0;
                while (true) {
                    t -= std::log(1 - double(rng.uniform())) / sigmaMaj;
                    if (t >= seg.t1) break;
                    ++ctx.counters.shadowSamples;
                    float d = q.density(r.at(t));
                    for (int c = 0; c < 3; ++c) T[c] *= std::max(0.f, 1 - k[c] * d / sigmaMaj);
                    if (maxComponent(T) < 1e-3f) {  // Russian roulette keeps it unbiased
                        float qq = maxComponent(T) / 1e-3f;
                        if (rng.uniform() >= qq) return Color(0);
                        T /= qq;
                    }
                }
            }
        }
        return T;
    }

    // Direct light at a medium scattering point (phase) or a diffuse surface
    // point (albedo cos / pi), with MIS for sphere lights.
    Color nextEvent(ThreadContext& ctx, int region, const Vec3& p, const Vec3& d, const MediumPoint* mp,
                    const Vec3* n, const Color& albedo, Rng& rng) const {
        Color Ld(0);
        for (size_t li = 0; li < mScene.lights.size(); ++li) {
            const Light& light = mScene.lights[li];
            LightSample ls;
            float u1 = rng.uniform(), u2 = rng.uniform();
            Vec3 origin = p;
            if (n) {  // leave the surface on the side the path arrived from
                Vec3 nf = dot(*n, d) < 0 ? *n : -*n;
                origin = p + nf * (1e-5f * std::max(mScene.sceneScale, maxComponent(max(p, -p))));
            }
            if (!light.sample(origin, u1, u2, ls) || isBlack(ls.L)) continue;
            Color f;
            float scatterPdf;
            if (mp) {
                float ph = hgMix(*mp, dot(ls.wi, d));
                f = phaseMixture(*mp, dot(ls.wi, d));
                scatterPdf = ph;
            } else {
                Vec3 nf = dot(*n, d) < 0 ? *n : -*n;
                float c = dot(ls.wi, nf);
                if (c <= 0) continue;
                f = albedo * (c * InvPi);
                scatterPdf = c * InvPi;
            }
            if (isBlack(f)) continue;
            float w = 1;
            if (light.isSphere()) w = powerHeuristic(ls.pdf, scatterPdf);
            Color T = transmittance(ctx, region, Ray{origin, ls.wi}, ls.dist, rng);
            Ld += f * ls.L * T * w;
        }
        return Ld;
    }

    // pdf of the phase mixture used for sampling (mixture weights by sigma_s).
    static float hgMix(const MediumPoint& mp, float cosTheta) {
        if (mp.count == 1) return hgPhase(cosTheta, mp.g[0]);
        float total = 0, pdf = 0;
        for (int i = 0; i < mp.count; ++i) total += average(mp.sigmaS[i]);
        for (int i = 0; i < mp.count; ++i) pdf += average(mp.sigmaS[i]) / total * hgPhase(cosTheta, mp.g[i]);
        return pdf;
    }

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
                L += beta * nextEvent(ctx, region, x, ray.d, &mp, nullptr, Color(0), rng);
                float pdf;
                Vec3 wi = samplePhaseMixture(mp, ray.d, rng, beta, pdf);
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
            const SurfaceInfo& s = scene.surfaces[size_t(h.surface)];
            bool entering = dot(ray.d, h.n) < 0;
            if (s.material.type == MaterialDesc::Type::Interface) {
                region = entering ? s.interiorRegion : s.exteriorRegion;
                ray.o = offsetRayOrigin(scene, h.p, h.n, ray.d);
                continue;
            }
            if (s.material.type == MaterialDesc::Type::Diffuse) {
                ++depth;
                if (depth > maxDepth) return {channelOnly(L, channel), 0.f};
                Vec3 nf = entering ? h.n : -h.n;
                L += beta * nextEvent(ctx, region, h.p, ray.d, nullptr, &h.n, s.material.albedo, rng);
                float u1 = rng.uniform(), u2 = rng.uniform();
                float cosT = std::sqrt(1 - u1);
                Vec3 wi = directionAround(nf, cosT, u2);
                beta *= s.material.albedo;  // f cos / pdf = albedo
                lastPdf = cosT * InvPi;
                specular = false;
                lastPoint = h.p;
                ray = Ray{offsetRayOrigin(scene, h.p, h.n, wi), wi};
                if (!roulette(beta, depth, rng)) return {channelOnly(L, channel), 0.f};
                continue;
            }
            // Dielectric: Fresnel choice; the weights cancel.
            bool refracted;
            Vec3 d = sampleDielectric(ray.d, h.n, s.material.ior, rng.uniform(), refracted);
            if (refracted) region = entering ? s.interiorRegion : s.exteriorRegion;
            specular = true;
            ray = Ray{offsetRayOrigin(scene, h.p, h.n, d), d};
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

    // Unbiased Russian roulette after three scattering events.
    static bool roulette(Color& beta, int depth, Rng& rng) {
        if (depth < 3) return true;
        float q = std::min(0.95f, maxComponent(beta));
        if (!(q > 0) || rng.uniform() >= q) return false;
        beta /= q;
        return true;
    }

    const Scene& mScene;
    bool mChromatic = false;
};

}  // namespace

std::unique_ptr<Marcher> makeReferenceTracer(const Scene& scene, std::shared_ptr<const Illumination>) {
    return std::make_unique<ReferenceTracer>(scene);
}

}  // namespace vdbmarch
