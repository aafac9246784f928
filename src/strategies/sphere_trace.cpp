#include "strategies/sphere_trace.h"

#include <algorithm>

namespace vdbmarch::sphere_trace {

// Refraction of unit d at unit normal n facing the arriving ray, eta =
// n_transmitted / n_incident; F the Fresnel reflectance (core/sampling.h's
// formula). False on total internal reflection.
bool refract(const D3& d, const D3& n, double eta, D3& t, double& F) {
    const double cosI = std::min(1.0, std::max(0.0, -dot(d, n)));
    const double sin2T = (1 - cosI * cosI) / (eta * eta);
    if (sin2T >= 1) return false;
    const double cosT = std::sqrt(1 - sin2T);
    const double rPar = (eta * cosI - cosT) / (eta * cosI + cosT);
    const double rPerp = (cosI - eta * cosT) / (cosI + eta * cosT);
    F = 0.5 * (rPar * rPar + rPerp * rPerp);
    t = normalize(d * (1 / eta) + n * (cosI / eta - cosT));
    return true;
}

// The ray x + t w (w unit) against sphere s: with oc = x - c, the roots of
// t^2 + 2 b t + cc = 0 are -b -+ sqrt(disc).
struct SphereRoots {
    D3 c;
    double R, b = 0, cc = 0, disc = 0;
    SphereRoots(const GlassSphere& s, const D3& x, const D3& w) : c(s.center), R(s.radius) {
        const D3 oc = x - c;
        b = dot(w, oc), cc = dot(oc, oc) - R * R, disc = b * b - cc;
    }
};

// The ray x + t w into sphere s and out again.
bool trace(const GlassSphere& s, const D3& x, const D3& w, Traced& out) {
    const SphereRoots q(s, x, w);
    const D3& c = q.c;
    const double R = q.R, b = q.b, cc = q.cc, disc = q.disc;
    if (!(cc > 0) || !(disc > 0) || !(b < 0)) return false;  // inside, missed, or behind
    const double t1 = -b - std::sqrt(disc);
    out.p1 = x + w * t1;
    const D3 n1 = (out.p1 - c) * (1 / R);
    D3 d1;
    double F1, F2;
    if (!refract(w, n1, s.ior, d1, F1)) return false;
    // The chord along d1 from p1 (|p1 - c| = R).
    const double chord = -2 * dot(out.p1 - c, d1);
    if (!(chord > 0)) return false;
    out.p2 = out.p1 + d1 * chord;
    const D3 n2 = (out.p2 - c) * (1 / R);
    if (!refract(d1, n2 * -1.0, 1 / double(s.ior), out.wo, F2)) return false;
    out.transmission = (1 - F1) * (1 - F2);
    return true;
}

// The ray x + t w across the surface of sphere s once: into it from
// outside, or out of it from inside.
bool traceAcross(const GlassSphere& s, const D3& x, const D3& w, Traced& out) {
    const SphereRoots q(s, x, w);
    const D3& c = q.c;
    const double R = q.R, b = q.b, cc = q.cc, disc = q.disc;
    if (!(disc > 0)) return false;
    const bool entering = cc > 0;
    if (entering && !(b < 0)) return false;  // the ball behind x
    const double t = entering ? -b - std::sqrt(disc) : -b + std::sqrt(disc);
    out.p1 = out.p2 = x + w * t;
    const D3 n = (out.p1 - c) * (1 / R);  // outwards
    double F;
    if (!(entering ? refract(w, n, s.ior, out.wo, F) : refract(w, n * -1.0, 1 / double(s.ior), out.wo, F)))
        return false;  // total internal reflection
    out.transmission = 1 - F;
    return true;
}

}  // namespace vdbmarch::sphere_trace
