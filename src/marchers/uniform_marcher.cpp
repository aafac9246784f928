// Baseline (i) of the paper: ray marching with a uniform step and one random
// offset per ray segment (eq. 5), lit by direct light through shadow rays.
//
// Per step of length dx at x_k the source term is integrated exactly under the
// constant-medium assumption of eq. 5: the step contributes
//   T_k * S(x_k, dx) * (sigma_a L_e + sigma_s L_i),  S = (1 - e^{-kappa dx}) / kappa  (eq. 7)
// and T_{k+1} = T_k e^{-kappa dx}. S replaces eq. 5's dx so optically thick
// steps cannot over-count (S -> dx as kappa dx -> 0). S sigma_x is evaluated as
// (1 - e^{-kappa dx}) (sigma_x / kappa) so that no product can overflow.
#include <cmath>

#include "core/error.h"
#include "core/sampling.h"
#include "marchers/marcher.h"
#include "scene/scene.h"

namespace vdbmarch {

namespace {

// Below this throughput, Russian roulette decides whether a ray goes on.
constexpr float RouletteThreshold = 1e-3f;

class UniformMarcher final : public Marcher {
public:
    explicit UniformMarcher(const Scene& s) : mScene(s) {}

    PathResult radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const override {
        const Scene& scene = mScene;
        ++ctx.counters.cameraRays;
        Color L(0), beta(1);
        Ray ray = cameraRay;
        int region = regionAtRayStart(scene, ray);
        for (int bounce = 0;; ++bounce) {
            SurfaceHit h;
            bool hit = scene.surfaceSet->intersect(ray, 0.f, Infinity, h);
            float tLight = Infinity;
            int light = intersectSphereLights(scene, ray, 0.f, hit ? h.t : Infinity, tLight);
            float segEnd = light >= 0 ? tLight : (hit ? h.t : Infinity);
            if (!marchSegment(ctx, region, ray, segEnd, rng, L, beta)) return {L, 0.f};
            if (light >= 0) {
                L += beta * scene.lights[size_t(light)].emittedRadiance();
                return {L, 0.f};
            }
            if (!hit) {
                L += beta * scene.background;
                return {L, average(beta)};
            }
            ++ctx.counters.surfaceHits;
            if (bounce >= scene.desc.render.maxSurfaceBounces) return {L, 0.f};
            const SurfaceInfo& s = scene.surfaces[size_t(h.surface)];
            bool entering = dot(ray.d, h.n) < 0;
            switch (s.material.type) {
                case MaterialDesc::Type::Diffuse:
                    L += beta * directDiffuse(ctx, region, h.p, h.n, ray.d, s.material.albedo, rng);
                    return {L, 0.f};
                case MaterialDesc::Type::Interface:
                    region = entering ? s.interiorRegion : s.exteriorRegion;
                    ray.o = offsetRayOrigin(scene, h.p, h.n, ray.d);
                    break;
                case MaterialDesc::Type::Dielectric: {
                    // Smooth Fresnel: reflect with probability F, else refract;
                    // the weights F/F and (1-F)/(1-F) cancel. The shading
                    // normal bends the directions; the geometric normal decides
                    // the side, and wins when the two disagree.
                    float eta = entering ? s.material.ior : 1 / s.material.ior;
                    Vec3 ng = entering ? h.n : -h.n;  // faces the incoming ray
                    Vec3 n = dot(h.ns, ng) > 0 ? h.ns : -h.ns;
                    if (-dot(ray.d, n) <= 0) n = ng;  // shading normal faces away from the ray
                    float cosI = -dot(ray.d, n), cosT;
                    float F = fresnelDielectric(cosI, eta, &cosT);
                    bool reflect = rng.uniform() < F;
                    Vec3 d = reflect ? ray.d + n * (2 * cosI) : ray.d / eta + n * (cosI / eta - cosT);
                    if (reflect ? dot(d, ng) <= 0 : dot(d, ng) >= 0) {
                        // The shading normal sent the ray to the wrong side of
                        // the true surface: redo the event with the geometric one.
                        cosI = -dot(ray.d, ng);
                        F = fresnelDielectric(cosI, eta, &cosT);
                        reflect = reflect || F >= 1;
                        d = reflect ? ray.d + ng * (2 * cosI) : ray.d / eta + ng * (cosI / eta - cosT);
                    }
                    if (!reflect) region = entering ? s.interiorRegion : s.exteriorRegion;
                    d = normalize(d);
                    ray = Ray{offsetRayOrigin(scene, h.p, h.n, d), d};
                    break;
                }
            }
        }
    }

private:
    // Marches [0, tEnd) of the ray in `region`, adding to L and attenuating
    // beta. Returns false when Russian roulette ended the path.
    bool marchSegment(ThreadContext& ctx, int region, const Ray& ray, float tEnd, Rng& rng, Color& L,
                      Color& beta) const {
        const Scene& scene = mScene;
        if (scene.regions[size_t(region)].media.empty()) return true;
        // An unbounded fog makes the last interval infinite. Past the scene's
        // finite content the fog is homogeneous: march until its transmittance
        // is below e^-20 (at most 1e5 steps), then T(infinity) = 0 in every
        // channel where it extinguishes.
        const Color& K = scene.regions[size_t(region)].unboundedSigmaT;
        const bool infiniteTail = !std::isfinite(tEnd) && !isBlack(K);
        float tLimit = tEnd;
        if (infiniteTail) {
            float kMin = Infinity;
            for (int c = 0; c < 3; ++c)
                if (K[c] > 0) kMin = std::min(kMin, K[c]);
            tLimit = length(ray.o) + 2 * scene.sceneScale + std::min(20.f / kMin, 1e5f * scene.step);
        }
        regionIntervals(ctx, region, ray, 0.f, tLimit, ctx.intervals);
        double active = 0;
        const float dx = scene.step;
        const float u = rng.uniform();  // one random offset per segment (eq. 5 with jitter)
        MediumPoint mp;
        for (const Interval& iv : ctx.intervals) {
            active += double(std::min(iv.t1, 1e30f) - iv.t0);
            // Lattice index in double: k + 1 must never round back to k.
            double k = std::ceil(double(iv.t0) / dx - u);
            for (double t = (k + u) * dx; t < iv.t1; k += 1, t = (k + u) * dx) {
                Vec3 x = ray.at(t);
                evalMedia(ctx, region, x, mp);
                ++ctx.counters.marchSamples;
                if (isBlack(mp.sigma_t)) continue;
                Color Li = mp.count > 0 ? directInScattering(ctx, region, x, ray.d, mp, rng) : Color(0);
                // S sigma_x = (1 - e^{-kappa dx}) sigma_x / kappa: the absorbed
                // fraction of the step split by albedo, bounded for any kappa.
                Color Tstep, absorbedA, absorbedS;
                for (int c = 0; c < 3; ++c) {
                    float kappa = mp.sigma_t[c];
                    float tauStep = kappa * dx;
                    Tstep[c] = std::exp(-tauStep);
                    float oneMinusT = tauStep > 1e-4f ? -std::expm1(-tauStep) : tauStep * (1 - 0.5f * tauStep);
                    absorbedA[c] = kappa > 0 ? oneMinusT * (mp.sigma_a[c] / kappa) : 0.f;
                    absorbedS[c] = kappa > 0 ? oneMinusT * (mp.sigma_s[c] / kappa) : 0.f;
                }
                L += beta * (absorbedA * mp.emission + absorbedS * Li);
                beta *= Tstep;
                float m = maxComponent(beta);
                if (m < RouletteThreshold) {
                    float q = m / RouletteThreshold;
                    if (rng.uniform() >= q) {
                        beta = Color(0);
                        addLengths(ctx, tEnd, active);
                        return false;
                    }
                    beta /= q;
                }
            }
        }
        addLengths(ctx, tEnd, active);
        if (infiniteTail)
            for (int c = 0; c < 3; ++c)
                if (K[c] > 0) beta[c] = 0;
        return true;
    }

    // Skipped = the part of [0, end) outside active intervals, where `end` is
    // the segment end or, for rays to infinity, the end of the last interval.
    static void addLengths(ThreadContext& ctx, float tEnd, double active) {
        ctx.counters.marchedLength += active;
        double end = std::isfinite(tEnd) ? double(tEnd)
                                         : (ctx.intervals.empty() ? 0.0 : double(std::min(ctx.intervals.back().t1, 1e30f)));
        ctx.counters.skippedLength += std::max(0.0, end - active);
    }

    const Scene& mScene;
};

}  // namespace

std::unique_ptr<Marcher> makeUniformMarcher(const Scene& scene) { return std::make_unique<UniformMarcher>(scene); }

}  // namespace vdbmarch
