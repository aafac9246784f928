#include "transport/sphere_caustics.h"

#include <cmath>

#include "core/sampling.h"
#include "transport/surface_event.h"

namespace vdbmarch {

namespace {

// Double-precision vectors: the roots and the spreading's central
// differences need more digits than float keeps.
struct D3 {
    double x = 0, y = 0, z = 0;
    D3() = default;
    D3(double a, double b, double c) : x(a), y(b), z(c) {}
    explicit D3(const Vec3& v) : x(v.x), y(v.y), z(v.z) {}
    D3 operator+(const D3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    D3 operator-(const D3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    D3 operator*(double s) const { return {x * s, y * s, z * s}; }
    Vec3 f() const { return Vec3(float(x), float(y), float(z)); }
};
double dot(const D3& a, const D3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross(const D3& a, const D3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double length(const D3& a) { return std::sqrt(dot(a, a)); }
D3 normalize(const D3& a) { return a * (1 / length(a)); }

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

struct Traced {
    D3 p1, p2, wo;
    double transmission = 0;
};

// The ray x + t w into sphere s and out again.
bool trace(const GlassSphere& s, const D3& x, const D3& w, Traced& out) {
    const D3 c(s.center);
    const double R = s.radius;
    const D3 oc = x - c;
    const double b = dot(w, oc), cc = dot(oc, oc) - R * R;
    const double disc = b * b - cc;
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

// Bracketing grid (cells) over the outline's arc that x sees, and refinement steps.
constexpr int RootGrid = 24;
constexpr int RootGridNearAxis = 4;
constexpr int RootIterations = 40;

// A direction from x matches a root when within about 1.4e-3 rad of it.
constexpr double RootMatchCos = 1 - 1e-6;

// G by forward differences from the traced path `base` of w (their error,
// O(eps) relative, is far below the noise of any estimate).
double spreading(const GlassSphere& s, const D3& x, const D3& w, const D3& y, const Traced& base) {
    // The exit ray of w perturbed by (u, v) in a tangent frame, met with the
    // plane through y perpendicular to the exit direction.
    const D3 helper = std::fabs(w.x) > 0.9 ? D3(0, 1, 0) : D3(1, 0, 0);
    const D3 t1 = normalize(cross(w, helper)), t2 = cross(w, t1);
    const double eps = 1e-6;
    D3 q[2];
    for (int k = 0; k < 2; ++k) {
        Traced tr;
        if (!trace(s, x, normalize(w + (k == 0 ? t1 : t2) * eps), tr)) return 0;
        const double den = dot(tr.wo, base.wo);
        if (!(den > 0)) return 0;
        q[k] = tr.p2 + tr.wo * (dot(y - tr.p2, base.wo) / den);
    }
    const D3 q0 = base.p2 + base.wo * dot(y - base.p2, base.wo);
    return length(cross(q[0] - q0, q[1] - q0)) / (eps * eps);
}

SphereConnection toConnection(const D3& w, const Traced& tr, double G) {
    SphereConnection c;
    c.wi = w.f();
    c.p1 = tr.p1.f();
    c.p2 = tr.p2.f();
    c.wo = tr.wo.f();
    c.transmission = float(tr.transmission);
    c.spreading = G;
    return c;
}

// The glass sphere a sphere light can be reached through: outside it.
bool lightOutside(const GlassSphere& s, const Light& l) {
    return l.isSphere() && length(l.desc().position - s.center) > s.radius + l.desc().radius;
}

}  // namespace

bool traceThroughSphere(const GlassSphere& s, const Vec3& x, const Vec3& w, SphereConnection& out) {
    Traced tr;
    const D3 wd = normalize(D3(w));
    if (!trace(s, D3(x), wd, tr)) return false;
    out = toConnection(wd, tr, 0);
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
    const D3 yPerp = cy - e1 * dot(cy, e1);
    const double yh = length(yPerp);
    if (!(yh > 1e-9 * (R + length(cy)))) return 0;  // y on the axis: a ring of paths, measure zero
    const D3 e2 = yPerp * (1 / yh);
    // Directions to the outline point at angle a from e1; the visible arc is
    // |a| < acos(R / dx).
    const double aMax = std::acos(R / dx);
    auto direction = [&](double a) {
        return normalize(c + (e1 * std::cos(a) + e2 * std::sin(a)) * R - x);
    };
    // In the plane, with the centre at the origin: x = (dx, 0), y = (y1, y2).
    const double y1 = dot(cy, e1), y2 = yh, eta = s.ior;
    // h(a): which side of the exit ray y lies (0 on a root), and how far
    // ahead of the exit point, from the outline point (cos a, sin a) R. The
    // two refractions in closed form: inside, the angle to the normal is
    // theta_t at both ends, so the exit's transmitted cosine is cos theta_i.
    struct Eval {
        bool ok = false;
        double h = 0, ahead = 0;
    };
    auto evalCS = [&](double ca, double sa) {
        Eval e;
        const double px = R * ca - dx, py = R * sa;  // p1 - x
        const double inv = 1 / std::sqrt(px * px + py * py);
        const double d0x = px * inv, d0y = py * inv;
        const double cosI = -(d0x * ca + d0y * sa);
        if (!(cosI > 0)) return e;
        const double sin2T = (1 - cosI * cosI) / (eta * eta);
        const double cosT = std::sqrt(1 - sin2T);
        const double k1 = cosI / eta - cosT;
        const double d1x = d0x / eta + ca * k1, d1y = d0y / eta + sa * k1;
        const double chord = -2 * R * (ca * d1x + sa * d1y);
        if (!(chord > 0)) return e;
        const double p2x = R * ca + d1x * chord, p2y = R * sa + d1y * chord;
        const double k2 = (eta * cosT - cosI) / R;  // n2 = p2 / R
        const double d2x = eta * d1x - p2x * k2, d2y = eta * d1y - p2y * k2;
        const double tx = y1 - p2x, ty = y2 - p2y;
        e.ok = true;
        e.h = d2x * ty - d2y * tx;
        e.ahead = d2x * tx + d2y * ty;
        return e;
    };
    auto eval = [&](double a) { return evalCS(std::cos(a), std::sin(a)); };
    // The grid's angles by rotation: one sincos for the whole grid. Its
    // points are the cells' middles; a thorough solve also takes the arc's
    // ends, just inside the outline (where the ray grazes the ball and no
    // refraction is defined), and where x, the centre and y are nearly in
    // line (within about 6 degrees), where the rays through the lens's
    // middle cross near its axis and up to three roots share a few degrees
    // of the arc, cells RootGridNearAxis times finer.
    const int cells = thorough && yh < 0.1 * length(cy) ? RootGrid * RootGridNearAxis : RootGrid;
    const int N = thorough ? cells + 1 : cells;
    const double inset = thorough ? 1e-5 * aMax : 0.0;
    const double step = (2 * aMax - 2 * inset) / cells, a0 = -aMax + inset + (thorough ? 0.0 : 0.5 * step);
    const double cStep = std::cos(step), sStep = std::sin(step);
    Eval grid[RootGrid * RootGridNearAxis + 1];
    double ca = std::cos(a0), sa = std::sin(a0);
    for (int k = 0; k < N; ++k) {
        grid[k] = evalCS(ca, sa);
        const double cNext = ca * cStep - sa * sStep;
        sa = sa * cStep + ca * sStep;
        ca = cNext;
    }
    auto angle = [&](int k) { return a0 + k * step; };
    int n = 0;
    // The root in [lo, hi], where h changes sign, by false position with the
    // Illinois modification (the bracket stays, convergence is
    // superlinear); kept if it is a connection.
    auto refine = [&](double lo, double hi, double hLo, double hHi) {
        int side = 0;
        double root = lo;
        for (int i = 0; i < RootIterations; ++i) {
            root = (lo * hHi - hi * hLo) / (hHi - hLo);
            if (!(root > std::min(lo, hi) && root < std::max(lo, hi))) root = 0.5 * (lo + hi);
            const Eval m = eval(root);
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
        const Eval r = eval(root);
        // A sign change behind the exit point is no connection.
        Traced tr;
        const D3 w = direction(root);
        if (n < MaxSphereConnections && r.ok && r.ahead > 0 && trace(s, x, w, tr) &&
            std::fabs(r.h) < 1e-6 * length(y - tr.p2)) {
            // 0 where a ray beside it misses the ball (grazing, where the
            // Fresnel transmission vanishes): no usable connection.
            const double G = spreading(s, x, w, y, tr);
            if (G > 0 || !thorough) out[n++] = toConnection(w, tr, G);
        }
    };
    for (int k = 1; k < N; ++k) {
        const Eval &prev = grid[k - 1], &cur = grid[k];
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
        Eval e1 = eval(m1), e2 = eval(m2);
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
        const Eval em = firstFlips ? e1 : e2;
        if (!em.ok || (em.h < 0) == (cur.h < 0)) continue;
        refine(angle(k - 1), am, prev.h, em.h);
        refine(am, angle(k + 1), em.h, grid[k + 1].h);
    }
    return n;
}

bool regionHasSphereCaustics(const Scene& scene, int region) {
    if (!(scene.hasSphereLights || scene.pointLightCaustics) || !scene.desc.render.sphereCaustics) return false;
    for (const GlassSphere& s : scene.glassSpheres)
        if (s.outside == region) return true;
    return false;
}

namespace {

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

// The connections' density over directions at x of the path through s along
// w that reaches y on light l: 0 when the solver from (x, y) finds no root
// matching w.
double connectionPdf(const GlassSphere& s, const Light& l, const Vec3& x, const Vec3& w, const Vec3& y) {
    SphereConnection roots[MaxSphereConnections];
    const int n = connectThroughSphere(s, x, y, roots);
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
    const double cosY = -double(dot(cn.wo, normalize(y - l.desc().position)));
    if (!(cosY > 0) || !(cn.spreading > 0)) return 0;
    const double rl = l.desc().radius;
    return cn.spreading / (4 * double(Pi) * rl * rl * cosY);
}

// Power heuristic of density a among a, b and c.
double power3(double a, double b, double c) {
    const double a2 = a * a, sum = a2 + b * b + c * c;
    return sum > 0 ? a2 / sum : 0.0;
}

}  // namespace

Color sphereCausticLight(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng,
                         TransmittanceEstimator estimator, const CausticLights& lights) {
    const Scene& scene = ctx.scene;
    Color L(0);
    const Vec3 origin = v.shadowOrigin(scene);
    SphereConnection roots[MaxSphereConnections];
    for (const GlassSphere& s : scene.glassSpheres) {
        if (s.outside != region) continue;
        float cosMax = 1;
        const double pc = ballConePdf(s, v.p, &cosMax);
        // What reaches x from y through the ball along the connection cn:
        // transmittance x -> p1, nothing inside the ball, p2 -> y.
        auto throughBall = [&](const SphereConnection& cn, const Vec3& y) {
            const float d1 = length(cn.p1 - origin);
            Color T = shadowTransmittance(ctx, region, origin, cn.wi, d1, rng, estimator);
            if (isBlack(T)) return T;
            if (!s.clearInside) {
                const Vec3 n1 = normalize(cn.p1 - s.center);
                const Vec3 d = normalize(cn.p2 - cn.p1);
                SurfaceHit h;
                const Ray inside{offsetRayOrigin(scene, cn.p1, n1, d), d};
                if (scene.surfaceSet->intersect(inside, 0.f, length(cn.p2 - inside.o) * (1 - 1e-4f), h)) return Color(0);
            }
            // p2 -> y: the light's own surface ends the shadow ray.
            const Vec3 o2 = offsetRayOrigin(scene, cn.p2, normalize(cn.p2 - s.center), cn.wo);
            return T * shadowTransmittance(ctx, s.outside, o2, cn.wo, length(y - o2), rng, estimator);
        };
        for (const Light& light : scene.lights) {
            if (light.isPointLike()) {
                if (!scene.pointLightCaustics || !lights.pointLights) continue;
                // Every root to the light's one point y: f I T (1 - F1)(1 - F2) / G.
                const Vec3 y = light.desc().position;
                const int n = connectThroughSphere(s, v.p, y, roots, true);
                for (int k = 0; k < n; ++k) {
                    const SphereConnection& cn = roots[k];
                    if (!(cn.spreading > 0)) continue;
                    // The intensity towards p2 (a spot's cone and falloff).
                    LightSample ls;
                    if (!light.sample(cn.p2, 0.f, 0.f, ls)) continue;
                    const Color f = v.f(cn.wi);
                    if (isBlack(f) || isBlack(ls.L)) continue;
                    const Color T = throughBall(cn, y);
                    if (isBlack(T)) continue;
                    const double d2 = double(ls.dist) * double(ls.dist);
                    L += f * ls.L * T * float(d2 * double(cn.transmission) / cn.spreading);
                }
                continue;
            }
            if (!lights.sphereLights || !lightOutside(s, light)) continue;
            const Vec3 lc = light.desc().position;
            const float rl = light.desc().radius;
            // 1. Connections: y uniform on the light's surface.
            const Vec3 ny = sampleUniformSphere(rng.uniform(), rng.uniform());
            const Vec3 y = lc + ny * rl;
            const double pA = 1 / (4 * double(Pi) * double(rl) * double(rl));
            const int n = connectThroughSphere(s, v.p, y, roots);
            for (int k = 0; k < n; ++k) {
                const SphereConnection& cn = roots[k];
                const double cosY = -double(dot(cn.wo, ny));
                if (!(cosY > 0) || !(cn.spreading > 0)) continue;  // the light's far side
                const Color f = v.f(cn.wi);
                if (isBlack(f)) continue;
                const Color T = throughBall(cn, y);
                if (isBlack(T)) continue;
                const double pm = pA * cn.spreading / cosY;  // solid-angle density at x
                const double pu = lights.pathFollows ? double(v.pdf(cn.wi)) * double(cn.transmission) : 0.0;
                L += f * light.emittedRadiance() * T * float(double(cn.transmission) * power3(pm, pu, pc) / pm);
            }
            // 2. A direction uniform in the ball's cone, traced through it:
            // where the lens focuses the light (G near 0), the light fills
            // much of the ball and this finds it where connections cannot.
            if (!(pc > 0)) continue;
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
            const Color T = throughBall(cn, yHit);
            if (isBlack(T)) continue;
            const double pm = connectionPdf(s, light, v.p, cn.wi, yHit);
            const double pu = lights.pathFollows ? double(v.pdf(cn.wi)) * double(cn.transmission) : 0.0;
            L += f * light.emittedRadiance() * T * float(double(cn.transmission) * power3(pc, pm, pu) / pc);
        }
    }
    return L;
}

float sphereCausticPathWeight(const Scene& scene, int sphere, int light, const Vec3& x, const Vec3& w, float pathPdf,
                              const Vec3& y) {
    const GlassSphere& s = scene.glassSpheres[size_t(sphere)];
    const Light& l = scene.lights[size_t(light)];
    if (!lightOutside(s, l)) return 1;
    const Vec3 wn = normalize(w);
    SphereConnection traced;
    if (!traceThroughSphere(s, x, wn, traced)) return 1;
    const double pu = double(pathPdf) * double(traced.transmission);
    return float(power3(pu, connectionPdf(s, l, x, wn, y), ballConePdf(s, x)));
}

}  // namespace vdbmarch
