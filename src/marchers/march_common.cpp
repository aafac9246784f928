#include "marchers/march_common.h"

#include <algorithm>
#include <cmath>

#include "core/sampling.h"

namespace vdbmarch {

ThreadContext::ThreadContext(const Scene& s) : scene(s) {
    for (const auto& m : s.media) queries.push_back(m->makeQuery());
}

void evalMedia(ThreadContext& ctx, int region, const Vec3& p, MediumPoint& mp) {
    mp.sigma_a = mp.sigma_s = mp.sigma_t = mp.emission = Color(0);
    mp.count = 0;
    for (int mi : ctx.scene.regions[size_t(region)].media) {
        float d = ctx.queries[size_t(mi)]->density(p);
        if (!(d > 0)) continue;
        const Medium& m = *ctx.scene.media[size_t(mi)];
        Color sa = min(m.sigma_a * d, Color(MaxCoefficient)), ss = min(m.sigma_s * d, Color(MaxCoefficient));
        mp.sigma_a += sa;
        mp.sigma_s += ss;
        if (m.hasEmission) {
            float e = ctx.queries[size_t(mi)]->emission(p);
            if (e > 0) mp.emission += sa * m.emissionColor * e;  // normalised below
        }
        if (!isBlack(ss) && mp.count < MaxMediaPerPoint) {
            mp.sigmaS[mp.count] = ss;
            mp.g[mp.count] = m.g;
            ++mp.count;
        }
    }
    mp.sigma_t = mp.sigma_a + mp.sigma_s;
    if (!isBlack(mp.emission))
        for (int c = 0; c < 3; ++c) mp.emission[c] = mp.sigma_a[c] > 0 ? mp.emission[c] / mp.sigma_a[c] : 0.f;
}

void regionIntervals(ThreadContext& ctx, int region, const Ray& r, float tMin, float tMax,
                     std::vector<Interval>& out) {
    out.clear();
    const auto& media = ctx.scene.regions[size_t(region)].media;
    if (media.empty() || !(tMax > tMin)) return;
    if (media.size() == 1) {
        ctx.queries[size_t(media[0])]->activeIntervals(r, tMin, tMax, out);
        return;
    }
    auto& all = ctx.scratch;
    all.clear();
    for (int mi : media) ctx.queries[size_t(mi)]->activeIntervals(r, tMin, tMax, all);
    std::sort(all.begin(), all.end(), [](const Interval& a, const Interval& b) { return a.t0 < b.t0; });
    for (const auto& iv : all) {
        if (!out.empty() && iv.t0 <= out.back().t1) out.back().t1 = std::max(out.back().t1, iv.t1);
        else out.push_back(iv);
    }
}

Color phaseMixture(const MediumPoint& mp, float cosTheta) {
    if (mp.count == 1) return Color(hgPhase(cosTheta, mp.g[0]));
    Color c(0);
    for (int i = 0; i < mp.count; ++i) c += (mp.sigmaS[i] / mp.sigma_s) * hgPhase(cosTheta, mp.g[i]);
    return c;
}

Vec3 offsetRayOrigin(const Scene& scene, const Vec3& p, const Vec3& n, const Vec3& d) {
    float eps = 1e-5f * std::max(scene.sceneScale, maxComponent(max(p, -p)));
    return p + (dot(n, d) > 0 ? n : -n) * eps;
}

int intersectSphereLights(const Scene& scene, const Ray& r, float tMin, float tMax, float& t) {
    if (!scene.hasSphereLights) return -1;
    int best = -1;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        float ti;
        if (scene.lights[i].intersect(r, tMin, tMax, ti)) {
            tMax = ti;
            t = ti;
            best = int(i);
        }
    }
    return best;
}

int regionAtRayStart(const Scene& scene, const Ray& r) {
    SurfaceHit h;
    if (!scene.surfaceSet->intersect(r, 0.f, Infinity, h)) return Scene::WorldRegion;
    const SurfaceInfo& s = scene.surfaces[size_t(h.surface)];
    return dot(r.d, h.n) > 0 ? s.interiorRegion : s.exteriorRegion;
}

namespace {

// Optical depth of the region's media over [0, tEnd) of ray r. Constant
// media integrate exactly; gridded media are marched with uniform steps at
// (k + u) * step, an unbiased estimate of the integral of sigma_t. Stops early
// once every channel's depth exceeds `depthCutoff`.
Color opticalDepth(ThreadContext& ctx, int region, const Ray& r, float tEnd, Rng& rng, float depthCutoff) {
    Color tau(0);
    const auto& media = ctx.scene.regions[size_t(region)].media;
    if (media.empty()) return tau;
    const float step = ctx.scene.shadowStep;
    const float u = rng.uniform();
    for (int mi : media) {
        MediumQuery& q = *ctx.queries[size_t(mi)];
        const Medium& m = *ctx.scene.media[size_t(mi)];
        const Color sigmaT = m.sigma_a + m.sigma_s;
        float integral;
        if (q.densityIntegral(r, 0.f, tEnd, integral)) {
            for (int c = 0; c < 3; ++c)  // unbounded fog: inf * 0 must not make NaN
                if (integral > 0 && sigmaT[c] > 0) tau[c] += sigmaT[c] * integral;
            if (minComponent(tau) > depthCutoff) return tau;
            continue;
        }
        ctx.shadowIntervals.clear();
        q.activeIntervals(r, 0.f, tEnd, ctx.shadowIntervals);
        float sum = 0;
        for (const Interval& iv : ctx.shadowIntervals) {
            // Lattice index in double: k + 1 must never round back to k.
            double k = std::ceil(double(iv.t0) / step - u);
            for (double t = (k + u) * step; t < iv.t1; k += 1, t = (k + u) * step) {
                sum += q.density(r.at(t));
                ++ctx.counters.shadowSamples;
                if (minComponent(tau + sigmaT * (sum * step)) > depthCutoff) return tau + sigmaT * (sum * step);
            }
        }
        tau += sigmaT * (sum * step);
    }
    return tau;
}

}  // namespace

Color shadowTransmittance(ThreadContext& ctx, int region, const Vec3& p, const Vec3& wi, float dist, Rng& rng) {
    ++ctx.counters.shadowRays;
    Color tau(0);
    // exp(-30) ~ 1e-13: beyond that depth the light is numerically gone.
    const float cutoff = 30.f;
    bool reached = walkShadowRay(ctx.scene, region, Ray{p, wi}, dist, [&](int reg, const Ray& r, float tEnd) {
        tau += opticalDepth(ctx, reg, r, tEnd, rng, cutoff - minComponent(tau));
        return !(minComponent(tau) > cutoff);
    });
    return reached ? exp(-tau) : Color(0);
}

Color directInScattering(ThreadContext& ctx, int region, const Vec3& p, const Vec3& rayDir, const MediumPoint& mp,
                         Rng& rng) {
    Color Ls(0);
    if (mp.count == 0) return Ls;
    const Scene& scene = ctx.scene;
    for (const Light& light : scene.lights) {
        LightSample ls;
        float u1 = rng.uniform(), u2 = rng.uniform();
        if (!light.sample(p, u1, u2, ls) || isBlack(ls.L)) continue;
        // cos between the light's travel direction (-wi) and the scattered
        // direction towards the camera (-rayDir).
        Color f = phaseMixture(mp, dot(ls.wi, rayDir));
        if (isBlack(f)) continue;
        Color T = shadowTransmittance(ctx, region, p, ls.wi, ls.dist, rng);
        Ls += f * ls.L * T;
    }
    if (!isBlack(scene.background)) {
        // Constant environment: pick one medium by its scattering weight and
        // sample its phase function; weight by the mixture pdf.
        float total = 0, w[MaxMediaPerPoint];
        for (int i = 0; i < mp.count; ++i) total += (w[i] = average(mp.sigmaS[i]));
        float u = rng.uniform() * total;
        int pick = 0;
        while (pick + 1 < mp.count && u >= w[pick]) u -= w[pick++];
        float cosT = sampleHgCosTheta(rng.uniform(), mp.g[pick]);
        // Travel direction of the arriving light is -wi; the sample is drawn
        // around the outgoing direction -rayDir, so wi lies around rayDir.
        Vec3 wi = directionAround(rayDir, cosT, rng.uniform());
        float cosTheta = dot(wi, rayDir);
        float pdf = 0;
        for (int i = 0; i < mp.count; ++i) pdf += w[i] / total * hgPhase(cosTheta, mp.g[i]);
        if (pdf > 0) {
            Color T = shadowTransmittance(ctx, region, p, wi, Infinity, rng);
            Ls += phaseMixture(mp, cosTheta) * scene.background * T / pdf;
        }
    }
    return Ls;
}

Color directDiffuse(ThreadContext& ctx, int region, const Vec3& p, const Vec3& n, const Vec3& rayDir,
                    const Color& albedo, Rng& rng) {
    const Scene& scene = ctx.scene;
    Vec3 nf = dot(n, rayDir) < 0 ? n : -n;  // shade the side the ray came from
    Vec3 o = p + nf * (1e-5f * std::max(scene.sceneScale, maxComponent(max(p, -p))));
    Color Lo(0);
    for (const Light& light : scene.lights) {
        LightSample ls;
        float u1 = rng.uniform(), u2 = rng.uniform();
        if (!light.sample(o, u1, u2, ls) || isBlack(ls.L)) continue;
        float cosI = dot(ls.wi, nf);
        if (cosI <= 0) continue;
        Lo += albedo * InvPi * ls.L * cosI * shadowTransmittance(ctx, region, o, ls.wi, ls.dist, rng);
    }
    if (!isBlack(scene.background)) {
        // Cosine-weighted hemisphere: the pdf cancels the cosine and 1/pi.
        float u1 = rng.uniform(), u2 = rng.uniform();
        float cosT = std::sqrt(1 - u1);
        Vec3 wi = directionAround(nf, cosT, u2);
        Lo += albedo * scene.background * shadowTransmittance(ctx, region, o, wi, Infinity, rng);
    }
    return Lo;
}


void mediumMajorants(ThreadContext& ctx, int mi, const Ray& r, float tEnd, std::vector<MajorantSegment>& out) {
    const Medium& m = *ctx.scene.media[size_t(mi)];
    if (!ctx.scene.desc.render.globalMajorant || m.minVoxelSize() == 0) {
        ctx.queries[size_t(mi)]->majorantSegments(r, 0.f, tEnd, out);
        return;
    }
    float t0 = 0, t1 = tEnd;
    if (m.maxDensity() > 0 && m.worldBounds().intersect(r, t0, t1) && t1 > t0) out.push_back({t0, t1, m.maxDensity()});
}

void regionMajorants(ThreadContext& ctx, int region, const Ray& r, float tEnd, int channel,
                     std::vector<MajorantSegment>& out) {
    out.clear();
    const auto& media = ctx.scene.regions[size_t(region)].media;
    auto coefficient = [&](int mi) {
        const Medium& m = *ctx.scene.media[size_t(mi)];
        return trackedSigmaT(m.sigma_a + m.sigma_s, channel);
    };
    if (media.size() == 1) {
        float k = coefficient(media[0]);
        mediumMajorants(ctx, media[0], r, tEnd, out);
        for (auto& s : out) s.maxDensity *= k;
        return;
    }
    // Several media: sum their piecewise-constant majorants.
    std::vector<MajorantSegment> all;
    std::vector<float> cuts;
    std::vector<std::pair<size_t, size_t>> ranges;
    for (int mi : media) {
        size_t first = all.size();
        mediumMajorants(ctx, mi, r, tEnd, all);
        float k = coefficient(mi);
        for (size_t i = first; i < all.size(); ++i) {
            all[i].maxDensity *= k;
            cuts.push_back(all[i].t0);
            cuts.push_back(all[i].t1);
        }
        ranges.push_back({first, all.size()});
    }
    std::sort(cuts.begin(), cuts.end());
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
        float a = cuts[i], b = cuts[i + 1], mid = 0.5f * (a + b), sum = 0;
        if (!std::isfinite(mid)) mid = a + 1;
        for (const auto& rg : ranges)
            for (size_t j = rg.first; j < rg.second; ++j)
                if (all[j].t0 <= mid && mid < all[j].t1) sum += all[j].maxDensity;
        if (sum > 0) out.push_back({a, b, sum});
    }
}

Vec3 sampleDielectric(const Vec3& d, const Vec3& outward, float ior, float u, bool& refracted) {
    bool entering = dot(d, outward) < 0;
    float eta = entering ? ior : 1 / ior;
    Vec3 n = entering ? outward : -outward;
    float cosI = -dot(d, n), cosT;
    float F = fresnelDielectric(cosI, eta, &cosT);
    refracted = !(u < F);
    return normalize(refracted ? d / eta + n * (cosI / eta - cosT) : d + n * (2 * cosI));
}

Vec3 samplePhaseMixture(const MediumPoint& mp, const Vec3& d, Rng& rng, Color& weight, float& pdf) {
    float total = 0;
    for (int i = 0; i < mp.count; ++i) total += average(mp.sigmaS[i]);
    float pick = rng.uniform() * total;
    int k = 0;
    while (k + 1 < mp.count && pick >= average(mp.sigmaS[k])) pick -= average(mp.sigmaS[k++]);
    float cosT = sampleHgCosTheta(rng.uniform(), mp.g[k]);
    Vec3 wi = directionAround(d, cosT, rng.uniform());
    float c = dot(wi, d);
    if (mp.count == 1) {
        pdf = hgPhase(c, mp.g[0]);
        return wi;
    }
    pdf = 0;
    for (int i = 0; i < mp.count; ++i) pdf += average(mp.sigmaS[i]) / total * hgPhase(c, mp.g[i]);
    weight *= phaseMixture(mp, c) / pdf;
    return wi;
}

}  // namespace vdbmarch
