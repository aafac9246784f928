#include "transport/direct_light.h"

#include <cmath>

#include "core/sampling.h"
#include "transport/roulette.h"

namespace vdbmarch {

Color ScatterVertex::f(const Vec3& wi) const {
    // cos between the light's travel direction (-wi) and the scattered
    // direction (-d).
    if (phase) return phase->eval(dot(wi, d));
    const float c = dot(wi, arrivalNormal());
    return c > 0 ? albedo * (c * InvPi) : Color(0);
}

float ScatterVertex::pdf(const Vec3& wi) const {
    if (pathPdf) return pathPdf(pathSampler, wi);
    return fPdf(wi);
}

float ScatterVertex::fPdf(const Vec3& wi) const {
    if (phase) return phase->pdf(dot(wi, d));
    return std::max(0.f, dot(wi, arrivalNormal())) * InvPi;
}

Vec3 ScatterVertex::shadowOrigin(const Scene& scene) const {
    if (phase) return p;
    return p + arrivalNormal() * (1e-5f * std::max(scene.sceneScale, maxComponent(max(p, -p))));
}

namespace {

// The level of shadow-ray roulette by the phase value at vertex v, in units
// of the isotropic 1 / (4 pi) (DirectLightOptions::phaseRoulette); 0 where
// nothing is rouletted.
float phaseRouletteLevel(const Scene& scene, int region, const ScatterVertex& v, const DirectLightOptions& o) {
    if (!o.phaseRoulette || !v.phase || !scene.regions[size_t(region)].gridded) return 0.f;
    const float level = PhaseRouletteShare * v.phase->meanPhaseValue();
    return level > 1 ? level : 0.f;
}

// What a light sample of phase value f counts: 1 at or above the level,
// else 1 / q with probability q = f / level and 0 (no shadow ray) otherwise.
float phaseRouletteWeight(float level, const Color& f, Rng& rng) {
    if (!(level > 0)) return 1.f;
    const float q = average(f) * (4 * Pi) / level;
    if (!(q < 1)) return 1.f;
    return q > 0 && rng.uniform() < q ? 1 / q : 0.f;
}

}  // namespace

Color directLight(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng, const DirectLightOptions& o) {
    const Scene& scene = ctx.scene;
    const float rouletteLevel = phaseRouletteLevel(scene, region, v, o);
    Color L(0);
    const Vec3 origin = v.shadowOrigin(scene);
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& light = scene.lights[i];
        if (o.onlyLight >= 0 && int(i) != o.onlyLight) continue;
        if (o.skipPointLights && light.isPointLike()) continue;
        if (!scene.shadowRaysCanReach(region, i)) continue;  // sealed off: every shadow ray would be blocked
        float lightWeight = o.lightWeights ? o.lightWeights[i] : 1.f;
        if (!(lightWeight > 0) || !russianRoulette(lightWeight, rng, MisWeightRouletteThreshold)) continue;
        LightSample ls;
        const float u1 = rng.uniform(), u2 = rng.uniform();
        if (!light.sample(origin, u1, u2, ls) || isBlack(ls.L)) continue;
        const Color f = v.f(ls.wi);
        if (isBlack(f)) continue;
        const float survivor = phaseRouletteWeight(rouletteLevel, f, rng);
        if (!(survivor > 0)) continue;
        const float w = o.misWithPathHits && !light.isDelta() ? powerHeuristic(ls.pdf, v.pdf(ls.wi)) : 1.f;
        L += f * ls.L * shadowTransmittance(ctx, region, origin, ls.wi, ls.dist, rng, o.transmittance) *
             (w * lightWeight * survivor);
    }
    if (o.onlyLight >= 0) return L;
    const Environment& env = scene.environment;
    if (!scene.shadowRaysCanReach(region, scene.lights.size())) return L;
    // An environment map is a light: sampled by its texel power, weighed by
    // the power heuristic against the direction sampling of f, done by the
    // path that goes on (misWithPathHits) or below (sampleBackground). A
    // constant background is left to f's sampling alone (it is as good).
    const bool envByLight = env.hasMap() && !env.isBlack() && (o.misWithPathHits || o.sampleBackground);
    if (envByLight) {
        Vec3 wi;
        float pdf;
        Color radianceOverPdf;
        const float u1 = rng.uniform(), u2 = rng.uniform();
        if (env.sample(u1, u2, wi, pdf, radianceOverPdf)) {
            const Color f = v.f(wi);
            const float survivor = isBlack(f) ? 0.f : phaseRouletteWeight(rouletteLevel, f, rng);
            if (survivor > 0) {
                const float w = powerHeuristic(pdf, o.misWithPathHits ? v.pdf(wi) : v.fPdf(wi)) * survivor;
                L += f * radianceOverPdf * (w * shadowTransmittance(ctx, region, origin, wi, Infinity, rng, o.transmittance));
            }
        }
    }
    if (o.sampleBackground && !env.isBlack()) {
        // One direction sampled by f: the pdf cancels f up to the mixture's weight.
        const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        Color weight(1);
        Vec3 wi;
        float pdf;
        if (v.phase) {
            // The scattered light leaves along -d, so the arriving light's
            // direction -wi is drawn around -d: wi around d.
            wi = v.phase->sample(v.d, u0, u1, u2, weight, pdf);
            if (!(pdf > 0)) return L;
        } else {
            const float cosTheta = std::sqrt(1 - u1);
            wi = directionAround(v.arrivalNormal(), cosTheta, u2);
            weight = v.albedo;
            pdf = cosTheta * InvPi;
        }
        const float w = envByLight ? powerHeuristic(pdf, env.pdf(wi)) : 1.f;
        L += weight * env.radiance(wi) * (w * shadowTransmittance(ctx, region, origin, wi, Infinity, rng, o.transmittance));
    }
    return L;
}

}  // namespace vdbmarch
