#include "scene/lights/light_kinds.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace vdbmarch {

CollimatedQuadLight::CollimatedQuadLight(const LightDesc& d) : Light(d) {
    mQuad = {d.center, d.u, d.v, d.direction};
    // Dual basis so a point's (a, b) in h = center + a u + b v comes
    // from two dot products even when u and v are not orthogonal.
    mQuadNormal = cross(d.u, d.v);
    float n2 = lengthSquared(mQuadNormal);
    mDualU = cross(d.v, mQuadNormal) / n2;
    mDualV = cross(mQuadNormal, d.u) / n2;
}

bool CollimatedQuadLight::sample(const Vec3& x, float u1, float u2, LightSample& s) const {
    // Follow the beam backwards to the emitting plane.
    float denom = dot(-mDesc.direction, mQuadNormal);
    float t = dot(mDesc.center - x, mQuadNormal) / denom;
    if (!(t > 0)) return false;
    Vec3 h = x - mDesc.direction * t - mDesc.center;
    float a = dot(h, mDualU), b = dot(h, mDualV);
    if (std::fabs(a) > 0.5f || std::fabs(b) > 0.5f) return false;
    s.wi = -mDesc.direction;
    s.dist = t;
    s.L = mDesc.irradiance;
    return true;
}

namespace {

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


// Every photon starts uniformly on the quad and carries E times the quad's
// area seen along the beam.
class QuadEmission final : public LightEmission {
public:
    QuadEmission(const LightDesc& d, const Vec3& dir, float projArea) : mU(d.u), mV(d.v) {
        mOrigin = d.center;
        mAxis = dir;
        mWeight = d.irradiance * projArea;
        mPower = mWeight;
    }
    bool sample(const float u[4], EmittedPhoton& out) const override {
        startPhoton(out);
        out.ray.o = mOrigin + mU * (u[0] - 0.5f) + mV * (u[1] - 0.5f);
        out.power = mWeight;
        return true;
    }

private:
    Vec3 mU, mV;  // the quad's edge vectors
};

}  // namespace

std::unique_ptr<LightEmission> CollimatedQuadLight::emissionTowards(const PhotonTarget& target) const {
    const LightDesc& d = mDesc;
    Vec3 dir = unitOr(d.direction, Vec3(0, -1, 0));
    // sample() gives irradiance perpendicular to the beam: the
    // flux through the quad is E times its area seen along the beam.
    float projArea = std::fabs(dot(cross(d.u, d.v), dir));
    if (isBlack(d.irradiance) || !(projArea > 0) || !std::isfinite(projArea)) return nullptr;
    if (!target.unbounded && finiteBox(target.bounds) && beamMissesBox(d.center, d.u, d.v, dir, target.bounds))
        return nullptr;
    return std::make_unique<QuadEmission>(d, dir, projArea);
}

}  // namespace vdbmarch
