#include "strategies/caustic_folds.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "strategies/sphere_caustics.h"
#include "transport/direct_light.h"

namespace vdbmarch {

namespace {

// The half-width of the density around a crossing, in radii of the ball:
// the fold's 1 / sqrt(d) holds over a fraction of the caustic's size.
constexpr float FoldHalfWidthRadii = 0.25f;

}  // namespace

void FoldSampler::add(float t, float w) {
    if (mCount >= MaxCrossings || !(w > 0)) return;
    mT[mCount] = t;
    mW[mCount] = w;
    ++mCount;
}

float FoldSampler::sample(float u) const {
    // A crossing by equal odds, a side by equal odds, then |t - t_f| = W v^2
    // (v uniform), the inverse of the density's CDF on that side. A draw
    // that rounds onto t_f moves to the next float on its side: at t_f
    // itself the light is bounded only by how far that float point happens
    // to lie from the fold (often far below a float step), so the density
    // leaves it to the other samplers.
    const float x = std::clamp(u, 0.f, 1.f) * float(mCount);
    const int i = std::min(int(x), mCount - 1);
    float v = std::clamp(x - float(i), 0.f, 1.f);
    const float side = v < 0.5f ? -1.f : 1.f;
    v = v < 0.5f ? 2 * v : 2 * v - 1;
    const float t = mT[i] + side * mW[i] * v * v;
    return t == mT[i] ? std::nextafter(t, side * Infinity) : t;
}

float FoldSampler::offCrossing(float t) const {
    for (int i = 0; i < mCount; ++i)
        if (t == mT[i]) return std::nextafter(t, Infinity);
    return t;
}

double FoldSampler::pdf(float t) const {
    double p = 0;
    for (int i = 0; i < mCount; ++i) {
        const double w = mW[i], d = std::fabs(double(t) - double(mT[i]));
        if (!(d > 0) || !(d < w)) continue;
        // The float next to t_f holds the draws that round onto it and onto
        // t_f: those within 1.5 steps, sqrt(1.5 ulp / w) / 2 of the
        // mass; farther out the rounding averages the density over a step.
        const double ulp = std::fabs(double(std::nextafter(mT[i], t > mT[i] ? Infinity : -Infinity)) - double(mT[i]));
        p += d <= 1.5 * ulp ? std::sqrt(1.5 * ulp / w) / (2 * ulp) : 1 / (4 * std::sqrt(w * d));
    }
    return p / double(mCount);
}

namespace {

// A ray o + t d against the fold's axis, in double: z(t) = qz + t dz along
// it, rho^2(t) = |q + t d|^2 - z(t)^2 (q = o - centre).
struct AxialRay {
    double qz, dz, qd, qq, dd;
    AxialRay(const CausticFold& f, const Ray& ray) {
        // In double: rho^2 is a small difference of large squares near the axis.
        const double q[3] = {double(ray.o.x) - f.center.x, double(ray.o.y) - f.center.y, double(ray.o.z) - f.center.z};
        const double d[3] = {ray.d.x, ray.d.y, ray.d.z}, a[3] = {f.axis.x, f.axis.y, f.axis.z};
        auto dot3 = [](const double* u, const double* v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
        qz = dot3(q, a);
        dz = dot3(d, a);
        qd = dot3(q, d);
        qq = dot3(q, q);
        dd = dot3(d, d);
    }
    double rho(double t) const {
        const double z = qz + t * dz;
        return std::sqrt(std::max(0.0, qq + t * (2 * qd + t * dd) - z * z));
    }
};

// The crossing near tLin (found on edge e of the polyline, whose chords
// stray from the fold by up to ~1e-5 of its size) moved onto the exact fold:
// false position on u between the edge's neighbours for h(u), the ray's
// offset from the fold's point E(u) (in rho at E's axial position, or,
// for a ray across the axis, in z at E's radius). tLin where h keeps its
// sign there (the ray meets the fold twice within the bracket).
double refineCrossing(const GlassSphere& s, const Light& l, const CausticFold& f, const AxialRay& r, size_t e,
                      double tLin) {
    const bool alongAxis = std::fabs(r.dz) >= 0.3;
    double tAt = tLin;
    auto h = [&](double u, double& value) {
        double zc, rc;
        if (!causticFoldPoint(s, l, u, zc, rc)) return false;
        if (alongAxis) {
            tAt = (zc - r.qz) / r.dz;
            value = r.rho(tAt) - rc;
            return true;
        }
        // rho(t) = rc: the root nearest tLin.
        const double A = r.dd - r.dz * r.dz, B = 2 * (r.qd - r.qz * r.dz), C = r.qq - r.qz * r.qz - rc * rc;
        const double disc = B * B - 4 * A * C;
        if (!(A > 0) || disc < 0) return false;
        const double sq = std::sqrt(disc), t0 = (-B - sq) / (2 * A), t1 = (-B + sq) / (2 * A);
        tAt = std::fabs(t0 - tLin) < std::fabs(t1 - tLin) ? t0 : t1;
        value = r.qz + tAt * r.dz - zc;
        return true;
    };
    const size_t n = f.u.size();
    double ul = f.u[e > 0 ? e - 1 : 0], uh = f.u[std::min(e + 2, n - 1)], hl, hh;
    if (!h(ul, hl) || !h(uh, hh) || !(hl * hh < 0)) return tLin;
    int side = 0;  // Illinois: halve the weight of an end kept twice
    for (int i = 0; i < 40 && uh - ul > 1e-14 * f.u.back(); ++i) {
        const double um = (ul * hh - uh * hl) / (hh - hl);
        double hm;
        if (!h(um, hm)) return tLin;
        if (hm == 0) return tAt;
        if ((hm < 0) == (hl < 0)) {
            ul = um;
            hl = hm;
            if (side == -1) hh *= 0.5;
            side = -1;
        } else {
            uh = um;
            hh = hm;
            if (side == 1) hl *= 0.5;
            side = 1;
        }
    }
    double hm;
    return h(0.5 * (ul + uh), hm) ? tAt : tLin;
}

}  // namespace

int foldCrossings(const GlassSphere& s, const Light& l, const CausticFold& fold, const Ray& ray, float t0, float t1,
                  float* out, int max) {
    // An edge (z0, rho0)-(z1, rho1) sweeps the frustum rho = m0 + m1 t at
    // the ray, m0 = rho0 + k (qz - z0), m1 = k dz, k its slope: a quadratic
    // in t, whose roots are then moved onto the exact fold.
    const AxialRay r(fold, ray);
    const double qz = r.qz, dz = r.dz, qd = r.qd, qq = r.qq, dd = r.dd;
    int n = 0;
    for (size_t e = 0; e + 1 < fold.z.size() && n < max; ++e) {
        const double z0 = fold.z[e], z1 = fold.z[e + 1], r0 = fold.rho[e], r1 = fold.rho[e + 1];
        if (!(std::fabs(z1 - z0) > 0)) continue;
        const double k = (r1 - r0) / (z1 - z0);
        const double m0 = r0 + k * (qz - z0), m1 = k * dz;
        const double A = dd - dz * dz - m1 * m1, B = 2 * (qd - qz * dz - m0 * m1), C = qq - qz * qz - m0 * m0;
        double roots[2];
        int nr = 0;
        if (std::fabs(A) > 1e-12) {
            const double disc = B * B - 4 * A * C;
            if (disc < 0) continue;
            const double sq = -0.5 * (B + std::copysign(std::sqrt(disc), B));
            roots[nr++] = sq / A;
            if (sq != 0) roots[nr++] = C / sq;
        } else if (B != 0) {
            roots[nr++] = -C / B;
        }
        const double zLo = std::min(z0, z1), zHi = std::max(z0, z1);
        for (int i = 0; i < nr && n < max; ++i) {
            const double t = roots[i], z = qz + t * dz;
            if (!(t >= t0 && t <= t1) || !(z >= zLo && z < zHi) || m0 + m1 * t < 0) continue;
            out[n++] = float(refineCrossing(s, l, fold, r, e, t));
        }
    }
    return n;
}

CausticFolds::CausticFolds(const Scene& scene, size_t slot) : mScene(scene), mSlot(slot) {
    if (!sceneHasSphereCaustics(scene) || !scene.deltaLightCaustics) return;
    for (size_t si = 0; si < scene.glassSpheres.size(); ++si) {
        const GlassSphere& s = scene.glassSpheres[si];
        for (size_t li = 0; li < scene.lights.size(); ++li) {
            const Light& l = scene.lights[li];
            if (!l.isDelta()) continue;
            // A spot whose cone misses the ball casts no caustic through it.
            if (const SpotCone* cone = l.spotCone()) {
                const Vec3 to = s.center - cone->apex;
                const float dist = length(to);
                if (!(dist > s.radius)) continue;
                const float reach = radians(cone->coneDeg) + std::asin(s.radius / dist);
                if (!(dot(to / dist, normalize(cone->axis)) > std::cos(std::min(reach, Pi)))) continue;
            }
            Surface f;
            if (!causticFold(s, l, f.fold)) continue;
            f.sphere = int(si);
            f.light = int(li);
            float zLo = Infinity, zHi = -Infinity, rhoMax = 0;
            for (size_t k = 0; k < f.fold.z.size(); ++k) {
                zLo = std::min(zLo, f.fold.z[k]);
                zHi = std::max(zHi, f.fold.z[k]);
                rhoMax = std::max(rhoMax, f.fold.rho[k]);
            }
            f.boundCenter = f.fold.center + f.fold.axis * (0.5f * (zLo + zHi));
            f.boundRadius = 1.001f * std::sqrt(0.25f * (zHi - zLo) * (zHi - zLo) + rhoMax * rhoMax) + 1e-6f;
            f.halfWidth = FoldHalfWidthRadii * s.radius;
            mSurfaces.push_back(std::move(f));
        }
    }
}

bool CausticFolds::crossings(int region, const Ray& ray, float tEnd, FoldSampler& out) const {
    out.clear();
    float t[FoldSampler::MaxCrossings];
    for (const Surface& f : mSurfaces) {
        if (mScene.glassSpheres[size_t(f.sphere)].outside != region) continue;
        // The bounding sphere first: most segments pass far from a fold.
        const Vec3 oc = ray.o - f.boundCenter;
        const float b = dot(oc, ray.d), c = dot(oc, oc) - f.boundRadius * f.boundRadius, disc = b * b - c;
        if (!(disc > 0)) continue;
        const float h = std::sqrt(disc);
        const float a0 = std::max(0.f, -b - h), a1 = std::min(tEnd, -b + h);
        if (!(a1 > a0)) continue;
        const int n = foldCrossings(mScene.glassSpheres[size_t(f.sphere)], mScene.lights[size_t(f.light)], f.fold, ray,
                                    a0, a1, t, FoldSampler::MaxCrossings - out.count());
        for (int i = 0; i < n; ++i) out.add(t[i], f.halfWidth);
    }
    return !out.empty();
}

bool CausticFolds::prepare(ThreadContext& ctx, const PathSegment& seg) const {
    return crossings(seg.region, seg.ray, seg.tEnd, sampler(ctx));
}

Color CausticFolds::sample(ThreadContext& ctx, const PathSegment& seg, Rng& rng) const {
    const FoldSampler& folds = sampler(ctx);
    if (folds.empty()) return Color(0);
    const float t = folds.sample(rng.uniform());
    if (!(t > 0 && t < seg.tEnd)) return Color(0);
    // The connections of sphereCausticLight's delta part (point-like lights
    // only where the vertices connect them).
    return scatteredAt(ctx, seg, t, float(folds.pdf(t)), false, rng, [&](const ScatterVertex& v) {
        return sphereCausticLight(ctx, seg.region, v, rng, TransmittanceEstimator::UnbiasedMarching,
                                  {false, !seg.skipPointLights, false, true});
    });
}

void CausticFolds::weighCollision(ThreadContext& ctx, const PathSegment& seg, float t, const MediumPoint& mp,
                                  CollisionWeights& w) const {
    const FoldSampler& folds = sampler(ctx);
    if (folds.empty()) return;
    w.connectionWeight = 1 - distanceWeight(float(folds.pdf(t)), trackingDensity(ctx, seg, t, mp));
}

}  // namespace vdbmarch
