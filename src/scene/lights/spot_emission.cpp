// A spot light's photon emission: uniform in the narrower of the spot cone
// and the cone that subtends the target, weighted by intensity * falloff /
// pdf, zero outside the other cone; its power is the falloff's integral over
// their overlap.
#include <algorithm>
#include <cmath>
#include <vector>

#include "scene/lights/light_kinds.h"

namespace vdbmarch {

namespace {

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

class SpotEmission final : public ConeEmission {
public:
    // Null when the cone misses the target.
    static std::unique_ptr<SpotEmission> make(const LightDesc& d, const SpotCone& cone, const PhotonTarget& target);
    bool sample(const float u[4], EmittedPhoton& out) const override;

private:
    // The falloff as SpotLight::sample evaluates it (its cosines as 1 -
    // cos), and the cone not sampled (directions outside it carry nothing).
    Vec3 mSpotAxis;
    float mOmcCone = 2, mOmcFalloffStart = 2;
    bool mSampleSpotCone = true;  // else the target cone is sampled
    bool mTestTargetCone = false;
    Vec3 mTargetAxis;
    float mTargetOneMinusCos = 2;
};

std::unique_ptr<SpotEmission> SpotEmission::make(const LightDesc& d, const SpotCone& cone, const PhotonTarget& target) {
    // The light's own float cosines, so the cone edge matches exactly.
    const float cc = cone.cosCone, cf = cone.cosFalloffStart, spotOmc = cone.omcCone;
    auto e = std::make_unique<SpotEmission>();
    e->mOrigin = d.position;
    e->mSpotAxis = unitOr(d.direction, Vec3(0, -1, 0));
    e->mOmcCone = spotOmc;
    e->mOmcFalloffStart = cone.omcFalloffStart;
    // Closed form over the whole spot cone: the smoothstep averages 1/2.
    double cHard = std::max(cf, cc);
    double spotIntegral = 2 * PiD * ((1 - cHard) + 0.5 * (cHard - double(cc)));
    e->mAxis = e->mSpotAxis;
    e->mOneMinusCos = spotOmc;
    double integral = spotIntegral;
    TargetCone c;
    if (targetCone(target, d.position, c)) {
        Vec3 a = e->mSpotAxis;
        double beta = std::atan2(double(length(cross(a, c.axis))), double(dot(a, c.axis)));
        double thetaS = std::acos(double(cc));
        if (beta >= thetaS + c.halfAngle) return nullptr;  // the cone misses the target
        if (beta + thetaS > c.halfAngle) {
            // Partial overlap: sample the narrower cone, zero outside the other.
            e->mSampleSpotCone = spotOmc <= c.oneMinusCos;
            e->mTestTargetCone = e->mSampleSpotCone;
            e->mTargetAxis = c.axis;
            e->mTargetOneMinusCos = c.oneMinusCos;
            if (!e->mSampleSpotCone) {
                e->mAxis = c.axis;
                e->mOneMinusCos = c.oneMinusCos;
            }
            integral = overlapIntegral({beta, cc, cf, c.halfAngle, e->mSampleSpotCone});
        }
    }
    e->mWeight = d.intensity * (2 * Pi * e->mOneMinusCos);
    e->mPower = d.intensity * float(integral);
    return e;
}

bool SpotEmission::sample(const float u[4], EmittedPhoton& out) const {
    startPhoton(out);
    float t;
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

}  // namespace

std::unique_ptr<LightEmission> SpotLight::emissionTowards(const PhotonTarget& target) const {
    if (isBlack(mDesc.intensity) || !(mCone.omcCone > 0)) return nullptr;
    return SpotEmission::make(mDesc, mCone, target);
}

}  // namespace vdbmarch
