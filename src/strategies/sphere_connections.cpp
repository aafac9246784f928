#include "strategies/sphere_connections.h"
#include "strategies/sphere_trace.h"

#include <cmath>

#include "core/sampling.h"
#include "transport/surface_event.h"

namespace vdbmarch {

using namespace sphere_trace;

namespace {

// Bracketing grid (cells) over the outline's arc that x sees, and refinement steps.
constexpr int RootGrid = 24;
constexpr int RootGridNearAxis = 4;
constexpr int RootIterations = 40;


// G by forward differences from the traced path `base` of w (their error,
// O(eps) relative, is far below the noise of any estimate); `trace` is the
// pattern's tracer (trace or traceAcross). Without y (a light at
// infinity), J = d omega_exit / d omega(x) instead, the solid angle the exit
// directions spread over.
template <class Trace>
double spreading(Trace&& trace, const GlassSphere& s, const D3& x, const D3& w, const D3* y, const Traced& base) {
    // The exit ray of w perturbed by (u, v) in a tangent frame, met with the
    // plane through y perpendicular to the exit direction (or its direction).
    const D3 helper = std::fabs(w.x) > 0.9 ? D3(0, 1, 0) : D3(1, 0, 0);
    const D3 t1 = normalize(cross(w, helper)), t2 = cross(w, t1);
    const double eps = 1e-6;
    D3 q[2];
    for (int k = 0; k < 2; ++k) {
        Traced tr;
        if (!trace(s, x, normalize(w + (k == 0 ? t1 : t2) * eps), tr)) return 0;
        if (!y) {
            q[k] = tr.wo - base.wo;
            continue;
        }
        const double den = dot(tr.wo, base.wo);
        if (!(den > 0)) return 0;
        q[k] = tr.p2 + tr.wo * (dot(*y - tr.p2, base.wo) / den);
    }
    if (!y) return length(cross(q[0], q[1])) / (eps * eps);
    const D3 q0 = base.p2 + base.wo * dot(*y - base.p2, base.wo);
    return length(cross(q[0] - q0, q[1] - q0)) / (eps * eps);
}

SphereConnection toConnection(const D3& w, const Traced& tr, double G, int refractions) {
    SphereConnection c;
    c.wi = w.f();
    c.p1 = tr.p1.f();
    c.p2 = tr.p2.f();
    c.wo = tr.wo.f();
    c.transmission = float(tr.transmission);
    c.spreading = G;
    c.refractions = refractions;
    return c;
}

// The one-refraction path from x towards the point of the sphere's outline
// at angle `a` in the plane (e1, e2) through its centre: the direction w
// and the path traced across the surface.
bool traceFromOutline(const GlassSphere& s, const D3& x, const D3& e1, const D3& e2, double a, D3& w, Traced& tr) {
    const D3 p = D3(s.center) + (e1 * std::cos(a) + e2 * std::sin(a)) * double(s.radius);
    w = normalize(p - x);
    return traceAcross(s, x, w, tr);
}


// In the plane of the ball's outline (centre at the origin, radius R), the
// ray from (dx, 0) to the outline point R (ca, sa), refracted into the
// ball: its incident and transmitted cosines and its direction inside.
// False where the point is on the outline's far side.
struct PlaneEntry {
    double cosI, cosT, d1x, d1y;
};
inline bool enterInPlane(double R, double dx, double eta, double ca, double sa, PlaneEntry& e) {
    const double px = R * ca - dx, py = R * sa;
    const double inv = 1 / std::sqrt(px * px + py * py);
    const double d0x = px * inv, d0y = py * inv;
    e.cosI = -(d0x * ca + d0y * sa);
    if (!(e.cosI > 0)) return false;
    const double sin2T = (1 - e.cosI * e.cosI) / (eta * eta);
    e.cosT = std::sqrt(1 - sin2T);
    const double k1 = e.cosI / eta - e.cosT;
    e.d1x = d0x / eta + ca * k1;
    e.d1y = d0y / eta + sa * k1;
    return true;
}

// The entered ray continued through the ball and out of it: the exit point
// and direction. In closed form: inside, the angle to the normal is theta_t
// at both ends, so the exit's transmitted cosine is cos theta_i.
struct PlaneExit {
    double p2x, p2y, d2x, d2y;
};
inline bool exitInPlane(double R, double eta, double ca, double sa, const PlaneEntry& in, PlaneExit& e) {
    const double chord = -2 * R * (ca * in.d1x + sa * in.d1y);
    if (!(chord > 0)) return false;
    e.p2x = R * ca + in.d1x * chord;
    e.p2y = R * sa + in.d1y * chord;
    const double k2 = (eta * in.cosT - in.cosI) / R;  // n2 = p2 / R
    e.d2x = eta * in.d1x - e.p2x * k2;
    e.d2y = eta * in.d1y - e.p2y * k2;
    return true;
}

// The unit e2 perpendicular to unit e1 in the plane of e1 and v, and the
// length of v's part along it; false where that part is not above `tol` (v
// on e1's axis), e2 then any perpendicular.
bool planeAround(const D3& e1, const D3& v, double tol, D3& e2, double& vPerp) {
    const D3 p = v - e1 * dot(v, e1);
    vPerp = length(p);
    if (vPerp > tol) {
        e2 = p * (1 / vPerp);
        return true;
    }
    e2 = normalize(cross(e1, std::fabs(e1.x) > 0.9 ? D3(0, 1, 0) : D3(1, 0, 0)));
    return false;
}

// h on the outline at angle a: which side of the ray after the glass the
// far end lies (0 on a root), and how far ahead of the ray's start.
struct ArcEval {
    bool ok = false;
    double h = 0, ahead = 0;
};

// Where the point (i1, i2) lies from the ray from (px, py) along (dx, dy):
// h its side (0 on the ray), ahead how far along it.
inline ArcEval pointFromRay(double px, double py, double dx, double dy, double i1, double i2) {
    ArcEval e;
    const double tx = i1 - px, ty = i2 - py;
    e.ok = true;
    e.h = dx * ty - dy * tx;
    e.ahead = dx * tx + dy * ty;
    return e;
}

// The roots of h over the arc |a| < aMax of the ball's outline, h given as
// evalCS(cos a, sin a); keep(a, h(a)) takes each. A grid brackets them and
// false position refines them; a thorough solve also takes the arc's ends,
// pairs between grid points and a finer grid where `nearAxis`.
template <class EvalCS, class Keep>
void solveOnArc(double aMax, bool thorough, bool nearAxis, EvalCS&& evalCS, Keep&& keep) {
    auto eval = [&](double a) { return evalCS(std::cos(a), std::sin(a)); };
    // The grid's angles by rotation: one sincos for the whole grid. Its
    // points are the cells' middles; a thorough solve also takes the arc's
    // ends, just inside the outline (where the ray grazes the ball and no
    // refraction is defined), and where x, the centre and y are nearly in
    // line (within about 6 degrees), where the rays through the lens's
    // middle cross near its axis and up to three roots share a few degrees
    // of the arc, cells RootGridNearAxis times finer.
    const int cells = thorough && nearAxis ? RootGrid * RootGridNearAxis : RootGrid;
    const int N = thorough ? cells + 1 : cells;
    const double inset = thorough ? 1e-5 * aMax : 0.0;
    const double step = (2 * aMax - 2 * inset) / cells, a0 = -aMax + inset + (thorough ? 0.0 : 0.5 * step);
    const double cStep = std::cos(step), sStep = std::sin(step);
    ArcEval grid[RootGrid * RootGridNearAxis + 1];
    double ca = std::cos(a0), sa = std::sin(a0);
    for (int k = 0; k < N; ++k) {
        grid[k] = evalCS(ca, sa);
        const double cNext = ca * cStep - sa * sStep;
        sa = sa * cStep + ca * sStep;
        ca = cNext;
    }
    auto angle = [&](int k) { return a0 + k * step; };
    // The root in [lo, hi], where h changes sign, by false position with the
    // Illinois modification (the bracket stays, convergence is
    // superlinear).
    auto refine = [&](double lo, double hi, double hLo, double hHi) {
        int side = 0;
        double root = lo;
        for (int i = 0; i < RootIterations; ++i) {
            root = (lo * hHi - hi * hLo) / (hHi - hLo);
            if (!(root > std::min(lo, hi) && root < std::max(lo, hi))) root = 0.5 * (lo + hi);
            const ArcEval m = eval(root);
            if (!m.ok) break;
            if (std::fabs(m.h) < 1e-12 * (1 + std::fabs(m.ahead)) || std::fabs(hi - lo) < 1e-13) break;
            if ((m.h < 0) == (hLo < 0)) {
                lo = root;
                hLo = m.h;
                if (side == -1) hHi *= 0.5;
                side = -1;
            } else {
                hi = root;
                hHi = m.h;
                if (side == 1) hLo *= 0.5;
                side = 1;
            }
        }
        keep(root, eval(root));
    };
    for (int k = 1; k < N; ++k) {
        const ArcEval &prev = grid[k - 1], &cur = grid[k];
        if (!prev.ok || !cur.ok) continue;
        if ((prev.h < 0) != (cur.h < 0)) {
            refine(angle(k - 1), angle(k), prev.h, cur.h);
            continue;
        }
        // Two roots closer than the grid's step leave no sign change: near
        // a fold of the caustic, where two paths from x merge, they lie on
        // either side of an extremum of h. Where |h| has a local minimum
        // at a grid point with the same sign on both sides, find the
        // extremum (golden section) and, if h changes sign there, both roots.
        if (!thorough || k + 1 >= N || !grid[k + 1].ok || (grid[k + 1].h < 0) != (cur.h < 0)) continue;
        if (!(std::fabs(cur.h) <= std::fabs(prev.h) && std::fabs(cur.h) < std::fabs(grid[k + 1].h))) continue;
        const double sign = cur.h < 0 ? -1 : 1;
        double lo = angle(k - 1), hi = angle(k + 1);
        const double g = 0.5 * (std::sqrt(5.0) - 1);
        double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
        ArcEval e1 = eval(m1), e2 = eval(m2);
        // To a thousandth of the step: a pair closer than that lies within
        // about (1e-3 step)^2 of a fold (their gap grows as the square root
        // of the distance), a vanishing share of the light.
        for (int i = 0; i < RootIterations && e1.ok && e2.ok && hi - lo > 1e-3 * step; ++i) {
            if (sign * e1.h < sign * e2.h) {
                hi = m2;
                m2 = m1;
                e2 = e1;
                m1 = hi - g * (hi - lo);
                e1 = eval(m1);
            } else {
                lo = m1;
                m1 = m2;
                e1 = e2;
                m2 = lo + g * (hi - lo);
                e2 = eval(m2);
            }
            if ((e1.ok && (e1.h < 0) != (cur.h < 0)) || (e2.ok && (e2.h < 0) != (cur.h < 0))) break;
        }
        const bool firstFlips = e1.ok && (e1.h < 0) != (cur.h < 0);
        const double am = firstFlips ? m1 : m2;
        const ArcEval em = firstFlips ? e1 : e2;
        if (!em.ok) continue;
        if ((em.h < 0) == (cur.h < 0)) {
            // An extremum that misses y by less than 1e-7 of the distance:
            // y lies on the fold itself, within rounding of its float
            // coordinates, where the pair merges into one path.
            if (std::fabs(em.h) < 1e-7 * em.ahead) keep(am, em);
            continue;
        }
        refine(angle(k - 1), am, prev.h, em.h);
        refine(am, angle(k + 1), em.h, grid[k + 1].h);
    }
}

}  // namespace

bool traceThroughSphere(const GlassSphere& s, const Vec3& x, const Vec3& w, SphereConnection& out) {
    Traced tr;
    const D3 wd = normalize(D3(w));
    if (!trace(s, D3(x), wd, tr)) return false;
    out = toConnection(wd, tr, 0, 2);
    return true;
}

bool traceAcrossSphere(const GlassSphere& s, const Vec3& x, const Vec3& w, SphereConnection& out) {
    Traced tr;
    const D3 wd = normalize(D3(w));
    if (!traceAcross(s, D3(x), wd, tr)) return false;
    out = toConnection(wd, tr, 0, 1);
    return true;
}

int connectThroughSphere(const GlassSphere& s, const Vec3& xf, const Vec3& yf, SphereConnection out[MaxSphereConnections],
                         bool thorough) {
    const D3 c(s.center), x(xf), y(yf);
    const double R = s.radius;
    const D3 cx = x - c;
    const double dx = length(cx);
    if (!(dx > R * (1 + 1e-6))) return 0;
    // The plane of x, y and the centre: e1 towards x, e2 towards y's side.
    const D3 e1 = cx * (1 / dx);
    const D3 cy = y - c;
    D3 e2;
    double yh;
    if (!planeAround(e1, cy, 1e-9 * (R + length(cy)), e2, yh)) return 0;  // y on the axis: a ring of paths, measure zero
    // Directions to the outline point at angle a from e1; the visible arc is
    // |a| < acos(R / dx).
    const double aMax = std::acos(R / dx);
    auto direction = [&](double a) {
        return normalize(c + (e1 * std::cos(a) + e2 * std::sin(a)) * R - x);
    };
    // In the plane, with the centre at the origin: x = (dx, 0), y = (y1, y2).
    const double y1 = dot(cy, e1), y2 = yh, eta = s.ior;
    // h(a): which side of the exit ray y lies (0 on a root), and how far
    // ahead of the exit point, from the outline point (cos a, sin a) R.
    auto evalCS = [&](double ca, double sa) {
        PlaneEntry in;
        PlaneExit out;
        if (!enterInPlane(R, dx, eta, ca, sa, in) || !exitInPlane(R, eta, ca, sa, in, out)) return ArcEval{};
        return pointFromRay(out.p2x, out.p2y, out.d2x, out.d2y, y1, y2);
    };
    int n = 0;
    solveOnArc(aMax, thorough, yh < 0.1 * length(cy), evalCS, [&](double root, const ArcEval& r) {
        // A sign change behind the exit point is no connection.
        Traced tr;
        const D3 w = direction(root);
        if (n < MaxSphereConnections && r.ok && r.ahead > 0 && trace(s, x, w, tr) &&
            std::fabs(r.h) < 1e-6 * length(y - tr.p2)) {
            // 0 where a ray beside it misses the ball (grazing, where the
            // Fresnel transmission vanishes): no usable connection.
            const double G = spreading(trace, s, x, w, &y, tr);
            if (G > 0 || !thorough) out[n++] = toConnection(w, tr, G, 2);
        }
    });
    return n;
}

int connectAcrossSphere(const GlassSphere& s, const Vec3& xf, const Vec3& yf, SphereConnection out[MaxSphereConnections],
                        bool thorough) {
    const D3 c(s.center), x(xf), y(yf);
    const double R = s.radius;
    // The roots are found from the end outside, o, towards the end inside, i.
    const double dx = length(x - c), dy = length(y - c);
    const bool xInside = dx < R;
    const D3 o = xInside ? y : x, in = xInside ? x : y;
    const double dO = xInside ? dy : dx, dI = xInside ? dx : dy;
    if (!(dO > R * (1 + 1e-6)) || !(dI < R * (1 - 1e-6))) return 0;
    const D3 e1 = (o - c) * (1 / dO);
    const D3 ci = in - c;
    // On the axis through o and the centre, the one path is the axis itself
    // (any e2 will do); off it, the plane of o, i and the centre.
    D3 e2;
    double ih;
    const bool onAxis = !planeAround(e1, ci, 1e-9 * R, e2, ih);
    const double aMax = std::acos(R / dO);
    const double i1 = dot(ci, e1), i2 = onAxis ? 0.0 : ih, eta = s.ior;
    // h(a): which side of the refracted ray i lies, from the outline point
    // (cos a, sin a) R, o at (dO, 0).
    auto evalCS = [&](double ca, double sa) {
        PlaneEntry in;
        if (!enterInPlane(R, dO, eta, ca, sa, in)) return ArcEval{};
        return pointFromRay(R * ca, R * sa, in.d1x, in.d1y, i1, i2);
    };
    int n = 0;
    auto keep = [&](double root, const ArcEval& r) {
        if (!(n < MaxSphereConnections && r.ok && r.ahead > 0)) return;
        // The path from x, traced across the surface, must pass through y.
        D3 w;
        Traced tr;
        if (!traceFromOutline(s, x, e1, e2, root, w, tr)) return;
        const D3 toY = y - tr.p2;
        if (!(dot(toY, tr.wo) > 0) || !(length(cross(tr.wo, toY)) < 1e-6 * length(toY))) return;
        const double G = spreading(traceAcross, s, x, w, &y, tr);
        if (G > 0 || !thorough) out[n++] = toConnection(w, tr, G, 1);
    };
    if (onAxis) keep(0.0, evalCS(1.0, 0.0));
    else solveOnArc(aMax, thorough, ih < 0.1 * length(ci), evalCS, keep);
    return n;
}

int connectThroughSphereToward(const GlassSphere& s, const Vec3& xf, const Vec3& wLf,
                               SphereConnection out[MaxSphereConnections]) {
    const D3 c(s.center), x(xf), L = normalize(D3(wLf));
    const double R = s.radius;
    const double dx = length(x - c);
    if (!(dx > R * (1 + 1e-6))) return 0;
    // The plane of x, the centre and the light's direction.
    const D3 e1 = (x - c) * (1 / dx);
    D3 e2;
    double lh;
    if (!planeAround(e1, L, 1e-9, e2, lh)) return 0;  // x on the axis through the centre: a ring of paths, measure zero
    const double l1 = dot(L, e1), l2 = lh, eta = s.ior;
    const double aMax = std::acos(R / dx);
    // h(a): the sine of the angle from the exit direction to the light's.
    auto evalCS = [&](double ca, double sa) {
        ArcEval e;
        PlaneEntry in;
        PlaneExit out;
        if (!enterInPlane(R, dx, eta, ca, sa, in) || !exitInPlane(R, eta, ca, sa, in, out)) return e;
        e.ok = true;
        e.h = out.d2x * l2 - out.d2y * l1;
        e.ahead = out.d2x * l1 + out.d2y * l2;
        return e;
    };
    int n = 0;
    solveOnArc(aMax, true, lh < 0.1, evalCS, [&](double root, const ArcEval& r) {
        if (!(n < MaxSphereConnections && r.ok && r.ahead > 0)) return;
        const D3 w = normalize(c + (e1 * std::cos(root) + e2 * std::sin(root)) * R - x);
        Traced tr;
        if (!trace(s, x, w, tr) || !(dot(tr.wo, L) > 0) || !(length(cross(tr.wo, L)) < 1e-6)) return;
        const double J = spreading(trace, s, x, w, nullptr, tr);
        if (J > 0) out[n++] = toConnection(w, tr, J, 2);
    });
    return n;
}

int connectAcrossSphereToward(const GlassSphere& s, const Vec3& xf, const Vec3& wLf,
                              SphereConnection out[MaxSphereConnections]) {
    const D3 c(s.center), x(xf), L = normalize(D3(wLf));
    const double R = s.radius;
    const D3 cx = x - c;
    if (!(length(cx) < R * (1 - 1e-6))) return 0;
    // The light's rays enter on the half of the ball facing it: the entry
    // point at angle a from the direction towards the light, in the plane
    // of that direction, the centre and x.
    const D3 e1 = L;
    D3 e2;
    double xh;
    const bool onAxis = !planeAround(e1, cx, 1e-9 * R, e2, xh);
    const double i1 = dot(cx, e1), i2 = onAxis ? 0.0 : xh, eta = s.ior;
    // h(a): which side of the refracted ray x lies; the ray arrives along -e1.
    auto evalCS = [&](double ca, double sa) {
        const double cosI = ca;
        if (!(cosI > 0)) return ArcEval{};
        const double cosT = std::sqrt(1 - (1 - cosI * cosI) / (eta * eta));
        const double k1 = cosI / eta - cosT;
        return pointFromRay(R * ca, R * sa, -1 / eta + ca * k1, sa * k1, i1, i2);
    };
    int n = 0;
    auto keep = [&](double root, const ArcEval& r) {
        if (!(n < MaxSphereConnections && r.ok && r.ahead > 0)) return;
        D3 w;
        Traced tr;
        if (!traceFromOutline(s, x, e1, e2, root, w, tr) || !(dot(tr.wo, L) > 0) ||
            !(length(cross(tr.wo, L)) < 1e-6))
            return;
        const double J = spreading(traceAcross, s, x, w, nullptr, tr);
        if (J > 0) out[n++] = toConnection(w, tr, J, 1);
    };
    if (onAxis) keep(0.0, evalCS(1.0, 0.0));
    else solveOnArc(0.5 * double(Pi), true, xh < 0.1 * length(cx), evalCS, keep);
    return n;
}


}  // namespace vdbmarch
