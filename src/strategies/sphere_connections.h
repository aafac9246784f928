// The geometry of connections through a smooth glass sphere: every
// refracted path from a point x to a point or direction y through the ball
// (manifold next-event estimation made exact for a sphere, see
// sphere_caustics.h), traced in double precision, and the folds of the
// caustics of point-like and parallel lights behind the ball.
#pragma once

#include "scene/scene.h"

namespace vdbmarch {

// A connection from x through a glass sphere to a point y.
struct SphereConnection {
    Vec3 wi;             // unit, from x to the entry point p1
    Vec3 p1, p2;         // entry and exit points
    Vec3 wo;             // unit, from p2 towards y
    float transmission;  // (1 - F1)(1 - F2), the Fresnel transmittances
    double spreading;    // G = dA_perp(y) / d omega(x); to a light at infinity, d omega_exit / d omega(x)
    int refractions;     // 2: into the ball and out; 1: across its surface (p1 = p2)
};

// Most connections one (x, y) pair can have through a sphere.
constexpr int MaxSphereConnections = 8;

// Every connection from x to y through sphere s that the solver finds (x and
// y outside it); returns their number. A grid over the arc of the ball's
// outline brackets the roots. Two roots closer than its step (near a fold
// of the caustic) or three near the lens's axis can slip through it: sphere
// lights weigh the connections against two other ways to the same light,
// so a missed root only moves weight to them; a point light has no other
// way, so `thorough` also finds pairs between the grid's points (at local
// minima of |h|), the arc's ends and a finer grid near the axis
// (SphereCaustics.TheSolverFindsEveryTracedPathFromAPoint checks that none
// is missed). The extra points cost time, so only point lights' solves are
// thorough.
int connectThroughSphere(const GlassSphere& s, const Vec3& x, const Vec3& y, SphereConnection out[MaxSphereConnections],
                         bool thorough = false);

// Every connection across the surface of sphere s from x to y, one inside
// it and one outside (one refraction); returns their number. The roots are
// found on the arc of the outline that the outer end sees; `thorough` as
// above. On the axis through the outer end and the centre the one path is
// the axis (a point light at the centre of a glass globe).
int connectAcrossSphere(const GlassSphere& s, const Vec3& x, const Vec3& y, SphereConnection out[MaxSphereConnections],
                        bool thorough = false);

// Every connection from x to a light at infinity in direction wL (unit,
// towards the light: directional and collimated lights) through sphere s
// from outside it (two refractions), or across its surface from inside it
// (one); solved thoroughly. Each connection's `spreading` is then
// J = d omega_exit / d omega(x), and its estimate f E T (1 - F...) / J.
int connectThroughSphereToward(const GlassSphere& s, const Vec3& x, const Vec3& wL,
                               SphereConnection out[MaxSphereConnections]);
int connectAcrossSphereToward(const GlassSphere& s, const Vec3& x, const Vec3& wL,
                              SphereConnection out[MaxSphereConnections]);

// Traces direction w from x into sphere s and out again (double precision):
// the exit point and direction, the Fresnel transmittances. False when the
// ray misses the sphere.
bool traceThroughSphere(const GlassSphere& s, const Vec3& x, const Vec3& w, SphereConnection& out);

// Traces direction w from x across the surface of sphere s once (into it
// from outside, out of it from inside). False when the ray misses it or is
// totally reflected.
bool traceAcrossSphere(const GlassSphere& s, const Vec3& x, const Vec3& w, SphereConnection& out);

// A direction from x matches a root when within about 1.4e-3 rad of it.
constexpr double RootMatchCos = 1 - 1e-6;

// The glass sphere a sphere light can be reached through: outside it, or
// (one refraction) inside it.
inline bool lightOutside(const GlassSphere& s, const Light& l) {
    const LightSphere* ls = l.sphere();
    return ls && length(ls->center - s.center) > s.radius + ls->radius;
}
inline bool lightInside(const GlassSphere& s, const Light& l) {
    const LightSphere* ls = l.sphere();
    return ls && length(ls->center - s.center) + ls->radius < s.radius;
}

// The fold (scene.h's CausticFold) of light `light` through sphere s,
// traced through the ball in double precision (the envelope by central differences along the family
// of the light's rays); false when the light is not point-like or parallel,
// or lies inside or on the ball.
bool causticFold(const GlassSphere& s, const Light& light, CausticFold& out);
// The fold's exact point (z, rho) for the light's ray of parameter u;
// false where there is none.
bool causticFoldPoint(const GlassSphere& s, const Light& light, double u, double& z, double& rho);

}  // namespace vdbmarch
