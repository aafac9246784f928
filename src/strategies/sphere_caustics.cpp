#include "strategies/sphere_caustics.h"

#include <cmath>

#include "core/sampling.h"
#include "transport/surface_event.h"

namespace vdbmarch {

bool sceneHasSphereCaustics(const Scene& scene) {
    return (scene.hasSphereLights || scene.deltaLightCaustics) && scene.desc.experiments.sphereCaustics &&
           !scene.glassSpheres.empty();
}

namespace {

// The pattern a connection from x takes through sphere s to a light: two
// refractions (in and out) from outside to a light outside, one from
// outside to a light inside or from inside to a light outside; 0 for none
// (x and the light on the same side, or a sphere light across the
// surface). The connections and the paths' weights ask it alike.
int connectionPattern(const GlassSphere& s, const Light& l, const Vec3& x) {
    const bool xInside = lengthSquared(x - s.center) < s.radius * s.radius;
    bool inside, outside;
    if (l.isDelta() && !l.isPointLike()) {
        inside = false;  // directional, or a collimated quad outside the balls (Scene::deltaLightCaustics)
        outside = true;
    } else if (l.isPointLike()) {
        const float d = length(l.desc().position - s.center);
        inside = d < s.radius;
        outside = d > s.radius;
    } else {
        inside = lightInside(s, l);
        outside = lightOutside(s, l);
    }
    if (xInside) return outside ? 1 : 0;
    return outside ? 2 : inside ? 1 : 0;
}

// Every connection of the pattern from x to y.
int connect(const GlassSphere& s, int pattern, const Vec3& x, const Vec3& y, SphereConnection out[MaxSphereConnections],
            bool thorough = false) {
    return pattern == 2 ? connectThroughSphere(s, x, y, out, thorough) : connectAcrossSphere(s, x, y, out, thorough);
}

// The pdf of directions uniform in the cone that sphere s subtends from x
// (and the cone's cosine). 0 where x is inside, or where the ball is too
// small to sample its cone in float (1 - cos below 1e-6, a ball thousands
// of radii away): then no side counts cone directions, so the weights
// still sum to 1.
double ballConePdf(const GlassSphere& s, const Vec3& x, float* cosMax = nullptr) {
    const double d2 = double(lengthSquared(s.center - x)), r2 = double(s.radius) * double(s.radius);
    if (!(d2 > r2)) return 0;
    const double sin2 = r2 / d2, oneMinusCos = sin2 / (1 + std::sqrt(1 - sin2));
    if (!(oneMinusCos >= 1e-6)) return 0;
    if (cosMax) *cosMax = float(1 - oneMinusCos);
    return 1 / (2 * double(Pi) * oneMinusCos);
}

// The connections' density over directions at x of the path of the pattern
// along w that reaches y on light l: 0 when the solver from (x, y) finds no
// root matching w.
double connectionPdf(const GlassSphere& s, int pattern, const LightSphere& l, const Vec3& x, const Vec3& w,
                     const Vec3& y) {
    SphereConnection roots[MaxSphereConnections];
    const int n = connect(s, pattern, x, y, roots);
    int best = -1;
    double bestCos = RootMatchCos;
    for (int k = 0; k < n; ++k) {
        const double c = double(dot(roots[k].wi, w));
        if (c > bestCos) {
            bestCos = c;
            best = k;
        }
    }
    if (best < 0) return 0;
    const SphereConnection& cn = roots[best];
    const double cosY = -double(dot(cn.wo, normalize(y - l.center)));
    if (!(cosY > 0) || !(cn.spreading > 0)) return 0;
    const double rl = l.radius;
    return cn.spreading / (4 * double(Pi) * rl * rl * cosY);
}

// Power heuristic of density a among a, b and c.
double power3(double a, double b, double c) {
    const double a2 = a * a, sum = a2 + b * b + c * c;
    return sum > 0 ? a2 / sum : 0.0;
}

}  // namespace

Color sphereCausticLight(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng,
                         TransmittanceEstimator estimator, const ConnectionRequest& lights) {
    const Scene& scene = ctx.scene;
    Color L(0);
    const Vec3 origin = v.shadowOrigin(scene);
    SphereConnection roots[MaxSphereConnections];
    for (const GlassSphere& s : scene.glassSpheres) {
        const bool xInside = lengthSquared(v.p - s.center) < s.radius * s.radius;
        float cosMax = 1;
        const double pc = xInside ? 0.0 : ballConePdf(s, v.p, &cosMax);
        // What reaches x from the light along the connection cn:
        // transmittance x -> p1, through the ball's region p1 -> p2 (two
        // refractions), then p2 to y (the light's own surface ends the
        // shadow ray), or `farDist` beyond p2 for a light without a point
        // (Infinity: directional).
        auto throughBall = [&](const SphereConnection& cn, const Vec3* y, float farDist) {
            const float d1 = length(cn.p1 - origin);
            Color T = shadowTransmittance(ctx, region, origin, cn.wi, d1, rng, estimator);
            if (isBlack(T)) return T;
            if (cn.refractions == 2 && !s.emptyInside) {
                const Vec3 d = normalize(cn.p2 - cn.p1);
                const Vec3 o1 = offsetRayOrigin(scene, cn.p1, normalize(cn.p1 - s.center), d);
                T *= shadowTransmittance(ctx, s.inside, o1, d, length(cn.p2 - o1), rng, estimator);
                if (isBlack(T)) return T;
            }
            const int beyond = cn.refractions == 1 && !xInside ? s.inside : s.outside;
            const Vec3 o2 = offsetRayOrigin(scene, cn.p2, normalize(cn.p2 - s.center), cn.wo);
            return T * shadowTransmittance(ctx, beyond, o2, cn.wo, y ? length(*y - o2) : farDist, rng, estimator);
        };
        for (const Light& light : scene.lights) {
            const int pattern = connectionPattern(s, light, v.p);
            if (pattern == 0) continue;
            if (light.isDelta()) {
                const bool parallel = !light.isPointLike();
                if (!scene.deltaLightCaustics || !(parallel ? lights.parallelLights : lights.pointLights)) continue;
                if (!(lights.deltaWeight > 0)) continue;
                // Every root to a point or spot light's one point y, or
                // whose exit direction is a directional or collimated
                // light's: f I T (1 - F...) / G, or f E T (1 - F...) / J.
                const Vec3 y = light.desc().position;
                const Vec3 wL = normalize(-light.desc().direction);
                const int n = !parallel    ? connect(s, pattern, v.p, y, roots, true)
                              : pattern == 2 ? connectThroughSphereToward(s, v.p, wL, roots)
                                             : connectAcrossSphereToward(s, v.p, wL, roots);
                for (int k = 0; k < n; ++k) {
                    const SphereConnection& cn = roots[k];
                    if (!(cn.spreading > 0)) continue;
                    // Towards p2, the glass's last point: a spot's cone and
                    // falloff, a collimated quad's beam.
                    LightSample ls;
                    if (!light.sample(cn.p2, 0.f, 0.f, ls)) continue;
                    const Color f = v.f(cn.wi);
                    if (isBlack(f) || isBlack(ls.L)) continue;
                    const Color T = throughBall(cn, parallel ? nullptr : &y, ls.dist);
                    if (isBlack(T)) continue;
                    // The sample's irradiance: I / d^2 from a point, E along a direction.
                    const double intensityScale = parallel ? 1.0 : double(ls.dist) * double(ls.dist);
                    L += f * ls.L * T *
                         float(double(lights.deltaWeight) * intensityScale * double(cn.transmission) / cn.spreading);
                }
                continue;
            }
            const LightSphere* sphere = light.sphere();
            if (!lights.areaLights || !sphere) continue;
            const Vec3 lc = sphere->center;
            const float rl = sphere->radius;
            // 1. Connections: y uniform on the light's surface.
            const Vec3 ny = sampleUniformSphere(rng.uniform(), rng.uniform());
            const Vec3 y = lc + ny * rl;
            const double pA = 1 / (4 * double(Pi) * double(rl) * double(rl));
            const int n = connect(s, pattern, v.p, y, roots);
            // The cone of directions to the ball is a technique for the
            // lens pattern only (where the lens focuses the light).
            const double pcHere = pattern == 2 ? pc : 0.0;
            for (int k = 0; k < n; ++k) {
                const SphereConnection& cn = roots[k];
                const double cosY = -double(dot(cn.wo, ny));
                if (!(cosY > 0) || !(cn.spreading > 0)) continue;  // the light's far side
                const Color f = v.f(cn.wi);
                if (isBlack(f)) continue;
                const Color T = throughBall(cn, &y, 0.f);
                if (isBlack(T)) continue;
                const double pm = pA * cn.spreading / cosY;  // solid-angle density at x
                const double pu = lights.pathFollows ? double(v.pdf(cn.wi)) * double(cn.transmission) : 0.0;
                L += f * light.emittedRadiance() * T * float(double(cn.transmission) * power3(pm, pu, pcHere) / pm);
            }
            // 2. A direction uniform in the ball's cone, traced through it:
            // where the lens focuses the light (G near 0), the light fills
            // much of the ball and this finds it where connections cannot.
            if (!(pcHere > 0)) continue;
            SphereConnection cn;
            const Vec3 axis = normalize(s.center - v.p);
            const Vec3 w = sampleUniformCone(axis, cosMax, rng.uniform(), rng.uniform());
            if (!traceThroughSphere(s, v.p, w, cn)) continue;
            // p2 lies outside the light (lightOutside): its first hit faces the ball.
            float tLight;
            if (!light.intersect(Ray{cn.p2, cn.wo}, 0.f, Infinity, tLight)) continue;
            const Color f = v.f(cn.wi);
            if (isBlack(f)) continue;
            const Vec3 yHit = cn.p2 + cn.wo * tLight;
            const Color T = throughBall(cn, &yHit, 0.f);
            if (isBlack(T)) continue;
            const double pm = connectionPdf(s, 2, *sphere, v.p, cn.wi, yHit);
            const double pu = lights.pathFollows ? double(v.pdf(cn.wi)) * double(cn.transmission) : 0.0;
            L += f * light.emittedRadiance() * T * float(double(cn.transmission) * power3(pc, pm, pu) / pc);
        }
    }
    return L;
}

float sphereCausticPathWeight(const Scene& scene, int sphere, int refractions, int light, const Vec3& x, const Vec3& w,
                              float pathPdf, const Vec3& y) {
    const GlassSphere& s = scene.glassSpheres[size_t(sphere)];
    const Light& l = scene.lights[size_t(light)];
    const LightSphere* lightSphere = l.sphere();
    if (!lightSphere || connectionPattern(s, l, x) != refractions) return 1;
    const Vec3 wn = normalize(w);
    SphereConnection traced;
    if (!(refractions == 2 ? traceThroughSphere(s, x, wn, traced) : traceAcrossSphere(s, x, wn, traced))) return 1;
    const double pu = double(pathPdf) * double(traced.transmission);
    return float(power3(pu, connectionPdf(s, refractions, *lightSphere, x, wn, y), refractions == 2 ? ballConePdf(s, x) : 0.0));
}

float SphereCaustics::pathHitWeight(const SpecularChain& chain, int light, const Vec3& x, const Vec3& w, float pathPdf,
                                    const Vec3& y) const {
    // The pattern of refractions at one glass sphere (followLensPattern);
    // more events than a connection makes take no weight.
    if (chain.length > SpecularChain::MaxEvents) return 1;
    int sphere = -1, refractions = 0;
    for (int i = 0; i < chain.length; ++i) followLensPattern(mScene, chain.refracted[i], chain.surface[i], sphere, refractions);
    if (refractions < 1) return 1;
    return sphereCausticPathWeight(mScene, sphere, refractions, light, x, w, pathPdf, y);
}

}  // namespace vdbmarch
