#include "photons/photon_emission.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/sampling.h"

namespace vdbmarch {

namespace {


// ---------------------------------------------------------------------------
// Target geometry

bool finiteBox(const BBox& b) { return !b.empty() && isFinite(b.lo) && isFinite(b.hi); }

// Nothing can scatter: no emitter has anything to do.
bool targetEmpty(const PhotonTarget& t) { return !t.unbounded && t.bounds.empty(); }

// Bounding sphere of the target box, 1% larger so rounding never leaves a
// point of the box outside it. False when the box is empty or not finite.
bool targetSphere(const PhotonTarget& t, Vec3& center, float& radius) {
    if (!finiteBox(t.bounds)) return false;
    center = t.bounds.center();
    radius = 0.5f * length(t.bounds.extent()) * 1.01f;
    return std::isfinite(radius);
}

// Cone of directions from p that can reach the target's bounding sphere.
struct Cone {
    Vec3 axis;
    float oneMinusCos = 2;  // 1 - cos(half angle), accurate for tiny cones
    double halfAngle = PiD;
};

// False when every direction may reach the target (p inside the bounding
// sphere, or the target unbounded / not finite).
bool targetCone(const PhotonTarget& t, const Vec3& p, Cone& c) {
    Vec3 center;
    float radius;
    if (t.unbounded || !targetSphere(t, center, radius)) return false;
    // Double: distances may square past float range.
    Vec3 to = center - p;
    double d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += double(to[a]) * to[a];
    double r2 = double(radius) * radius;
    if (!(d2 > r2)) return false;
    c.axis = to / float(std::sqrt(d2));
    double sin2 = r2 / d2;
    c.oneMinusCos = float(sin2 / (1 + std::sqrt(1 - sin2)));
    c.halfAngle = std::asin(std::sqrt(sin2));
    return true;
}

// Conservative: true only when the half-infinite beam swept by the quad
// (centre c, edges u, v) along dir certainly misses the box. Separating axis
// test over the face normals and edge cross products of the two convex
// shapes, the beam's edges being u, v and dir.
bool beamMissesBox(const Vec3& c, const Vec3& u, const Vec3& v, const Vec3& dir, const BBox& box) {
    const Vec3 corners[4] = {c + (u + v) * 0.5f, c + (u - v) * 0.5f, c - (u - v) * 0.5f, c - (u + v) * 0.5f};
    const Vec3 boxAxes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    struct Axis {
        Vec3 a;
        // Perpendicular to dir by construction: the beam's extent is finite
        // (its drift from the rounded axis, ~1e-7 per unit length, is well
        // inside the margin over the distances involved).
        bool perpToDir;
    };
    std::vector<Axis> axes = {{cross(u, v), false}, {cross(u, dir), true}, {cross(v, dir), true}};
    for (const Vec3& b : boxAxes) {
        axes.push_back({b, false});
        axes.push_back({cross(u, b), false});
        axes.push_back({cross(v, b), false});
        axes.push_back({cross(dir, b), true});
    }
    Vec3 boxCenter = box.center(), half = box.extent() * 0.5f;
    for (Axis ax : axes) {
        float len = length(ax.a);
        if (!(len > 1e-12f)) continue;
        Vec3 a = ax.a / len;
        float lo = Infinity, hi = -Infinity;
        for (const Vec3& q : corners) {
            lo = std::min(lo, dot(q, a));
            hi = std::max(hi, dot(q, a));
        }
        float mid = dot(boxCenter, a);
        float r = half.x * std::fabs(a.x) + half.y * std::fabs(a.y) + half.z * std::fabs(a.z);
        // Slack for rounding in the projections, relative to their size.
        float margin = 1e-5f * (std::fabs(mid) + r + std::max(std::fabs(lo), std::fabs(hi))) + 1e-30f;
        if (!ax.perpToDir) {
            // Rounding can only widen the beam's interval here: conservative.
            float dd = dot(dir, a);
            if (dd > 0) hi = Infinity;
            if (dd < 0) lo = -Infinity;
        }
        if (lo > mid + r + margin || hi < mid - r - margin) return true;
    }
    return false;
}

// ---------------------------------------------------------------------------
// Spot falloff and its integral (spotFalloff: scene/lights.h)

// 16-point Gauss-Legendre rule on [-1, 1] (Newton on P_16, computed once).
// It integrates the smoothstep of a cosine (a degree-3 trigonometric
// polynomial) over any interval of length <= pi to double precision.
class GaussLegendre16 {
public:
    GaussLegendre16() {
        const int n = 16;
        for (int i = 0; i < n; ++i) {
            double z = std::cos(PiD * (i + 0.75) / (n + 0.5)), dp = 1;
            for (int it = 0; it < 100; ++it) {
                double p1 = 1, p2 = 0;
                for (int j = 1; j <= n; ++j) {
                    double p3 = p2;
                    p2 = p1;
                    p1 = ((2 * j - 1) * z * p2 - (j - 1) * p3) / j;
                }
                dp = n * (z * p1 - p2) / (z * z - 1);
                double step = p1 / dp;
                z -= step;
                if (std::fabs(step) < 1e-16) break;
            }
            mX[i] = z;
            mW[i] = 2 / ((1 - z * z) * dp * dp);
        }
    }
    template <typename F>
    double integrate(double a, double b, const F& f) const {
        double mid = 0.5 * (a + b), half = 0.5 * (b - a), s = 0;
        for (int i = 0; i < 16; ++i) s += mW[i] * f(mid + half * mX[i]);
        return s * half;
    }

private:
    double mX[16], mW[16];
};

const GaussLegendre16& gaussLegendre() {
    static const GaussLegendre16 rule;
    return rule;
}

// Measure of phi in [0, pi] where A + B cos(phi) > x (B >= 0).
double phiAbove(double A, double B, double x) {
    if (!(B > 0)) return A > x ? PiD : 0;
    return std::acos(clamp((x - A) / B, -1.0, 1.0));
}

// Integral over directions of falloff(cos to the spot axis) times the
// indicator of the target cone, over the sampled cone of one of them.
// Directions are (theta, phi) about the sampled axis, phi = 0 towards the
// other axis; both cosines are then A + B cos(phi) with B >= 0, decreasing in
// phi on [0, pi], so the phi integral is exact (region bounds from acos, the
// smoothstep part by Gauss-Legendre). The theta integral is split where those
// regions change and uses a cosine substitution per piece that removes the
// square-root behaviour of acos at the piece ends; the result is accurate to
// about 1e-10 relative.
struct ConeOverlap {
    double beta;         // angle between the spot and target axes
    double cc, cf;       // spot cone and falloff-start cosines (cf <= cc: hard edge)
    double thetaT;       // target cone half-angle
    bool aboutSpot;      // sampled cone: the spot's (else the target's)
};

double overlapIntegral(const ConeOverlap& o) {
    const GaussLegendre16& gl = gaussLegendre();
    const bool smooth = o.cf > o.cc;
    const double cb = std::cos(o.beta), sb = std::sin(o.beta), cosT = std::cos(o.thetaT);
    const double thetaC = std::acos(o.cc), thetaF = std::acos(std::max(o.cf, o.cc));

    auto inner = [&](double theta) {
        double ct = std::cos(theta), st = std::sin(theta);
        double A = ct, B = 0, phiT = PiD;  // spot cosine; target indicator extent
        if (o.aboutSpot)
            phiT = phiAbove(ct * cb, st * sb, cosT);
        else
            A = ct * cb, B = st * sb;
        double phiF = phiAbove(A, B, smooth ? o.cf : o.cc);
        double sum = std::min(phiF, phiT);
        if (smooth) {
            double phiC = std::min(phiAbove(A, B, o.cc), phiT);
            if (phiC > phiF)
                sum += gl.integrate(phiF, phiC, [&](double phi) {
                    return spotFalloff(1 - (A + B * std::cos(phi)), 1 - o.cc, 1 - o.cf);
                });
        }
        return 2 * sum;
    };

    const double thetaMax = o.aboutSpot ? thetaC : o.thetaT;
    std::vector<double> breaks = {0, thetaMax};
    for (double tx : {thetaF, thetaC, o.thetaT})
        for (double b : {tx, std::fabs(o.beta - tx), o.beta + tx})
            if (b > 0 && b < thetaMax) breaks.push_back(b);
    std::sort(breaks.begin(), breaks.end());

    const int panels = 4;
    double total = 0;
    for (size_t i = 0; i + 1 < breaks.size(); ++i) {
        double a = breaks[i], w = breaks[i + 1] - a;
        if (!(w > 0)) continue;
        for (int k = 0; k < panels; ++k) {
            // theta = a + w (1 - cos(pi s)) / 2, s in [0, 1].
            total += gl.integrate(double(k) / panels, double(k + 1) / panels, [&](double s) {
                double theta = a + w * 0.5 * (1 - std::cos(PiD * s));
                double jac = w * 0.5 * PiD * std::sin(PiD * s);
                return std::sin(theta) * inner(theta) * jac;
            });
        }
    }
    return total;
}

// Direction at 1 - cos(theta) = t about `axis` and azimuth 2 pi u; sin(theta)
// from t so that tiny cones (distant targets) keep their spread.
Vec3 coneDirection(const Vec3& axis, float t, float u) {
    Vec3 s, b;
    coordinateSystem(axis, s, b);
    float sinTheta = safeSqrt(t * (2 - t)), phi = 2 * Pi * u;
    return s * (sinTheta * std::cos(phi)) + b * (sinTheta * std::sin(phi)) + axis * (1 - t);
}

Vec3 unitOr(const Vec3& v, const Vec3& fallback) {
    float len = length(v);
    return len > 0 && std::isfinite(len) ? v / len : fallback;
}

}  // namespace

// ---------------------------------------------------------------------------

PhotonEmitter PhotonEmitter::forLight(const Light& light, const PhotonTarget& target) {
    PhotonEmitter e;
    if (targetEmpty(target)) return e;
    const LightDesc& d = light.desc();
    switch (d.type) {
        case LightDesc::Type::Point: {
            if (isBlack(d.intensity)) return e;
            e.mKind = Kind::Point;
            e.mOrigin = d.position;
            e.mAxis = Vec3(0, 0, 1);
            Cone c;
            if (targetCone(target, d.position, c)) {
                e.mAxis = c.axis;
                e.mOneMinusCos = c.oneMinusCos;
            }
            e.mWeight = d.intensity * (2 * Pi * e.mOneMinusCos);
            e.mPower = e.mWeight;
            break;
        }
        case LightDesc::Type::Spot: {
            // Same float cosines as Light, so the cone edge matches exactly.
            float cc = std::cos(radians(d.coneDeg));
            float cf = std::cos(radians(d.coneDeg - d.falloffDeg));
            float spotOmc = 1 - cc;
            if (isBlack(d.intensity) || !(spotOmc > 0)) return e;
            e.mKind = Kind::Spot;
            e.mOrigin = d.position;
            e.mSpotAxis = unitOr(d.direction, Vec3(0, -1, 0));
            e.mOmcCone = spotOmc;
            e.mOmcFalloffStart = 1 - cf;
            // Closed form over the whole spot cone: the smoothstep averages 1/2.
            double cHard = std::max(cf, cc);
            double spotIntegral = 2 * PiD * ((1 - cHard) + 0.5 * (cHard - double(cc)));
            e.mAxis = e.mSpotAxis;
            e.mOneMinusCos = spotOmc;
            double integral = spotIntegral;
            Cone c;
            if (targetCone(target, d.position, c)) {
                Vec3 a = e.mSpotAxis;
                double beta = std::atan2(double(length(cross(a, c.axis))), double(dot(a, c.axis)));
                double thetaS = std::acos(double(cc));
                if (beta >= thetaS + c.halfAngle) return PhotonEmitter();  // the cone misses the target
                if (beta + thetaS > c.halfAngle) {
                    // Partial overlap: sample the narrower cone, zero outside the other.
                    e.mSampleSpotCone = spotOmc <= c.oneMinusCos;
                    e.mTestTargetCone = e.mSampleSpotCone;
                    e.mTargetAxis = c.axis;
                    e.mTargetOneMinusCos = c.oneMinusCos;
                    if (!e.mSampleSpotCone) {
                        e.mAxis = c.axis;
                        e.mOneMinusCos = c.oneMinusCos;
                    }
                    integral = overlapIntegral({beta, cc, cf, c.halfAngle, e.mSampleSpotCone});
                }
            }
            e.mWeight = d.intensity * (2 * Pi * e.mOneMinusCos);
            e.mPower = d.intensity * float(integral);
            break;
        }
        case LightDesc::Type::Directional: {
            e = forDisc(d.irradiance, unitOr(d.direction, Vec3(0, -1, 0)), target);
            break;
        }
        case LightDesc::Type::CollimatedQuad: {
            Vec3 dir = unitOr(d.direction, Vec3(0, -1, 0));
            // Light::sample gives irradiance perpendicular to the beam: the
            // flux through the quad is E times its area seen along the beam.
            float projArea = std::fabs(dot(cross(d.u, d.v), dir));
            if (isBlack(d.irradiance) || !(projArea > 0) || !std::isfinite(projArea)) return e;
            if (!target.unbounded && finiteBox(target.bounds) &&
                beamMissesBox(d.center, d.u, d.v, dir, target.bounds))
                return e;
            e.mKind = Kind::Quad;
            e.mOrigin = d.center;
            e.mAxis = dir;
            e.mU = d.u;
            e.mV = d.v;
            e.mWeight = d.irradiance * projArea;
            e.mPower = e.mWeight;
            break;
        }
        case LightDesc::Type::Sphere: {
            if (isBlack(d.power)) return e;
            e.mKind = Kind::Sphere;
            e.mOrigin = d.position;
            e.mRadius = std::fabs(d.radius);
            e.mWeight = d.power;
            e.mPower = d.power;
            break;
        }
    }
    // Nothing to carry (an empty cone, a far-off speck of a target): no emitter.
    if (isBlack(e.mPower) || !isFinite(e.mPower)) return PhotonEmitter();
    return e;
}

PhotonEmitter PhotonEmitter::forEnvironment(const Color& radiance, const PhotonTarget& target) {
    PhotonEmitter e = forDisc(radiance * (4 * Pi), Vec3(0, 0, 1), target);
    if (e.mKind == Kind::Disc) e.mKind = Kind::Environment;
    return e;
}

PhotonEmitter PhotonEmitter::forEnvironment(const Environment& env, const PhotonTarget& target) {
    if (!env.hasMap()) return forEnvironment(env.radiance(Vec3(0, 1, 0)), target);
    // Expected power: the integral of L over the sphere x the disc's area.
    PhotonEmitter e = forDisc(env.integral(), Vec3(0, 0, 1), target);
    if (e.mKind == Kind::Disc) {
        e.mKind = Kind::EnvironmentMap;
        e.mEnvironment = &env;
    }
    return e;
}

// Disc of radius R (the bounding sphere's, already 1% larger) perpendicular
// to the travel direction, centred 1.01 R upstream of the sphere's centre, so
// every photon starts outside the sphere and the beam covers all of it.
PhotonEmitter PhotonEmitter::forDisc(const Color& irradiance, const Vec3& dir, const PhotonTarget& target) {
    PhotonEmitter e;
    Vec3 center;
    float radius;
    if (targetEmpty(target) || isBlack(irradiance) || !targetSphere(target, center, radius) || !(radius > 0))
        return e;
    e.mKind = Kind::Disc;
    e.mOrigin = center;
    e.mAxis = dir;
    e.mRadius = radius;
    e.mDiscDist = 1.01f * radius;
    e.mWeight = irradiance * (Pi * radius * radius);
    e.mPower = e.mWeight;
    if (!isFinite(e.mPower)) return PhotonEmitter();
    return e;
}

Vec3 PhotonEmitter::sampleCone(float u1, float u2, float& oneMinusCos) const {
    oneMinusCos = u1 * mOneMinusCos;
    return coneDirection(mAxis, oneMinusCos, u2);
}

Vec3 PhotonEmitter::sampleDisc(const Vec3& dir, float u1, float u2) const {
    Vec3 s, t;
    coordinateSystem(dir, s, t);
    float r = mRadius * std::sqrt(u1), phi = 2 * Pi * u2;
    return mOrigin - dir * mDiscDist + s * (r * std::cos(phi)) + t * (r * std::sin(phi));
}

bool PhotonEmitter::sample(const float u[4], EmittedPhoton& out) const {
    out.power = Color(0);
    out.ray = Ray{mOrigin, mAxis};
    float t;
    switch (mKind) {
        case Kind::None:
            return false;
        case Kind::Point:
            out.ray.d = sampleCone(u[0], u[1], t);
            out.power = mWeight;
            return true;
        case Kind::Spot: {
            out.ray.d = sampleCone(u[0], u[1], t);
            // Angles as 1 - cos, not cosines: float cosines of tiny cones
            // are too coarse and would bias the mean against power().
            if (mSampleSpotCone) {
                if (mTestTargetCone && !(oneMinusCosTo(out.ray.d, mTargetAxis) < mTargetOneMinusCos)) return false;
            } else {
                t = oneMinusCosTo(out.ray.d, mSpotAxis);
            }
            float f = spotFalloff(t, mOmcCone, mOmcFalloffStart);
            if (!(f > 0)) return false;
            out.power = mWeight * f;
            return true;
        }
        case Kind::Disc:
            out.ray.o = sampleDisc(mAxis, u[0], u[1]);
            out.power = mWeight;
            return true;
        case Kind::Environment:
            out.ray.d = sampleUniformSphere(u[2], u[3]);
            out.ray.o = sampleDisc(out.ray.d, u[0], u[1]);
            out.power = mWeight;
            return true;
        case Kind::EnvironmentMap: {
            // A sky direction w by texel power; the photon travels along -w
            // and carries L(w) / pdf(w) x the disc's area.
            Vec3 w;
            float pdf;
            Color radianceOverPdf;
            if (!mEnvironment->sample(u[2], u[3], w, pdf, radianceOverPdf)) return false;
            out.ray.d = -w;
            out.ray.o = sampleDisc(out.ray.d, u[0], u[1]);
            out.power = radianceOverPdf * (Pi * mRadius * mRadius);
            return isFinite(out.power);
        }
        case Kind::Quad:
            out.ray.o = mOrigin + mU * (u[0] - 0.5f) + mV * (u[1] - 0.5f);
            out.power = mWeight;
            return true;
        case Kind::Sphere: {
            Vec3 n = sampleUniformSphere(u[0], u[1]);
            out.ray.o = mOrigin + n * mRadius;
            // Cosine-weighted about the outward normal: a Lambertian emitter.
            // cos = sqrt(1 - u) > 0, so no photon leaves tangentially.
            out.ray.d = directionAround(n, std::sqrt(1 - u[2]), u[3]);
            out.power = mWeight;
            return true;
        }
    }
    return false;
}

}  // namespace vdbmarch
