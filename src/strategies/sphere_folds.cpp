#include "strategies/sphere_connections.h"
#include "strategies/sphere_trace.h"

namespace vdbmarch {

using namespace sphere_trace;

namespace {

// The family of a point-like or parallel light's rays through sphere s in
// one plane (a, e) through the axis: from the light's point at angle u off
// the axis, or parallel to the axis at height u; and the envelope of their
// exit rays, the caustic's fold.
struct FoldFamily {
    D3 c, a, e, source;
    bool parallel = false, valid = false;
    double uMax = 0;
    const GlassSphere* s = nullptr;

    FoldFamily(const GlassSphere& sphere, const Light& light) : c(sphere.center), s(&sphere) {
        parallel = light.isDelta() && !light.isPointLike();
        if (!parallel && !light.isPointLike()) return;
        const double R = sphere.radius;
        if (parallel) {
            a = normalize(D3(light.desc().direction));
            uMax = R;
        } else {
            source = D3(light.desc().position);
            const double D = length(c - source);
            if (!(D > R * (1 + 1e-6))) return;
            a = (c - source) * (1 / D);
            uMax = std::asin(R / D);
        }
        const D3 helper = std::fabs(a.x) > 0.9 ? D3(0, 1, 0) : D3(1, 0, 0);
        e = normalize(cross(a, helper));
        valid = true;
    }

    bool exitRay(double u, double& pz, double& pr, double& uz, double& ur) const {
        const D3 x = parallel ? c - a * (2 * double(s->radius)) + e * u : source;
        const D3 w = parallel ? a : a * std::cos(u) + e * std::sin(u);
        Traced tr;
        if (!trace(*s, x, w, tr)) return false;
        pz = dot(tr.p2 - c, a);
        pr = dot(tr.p2 - c, e);
        uz = dot(tr.wo, a);
        ur = dot(tr.wo, e);
        return true;
    }

    // Where exit rays u and u + du meet, P + lambda U with
    // (P' + lambda U') x U = 0 (2D cross products, central differences);
    // false where they meet before the exit (no fold outside) or u's ray
    // misses the ball.
    bool point(double u, double& z, double& rho) const {
        const double h = uMax * 1e-6;
        double pz, pr, uz, ur, pz0, pr0, uz0, ur0, pz1, pr1, uz1, ur1;
        if (!exitRay(u, pz, pr, uz, ur) || !exitRay(u - h, pz0, pr0, uz0, ur0) || !exitRay(u + h, pz1, pr1, uz1, ur1))
            return false;
        const double dpz = (pz1 - pz0) / (2 * h), dpr = (pr1 - pr0) / (2 * h);
        const double duz = (uz1 - uz0) / (2 * h), dur = (ur1 - ur0) / (2 * h);
        const double den = duz * ur - dur * uz;
        const double lambda = den != 0 ? -(dpz * ur - dpr * uz) / den : -1.0;
        if (!(lambda > 0) || !std::isfinite(lambda)) return false;
        z = pz + lambda * uz;
        rho = std::fabs(pr + lambda * ur);
        return true;
    }
};

}  // namespace

bool causticFold(const GlassSphere& s, const Light& light, CausticFold& out) {
    const FoldFamily family(s, light);
    if (!family.valid) return false;
    out = CausticFold{s.center, family.a.f(), {}, {}, {}};
    constexpr int Samples = 256;
    for (int i = 0; i < Samples; ++i) {
        const double u = family.uMax * (double(i) + 0.5) / Samples * 0.999;
        double z, rho;
        if (!family.point(u, z, rho)) {
            if (!out.z.empty()) break;  // one connected piece of curve: the first gap after it ends it
            continue;
        }
        out.z.push_back(float(z));
        out.rho.push_back(float(rho));
        out.u.push_back(u);
    }
    return out.z.size() >= 2;
}

bool causticFoldPoint(const GlassSphere& s, const Light& light, double u, double& z, double& rho) {
    const FoldFamily family(s, light);
    return family.valid && family.point(u, z, rho);
}

}  // namespace vdbmarch
