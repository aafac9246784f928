#include "transport/beam_directions.h"

#include <cmath>

#include "core/sampling.h"
#include "transport/light_distance.h"
#include "volume/medium.h"

namespace vdbmarch {

namespace {

// The largest optical depth across a region's bounds (its densest
// extinction times the diagonal) where beams are sampled.
constexpr double MaxBeamRegionDepth = 4;

// The beams of every region, made on a thread's first use: per region a
// list of spots with their axial range over the region's scattering media.
void buildBeams(ThreadContext& ctx) {
    const Scene& scene = ctx.scene;
    const size_t nLights = scene.lights.size();
    ctx.beamRegions.assign(scene.regions.size(), {});
    for (size_t r = 0; r < scene.regions.size(); ++r) {
        // The distance-sampling candidates say which spots can reach the
        // region at all (no blocking surface between) and give its hull.
        if (!regionHasLightDistances(ctx, int(r), false)) continue;
        const BBox& hull = ctx.scatterBounds[r];
        if (!hull.isFinite() || hull.empty()) continue;
        // Thin media only: in a dense one a path sent towards a beam meets
        // a collision long before it, and the directions it did not take
        // by f cost more than they bring (a spot in the sample cloud: 16x
        // the pair MSE per sample).
        double depth = 0;
        for (int mi : scene.regions[r].media) {
            const Medium& m = *scene.media[size_t(mi)];
            depth += double(maxComponent(m.sigma_a + m.sigma_s)) * double(m.maxDensity());
        }
        if (!(depth * double(length(hull.extent())) <= MaxBeamRegionDepth)) continue;
        ThreadContext::BeamRegion& out = ctx.beamRegions[r];
        double total = 0;
        for (size_t i = 0; i < nLights; ++i) {
            const Light& light = scene.lights[i];
            if (light.desc().type != LightDesc::Type::Spot || !ctx.lightDistanceCandidate[r * nLights + i]) continue;
            ThreadContext::Beam b;
            b.light = int(i);
            b.apex = light.desc().position;
            b.axis = normalize(light.desc().direction);
            const double cone = double(light.desc().coneDeg) * (PiD / 180);
            if (!(cone > 0 && cone < 0.5 * PiD * 0.99)) continue;
            b.tanCone = float(std::tan(cone));
            b.cosCone = float(std::cos(cone));
            // The axial range of the hull: its corners' projections.
            float s0 = Infinity, s1 = -Infinity;
            for (int c = 0; c < 8; ++c) {
                const Vec3 p(c & 1 ? hull.hi.x : hull.lo.x, c & 2 ? hull.hi.y : hull.lo.y, c & 4 ? hull.hi.z : hull.lo.z);
                const float s = dot(p - b.apex, b.axis);
                s0 = std::min(s0, s);
                s1 = std::max(s1, s);
            }
            b.s0 = std::max(s0, 1e-4f * std::max(scene.sceneScale, 1e-6f));
            b.s1 = s1;
            if (!(b.s1 > b.s0)) continue;
            // Chosen in proportion to the beam's power per unit length.
            b.choice = std::max(average(light.desc().intensity), 0.f) * (1 - b.cosCone);
            if (!(b.choice > 0)) continue;
            total += b.choice;
            coordinateSystem(b.axis, b.e1, b.e2);
            out.beams.push_back(b);
        }
        for (ThreadContext::Beam& b : out.beams) b.choice = float(b.choice / total);
    }
}

// The integral of t^2 / s(t)^2 over [ta, tb], s(t) = sx + c t > 0 there:
// in closed form where s varies, by 8-point Gauss-Legendre where it hardly
// does (the closed form cancels there; the integrand is then a smooth
// quadratic over a nearly constant s^2, which the rule integrates to
// rounding).
double inverseSquareMoment(double sx, double c, double ta, double tb) {
    const double ua = sx + c * ta, ub = sx + c * tb;
    if (std::fabs(c) * (tb - ta) > 0.25 * std::min(ua, ub)) {
        auto F = [&](double u) { return u - 2 * sx * std::log(u) - sx * sx / u; };
        return (F(ub) - F(ua)) / (c * c * c);
    }
    static const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static const double w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    const double mid = 0.5 * (ta + tb), half = 0.5 * (tb - ta);
    double sum = 0;
    for (int i = 0; i < 4; ++i)
        for (double t : {mid - half * x[i], mid + half * x[i]}) {
            const double s = sx + c * t;
            sum += w[i] * t * t / (s * s);
        }
    return sum * half;
}

// The density of directions towards beam b from x (solid angle): the
// volume density 1 / ((s1 - s0) pi tan^2 s^2) integrated along the ray over
// the cone's part in [s0, s1], with the Jacobian t^2.
double beamPdf(ThreadContext& ctx, const ThreadContext::Beam& b, const Vec3& x, const Vec3& wi) {
    float t0, t1;
    if (!lightReach(ctx, b.light, Ray{x, wi}, t0, t1)) return 0;
    const double sx = double(dot(x - b.apex, b.axis)), c = double(dot(wi, b.axis));
    double ta = t0, tb = t1;
    if (std::fabs(c) < 1e-12) {
        if (sx < b.s0 || sx > b.s1) return 0;
    } else {
        double a0 = (b.s0 - sx) / c, a1 = (b.s1 - sx) / c;
        if (a0 > a1) std::swap(a0, a1);
        ta = std::max(ta, a0);
        tb = std::min(tb, a1);
    }
    ta = std::max(ta, 0.0);
    if (!(tb > ta) || std::isinf(tb)) return 0;
    const double norm = double(b.s1 - b.s0) * PiD * double(b.tanCone) * double(b.tanCone);
    return inverseSquareMoment(sx, c, ta, tb) / norm;
}

}  // namespace

bool regionHasBeamDirections(ThreadContext& ctx, int region, bool skipPointLights) {
    if (!ctx.scene.desc.render.beamDirections || skipPointLights) return false;
    if (ctx.beamRegions.empty()) buildBeams(ctx);
    return !ctx.beamRegions[size_t(region)].beams.empty();
}

float beamDirectionPdf(ThreadContext& ctx, int region, const Vec3& x, const Vec3& wi) {
    double pdf = 0;
    for (const ThreadContext::Beam& b : ctx.beamRegions[size_t(region)].beams)
        pdf += double(b.choice) * beamPdf(ctx, b, x, wi);
    return float(pdf);
}

float BeamMixture::pdf(const Vec3& wi) const {
    return (1 - BeamShare) * vertex->fPdf(wi) + BeamShare * beamDirectionPdf(*ctx, region, vertex->p, wi);
}

Vec3 BeamMixture::sample(Rng& rng, Color& weight, float& pdfOut) const {
    const ScatterVertex& v = *vertex;
    const float u = rng.uniform();
    const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    Vec3 wi;
    if (u < BeamShare) {
        // A beam, a point along its axis, a point on the cone's disc there.
        const std::vector<ThreadContext::Beam>& beams = ctx->beamRegions[size_t(region)].beams;
        size_t k = 0;
        for (float cdf = beams[0].choice; k + 1 < beams.size() && !(u0 < cdf); cdf += beams[++k].choice) {
        }
        const ThreadContext::Beam& b = beams[k];
        const float s = b.s0 + u1 * (b.s1 - b.s0);
        const float r = s * b.tanCone * std::sqrt(u2), phi = 2 * Pi * rng.uniform();
        const Vec3 to = b.apex + b.axis * s + (b.e1 * std::cos(phi) + b.e2 * std::sin(phi)) * r - v.p;
        const float len = length(to);
        if (!(len > 0)) {
            pdfOut = 0;
            weight = Color(0);
            return v.d;
        }
        wi = to / len;
    } else if (v.phase) {
        Color unused(1);
        float phasePdf;
        wi = v.phase->sample(v.d, u0, u1, u2, unused, phasePdf);
    } else {
        wi = directionAround(v.arrivalNormal(), std::sqrt(1 - u1), u2);  // cosine
    }
    pdfOut = pdf(wi);
    const Color f = v.f(wi);
    if (!(pdfOut > 0) || isBlack(f)) {
        pdfOut = 0;
        weight = Color(0);
        return wi;
    }
    weight *= f / pdfOut;
    return wi;
}

}  // namespace vdbmarch
