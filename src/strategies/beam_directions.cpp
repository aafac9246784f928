#include "strategies/beam_directions.h"

#include <cmath>

#include "core/sampling.h"
#include "strategies/light_distances.h"
#include "transport/phase.h"
#include "volume/medium.h"

namespace vdbmarch {

namespace {

// The largest optical depth across a region's bounds (its densest
// extinction times the diagonal) where beams are sampled.
constexpr double MaxBeamRegionDepth = 4;

// The beams' axial density (BeamView): bins along the axis, and the angle
// table's resolution.
constexpr int BeamBins = 16;
constexpr int BeamAngleSteps = 256;

// The asymmetry of a region's scattering media, weighted by their densest
// scattering: the phase the axial density assumes (a proposal only).
float regionPhaseG(const Scene& scene, int region) {
    double sum = 0, weight = 0;
    for (int mi : scene.regions[size_t(region)].media) {
        const Medium& m = *scene.media[size_t(mi)];
        const double w = double(average(m.sigma_s)) * double(m.maxDensity());
        sum += w * double(m.g);
        weight += w;
    }
    return weight > 0 ? float(sum / weight) : 0.f;
}

// G(theta) = int_0^theta p_HG(cos a, g) da at BeamAngleSteps + 1 angles,
// by Simpson's rule on 8 sub-steps per step.
std::vector<float> phaseAngleIntegral(float g) {
    std::vector<float> G(BeamAngleSteps + 1, 0.f);
    const double step = PiD / BeamAngleSteps, h = step / 8;
    auto p = [&](double a) { return double(hgPhase(float(std::cos(a)), g)); };
    double sum = 0;
    for (int k = 0; k < BeamAngleSteps; ++k) {
        for (int j = 0; j < 8; ++j) {
            const double a = k * step + j * h;
            sum += h / 6 * (p(a) + 4 * p(a + 0.5 * h) + p(a + h));
        }
        G[size_t(k + 1)] = float(sum);
    }
    return G;
}

// The axial range [s0, s1] of `hull` along a beam from `origin` (its
// corners' projections).
void axialRange(const BBox& hull, const Vec3& origin, const Vec3& axis, float& s0, float& s1) {
    s0 = Infinity;
    s1 = -Infinity;
    for (int c = 0; c < 8; ++c) {
        const Vec3 p(c & 1 ? hull.hi.x : hull.lo.x, c & 2 ? hull.hi.y : hull.lo.y, c & 4 ? hull.hi.z : hull.lo.z);
        const float s = dot(p - origin, axis);
        s0 = std::min(s0, s);
        s1 = std::max(s1, s);
    }
}

// A spot's cone, where its distance sampling may pay in the region
// (light_distances.h's candidates).
bool spotBeam(const Scene& scene, const LightDistances& distances, const BBox& hull, size_t i, int region,
              BeamDirections::Beam& b) {
    const Light& light = scene.lights[i];
    const SpotCone* spot = light.spotCone();
    if (!spot || !distances.regionHasCandidates(region, false) || !distances.candidate(region, int(i))) return false;
    b.light = int(i);
    b.apex = spot->apex;
    b.axis = normalize(spot->axis);
    const double cone = double(spot->coneDeg) * (PiD / 180);
    if (!(cone > 0 && cone < 0.5 * PiD * 0.99)) return false;
    b.tanCone = float(std::tan(cone));
    const float cosCone = float(std::cos(cone));
    float s0, s1;
    axialRange(hull, b.apex, b.axis, s0, s1);
    b.s0 = std::max(s0, 1e-4f * std::max(scene.sceneScale, 1e-6f));
    b.s1 = s1;
    // The power it scatters per unit length (the choice between beams
    // weighs it by the vertex's view, BeamView).
    b.power = std::max(average(light.desc().intensity), 0.f) * (1 - cosCone);
    coordinateSystem(b.axis, b.e1, b.e2);  // the disc's axes
    return b.s1 > b.s0 && b.power > 0;
}

// A collimated quad's prism: the points the quad's parallel light reaches,
// from the axial position where the whole cross-section is downstream of
// the (possibly tilted) quad, over the region's hull. Its cross-section
// perpendicular to the axis is the quad seen along the beam, of constant
// area, so the power per unit length is the irradiance times that area.
bool prismBeam(const Scene& scene, const BBox& hull, size_t i, int region, BeamDirections::Beam& b) {
    const Light& light = scene.lights[i];
    const CollimatedQuad* quad = light.collimatedQuad();
    if (!quad || !openToRegion(scene, quad->center, region)) return false;
    const CollimatedQuad& q = *quad;
    b.light = int(i);
    b.prism = true;
    b.apex = q.center;
    b.axis = normalize(q.direction);
    b.u = q.u;
    b.v = q.v;
    b.uAxial = dot(q.u, b.axis);
    b.vAxial = dot(q.v, b.axis);
    const Vec3 n = cross(q.u, q.v);
    const float n2 = lengthSquared(n), dn = dot(b.axis, n);
    b.area = std::fabs(dn);
    if (!(n2 > 0) || !(b.area > 1e-6f * n2)) return false;  // a beam along the quad's plane
    // A point's quad coordinates along the beam: its projection along the
    // axis onto the quad's plane, in the dual basis of u and v.
    const Vec3 dualU = cross(q.v, n) / n2, dualV = cross(n, q.u) / n2;
    b.dualA = dualU - n * (dot(b.axis, dualU) / dn);
    b.dualB = dualV - n * (dot(b.axis, dualV) / dn);
    float s0, s1;
    axialRange(hull, b.apex, b.axis, s0, s1);
    b.s0 = std::max(s0, 0.5f * (std::fabs(b.uAxial) + std::fabs(b.vAxial)));
    b.s1 = s1;
    b.power = std::max(average(light.desc().irradiance), 0.f) * b.area;
    return b.s1 > b.s0 && b.power > 0;
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

// atan2(y, x) for y >= 0, in [0, pi], to about 1e-5: the axial density
// only needs the same function wherever it is evaluated.
inline double angleAt(double y, double x) {
    const double ax = std::fabs(x), big = std::max(ax, y), small = std::min(ax, y);
    if (!(big > 0)) return 0;
    const double a = small / big, q = a * a;
    double r = ((-0.0464964749 * q + 0.15931422) * q - 0.327622764) * q * a + a;
    if (y > ax) r = 0.5 * PiD - r;
    return x < 0 ? PiD - r : r;
}

// One beam as a vertex at x sees it. The axial density of its points is
// proportional to the beam's phase towards x times the inverse square of
// the distance (the light a point scatters towards x, per unit length of
// axis; the cone's disc area cancels the spot's 1/s^2). With theta(s) the
// angle at the axis point s between the beam's travel and the way to x,
// theta = atan2(h, sx - s) for x at axial position sx and distance h from
// the axis, that product is p(cos theta) d theta / h: its integral over an
// axial range is a difference of G(theta), the phase integrated over the
// angle (tabulated per region). The axial density is piecewise constant on
// BeamBins bins, each bin's mass from G at its ends, so that a direction's
// density keeps a closed form per bin (inverseSquareMoment).
static_assert(BeamMixture::Sight::Edges == BeamBins + 1, "a sight holds G at every bin edge");

struct BeamView {
    const BeamDirections::Beam* beam = nullptr;
    const std::vector<float>* G = nullptr;
    BeamMixture::Sight sight;
    // The vertex's stored sight, whose edge integrals are kept (or null).
    BeamMixture::Sight* stored = nullptr;

    BeamView(const BeamDirections::Beam& b, const std::vector<float>& table, BeamMixture::Sight& s)
        : beam(&b), G(&table), sight(s), stored(&s) {}
    BeamView(const BeamDirections::Beam& b, const std::vector<float>& table, const Vec3& x) : beam(&b), G(&table) {
        const Vec3 v = x - b.apex;
        sight.sx = double(dot(v, b.axis));
        // Off the axis by at least the disc's radius at the range's start
        // (a prism's half width): bounded weights for a vertex on the axis.
        const double radius = b.prism ? 0.5 * std::sqrt(double(b.area)) : double(b.tanCone) * double(b.s0);
        sight.h = std::max(double(length(v - b.axis * float(sight.sx))), radius);
        sight.g0 = angleIntegralAt(0);
        sight.g1 = angleIntegralAt(BeamBins);
        sight.weight = sight.g1 > sight.g0 ? double(b.power) * (sight.g1 - sight.g0) / sight.h : 0;
    }
    double weight() const { return sight.weight; }
    double edge(int i) const {
        const double s0 = beam->s0, s1 = beam->s1;
        return i >= BeamBins ? s1 : s0 + (s1 - s0) * i / BeamBins;
    }
    // G at bin edge i, linear between the table's angles.
    double angleIntegralAt(int i) const {
        if (stored && (stored->known >> i & 1u)) return stored->edgeIntegral[i];
        const double f = std::clamp(angleAt(sight.h, sight.sx - edge(i)) / PiD, 0.0, 1.0) * BeamAngleSteps;
        const int k = std::min(int(f), BeamAngleSteps - 1);
        const std::vector<float>& t = *G;
        const double g = double(t[size_t(k)]) + (f - k) * double(t[size_t(k + 1)] - t[size_t(k)]);
        if (stored) {
            stored->edgeIntegral[i] = g;
            stored->known |= 1u << i;
        }
        return g;
    }
};

// Beam k as the mixture's vertex sees it: from the sights made once per
// vertex (the first MaxSights beams), or made now.
BeamView viewOf(const BeamMixture& m, size_t k) {
    const BeamDirections::Region& r = m.beams->region(m.region);
    if (m.mBeamWeight < 0) {
        double total = 0;
        for (size_t j = 0; j < r.beams.size(); ++j) {
            const BeamView v(r.beams[j], *r.angleIntegral, m.vertex->p);
            if (j < size_t(BeamMixture::MaxSights)) {
                BeamMixture::Sight& stored = m.mSights[j];
                stored = v.sight;
                stored.edgeIntegral[0] = v.sight.g0;
                stored.edgeIntegral[BeamBins] = v.sight.g1;
                stored.known = 1u | 1u << BeamBins;
            }
            total += v.weight();
        }
        m.mBeamWeight = total;
    }
    if (k < size_t(BeamMixture::MaxSights)) return BeamView(r.beams[k], *r.angleIntegral, m.mSights[k]);
    return BeamView(r.beams[k], *r.angleIntegral, m.vertex->p);
}

// A prism's chord: the part of x + t wi whose quad coordinates lie in
// [-1/2, 1/2] (two slabs).
bool prismChord(const BeamDirections::Beam& b, const Vec3& x, const Vec3& wi, float& t0, float& t1) {
    double lo = 0, hi = double(Infinity);
    for (const Vec3* dual : {&b.dualA, &b.dualB}) {
        const double a = double(dot(x - b.apex, *dual)), da = double(dot(wi, *dual));
        if (std::fabs(da) < 1e-12) {
            if (std::fabs(a) > 0.5) return false;
            continue;
        }
        double e0 = (-0.5 - a) / da, e1 = (0.5 - a) / da;
        if (e0 > e1) std::swap(e0, e1);
        lo = std::max(lo, e0);
        hi = std::min(hi, e1);
    }
    t0 = float(lo);
    t1 = float(hi);
    return hi > lo;
}

// The density of directions towards the beam of `view` from x (solid
// angle): per bin, its mass times the volume density 1 / (bin length x
// cross-section area: pi tan^2 s^2 for a cone, constant for a prism)
// integrated along the ray over the beam's part in the bin, with the
// Jacobian t^2.
double beamPdf(ThreadContext& ctx, const BeamView& view, const Vec3& x, const Vec3& wi) {
    const BeamDirections::Beam& b = *view.beam;
    float t0, t1;
    if (b.prism ? !prismChord(b, x, wi, t0, t1) : !ctx.lightReach(b.light, Ray{x, wi}, t0, t1)) return 0;
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
    // The bins the chord crosses, from its axial ends.
    const double sa = std::fabs(c) < 1e-12 ? sx : sx + c * ta, sb = std::fabs(c) < 1e-12 ? sx : sx + c * tb;
    const double len = double(b.s1 - b.s0);
    const int i0 = std::clamp(int((std::min(sa, sb) - b.s0) / len * BeamBins), 0, BeamBins - 1);
    const int i1 = std::clamp(int((std::max(sa, sb) - b.s0) / len * BeamBins), 0, BeamBins - 1);
    // A cone's disc has area pi tan^2 s^2 (the s^2 in inverseSquareMoment);
    // a prism's cross-section a constant area (the plain moment of t^2).
    const double mass = view.sight.g1 - view.sight.g0,
                 area = b.prism ? double(b.area) : PiD * double(b.tanCone) * double(b.tanCone);
    double pdf = 0, gLo = view.angleIntegralAt(i0);
    for (int i = i0; i <= i1; ++i) {
        const double lo = view.edge(i), hi = view.edge(i + 1), gHi = view.angleIntegralAt(i + 1);
        const double binMass = std::max(gHi - gLo, 0.0) / mass;
        gLo = gHi;
        if (!(binMass > 0)) continue;
        double u = ta, v = tb;
        if (std::fabs(c) >= 1e-12) {
            double a0 = (lo - sx) / c, a1 = (hi - sx) / c;
            if (a0 > a1) std::swap(a0, a1);
            u = std::max(u, a0);
            v = std::min(v, a1);
        }
        if (!(v > u)) continue;
        const double moment = b.prism ? (v * v * v - u * u * u) / 3 : inverseSquareMoment(sx, c, u, v);
        pdf += binMass * moment / ((hi - lo) * area);
    }
    return pdf;
}

// The beams' density of wi from x (solid angle): each of the n beams'
// density weighed by its share of the views' weights (viewAt(k): beam k as
// x sees it).
template <typename ViewAt>
double beamsPdf(ThreadContext& ctx, size_t n, ViewAt&& viewAt, const Vec3& x, const Vec3& wi) {
    double pdf = 0, total = 0;
    for (size_t k = 0; k < n; ++k) {
        const BeamView view = viewAt(k);
        total += view.weight();
        if (view.weight() > 0) pdf += view.weight() * beamPdf(ctx, view, x, wi);
    }
    return total > 0 ? pdf / total : 0.0;
}

}  // namespace

BeamDirections::BeamDirections(const Scene& scene, const LightDistances& distances, size_t slot)
    : mRegions(scene.regions.size()), mSlot(slot) {
    if (!scene.desc.experiments.beamDirections) return;
    const size_t nLights = scene.lights.size();
    for (size_t r = 0; r < scene.regions.size(); ++r) {
        const BBox& hull = distances.scatterBounds(int(r));
        if (!hull.isFinite() || hull.empty()) continue;
        // Thin media only: in a dense one a path sent towards a beam meets
        // a collision long before it, and the directions it did not take
        // by f cost more than they bring (docs/method.md).
        double depth = 0;
        for (int mi : scene.regions[r].media) {
            const Medium& m = *scene.media[size_t(mi)];
            depth += double(maxComponent(m.sigma_a + m.sigma_s)) * double(m.maxDensity());
        }
        if (!(depth * double(length(hull.extent())) <= MaxBeamRegionDepth)) continue;
        Region& out = mRegions[r];
        for (size_t i = 0; i < nLights; ++i) {
            Beam b;  // each maker first checks the light's type
            if (spotBeam(scene, distances, hull, i, int(r), b) || prismBeam(scene, hull, i, int(r), b))
                out.beams.push_back(b);
        }
        if (out.beams.empty()) continue;
        const float g = regionPhaseG(scene, int(r));
        auto it = mAngleIntegrals.find(g);
        if (it == mAngleIntegrals.end()) it = mAngleIntegrals.emplace(g, phaseAngleIntegral(g)).first;
        out.angleIntegral = &it->second;
    }
}

bool BeamDirections::attach(ThreadContext& ctx, int region, ScatterVertex& v, bool skipPointLights) const {
    if (!hasBeams(region, skipPointLights)) return false;
    BeamMixture& m = ctx.extensionAt<Scratch>(mSlot).mixture;
    m.ctx = &ctx;
    m.beams = this;
    m.region = region;
    m.vertex = &v;
    m.mBeamWeight = -1;  // the sights are made again for this vertex
    v.pathPdf = &BeamMixture::pdfOf;
    v.pathSampler = &m;
    return true;
}

Vec3 BeamDirections::sample(ThreadContext& ctx, Rng& rng, Color& weight, float& pdf) const {
    return ctx.extensionAt<Scratch>(mSlot).mixture.sample(rng, weight, pdf);
}

float BeamDirections::beamDirectionPdf(ThreadContext& ctx, int region, const Vec3& x, const Vec3& wi) const {
    const Region& r = mRegions[size_t(region)];
    return float(beamsPdf(
        ctx, r.beams.size(), [&](size_t k) { return BeamView(r.beams[k], *r.angleIntegral, x); }, x, wi));
}

double BeamMixture::beamWeight() const {
    if (mBeamWeight < 0) viewOf(*this, 0);
    return mBeamWeight;
}

float BeamMixture::pdf(const Vec3& wi) const {
    // A vertex that sees no beam (every view's weight zero) keeps f alone.
    if (!(beamWeight() > 0)) return vertex->fPdf(wi);
    const double beamsDensity = beamsPdf(
        *ctx, beams->region(region).beams.size(), [&](size_t k) { return viewOf(*this, k); }, vertex->p, wi);
    return (1 - BeamShare) * vertex->fPdf(wi) + BeamShare * float(beamsDensity);
}

Vec3 BeamMixture::sample(Rng& rng, Color& weight, float& pdfOut) const {
    const ScatterVertex& v = *vertex;
    const float u = rng.uniform();
    const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    Vec3 wi;
    if (u < BeamShare && beamWeight() > 0) {
        // A beam by its weight, a bin by its mass (a search on G at the
        // bins' edges), a point along the bin, a point on the disc there.
        const BeamDirections::Region& r = beams->region(region);
        double pick = double(u0) * beamWeight();
        size_t k = 0;
        for (; k + 1 < r.beams.size(); ++k) {
            const double w = viewOf(*this, k).weight();
            if (pick < w) break;
            pick -= w;
        }
        BeamView view = viewOf(*this, k);
        while (!(view.weight() > 0) && k > 0) view = viewOf(*this, --k);
        const BeamDirections::Beam& b = r.beams[k];
        const double target = view.sight.g0 + double(u1) * (view.sight.g1 - view.sight.g0);
        int lo = 0, hi = BeamBins;  // G(edge lo) <= target < G(edge hi)
        double gLo = view.sight.g0, gHi = view.sight.g1;
        while (hi - lo > 1) {
            const int mid = (lo + hi) / 2;
            const double gm = view.angleIntegralAt(mid);
            if (target < gm) {
                hi = mid;
                gHi = gm;
            } else {
                lo = mid;
                gLo = gm;
            }
        }
        const double along = gHi > gLo ? std::clamp((target - gLo) / (gHi - gLo), 0.0, 1.0) : 0.5;
        const float s = float(view.edge(lo) + along * (view.edge(lo + 1) - view.edge(lo)));
        Vec3 point;
        if (b.prism) {
            // Uniform over the cross-section at s: quad coordinates (a, c),
            // moved along the beam to axial position s.
            const float a = u2 - 0.5f, c = rng.uniform() - 0.5f;
            point = b.apex + b.u * a + b.v * c + b.axis * (s - a * b.uAxial - c * b.vAxial);
        } else {
            const float rad = s * b.tanCone * std::sqrt(u2), phi = 2 * Pi * rng.uniform();
            point = b.apex + b.axis * s + (b.e1 * std::cos(phi) + b.e2 * std::sin(phi)) * rad;
        }
        const Vec3 to = point - v.p;
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
