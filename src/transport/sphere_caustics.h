// Next-event estimation through a smooth glass sphere: the light a lens
// focuses into a medium or onto a diffuse floor (a caustic), which ordinary
// shadow rays cannot follow (glass blocks them) and a path finds only when
// its sampled direction happens to refract into the light.
//
// This is manifold next-event estimation (Hanika, Droske and Fascione 2015,
// "Manifold Next Event Estimation"; Cycles' shadow caustics) for the case a
// sphere makes exact: a path x -> p1 (enters) -> p2 (leaves) -> y refracts in
// the plane through x, y and the sphere's centre (each refraction keeps the
// ray in the plane of the incident direction and the normal), so the
// connections from x to a light point y are the roots of a function of one
// angle on the sphere's outline in that plane. They are bracketed on a fixed
// grid and refined by false position, deterministically in (x, y).
//
// The estimate for each root, with y drawn on the light with area density
// p_A (sphere lights):
//   f(w) L_e T (1 - F1)(1 - F2) |cos theta_y| / (p_A G),
// G = dA_perp(y) / d omega(x), the ray spreading through the lens (the
// generalised geometry term; r^2 without glass), by forward differences of
// the traced rays in double precision. Its solid-angle density at x is
// p_m = p_A G / |cos theta_y|.
//
// A point or spot light (Scene::deltaLightCaustics) is its one point y:
// each root brings f(w) I(y -> p2) T (1 - F1)(1 - F2) / G, the limit of the
// above for a sphere light of intensity I shrunk to a point; no path or cone
// direction can hit it, so there is nothing to weigh it against. A
// directional or collimated light is a direction: each root whose exit
// direction is the light's brings f(w) E T (1 - F1)(1 - F2) / J, J the
// exit directions' solid angle per solid angle at x.
//
// Near the lens's focus G goes to 0 and these estimates grow without bound;
// there a direction drawn uniformly in the cone the ball subtends (density
// p_c), traced through it, finds the light often. A path that samples its
// own direction at x (density p_u, times the Fresnel transmission choices)
// and reaches the light through the same two refractions is the third way
// to the same light; the three are weighed by the power heuristic. The
// path's and the cone's side find p_m by solving from (x, y) with the same
// solver and matching their direction to a root, 0 when none matches (the
// grid missed a pair of roots at a fold), so the weights sum to 1 whatever
// the solver finds.
//
// A light inside the ball seen from outside, or a light outside seen from
// inside (a lamp in a glass globe; smoke sealed in glass under a spot), is
// reached across the surface once: x -> p -> y, the same estimates with one
// Fresnel factor, the roots found on the same arc from the end outside;
// the connections and the path weigh against each other (no cone). A
// medium inside the ball attenuates every connection that crosses it
// (shadow rays through the ball's region).
#pragma once

#include "core/rng.h"
#include "scene/scene.h"
#include "transport/direct_light.h"

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
// (SphereCaustics.TheSolverFindsEveryTracedPathFromAPoint: without these,
// 0.8 % of a point light's paths through the ball were missed); with every
// solve thorough, fig4_caustic_sphere rendered 10-16 % slower.
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

// Which lights sphereCausticLight connects to, and whether the path goes on
// from the vertex (its hits of sphere lights through the glass then weigh
// against the connections, sphereCausticPathWeight; else the connections
// and the cone directions share the light between them alone).
struct CausticLights {
    bool sphereLights = true;
    bool pointLights = true;     // where Scene::deltaLightCaustics holds
    bool pathFollows = true;
    bool parallelLights = true;  // directional and collimated, where Scene::deltaLightCaustics holds
    // The share of the point-like and parallel lights' connections left to
    // this vertex by distance sampling near caustic folds (light_distance.h).
    float deltaWeight = 1;
};

// The caustic light at vertex v (in `region`) through every glass sphere:
// from sphere lights, the connections to one light point (and through the
// ball, one direction in its cone), each weighed against the other and the
// path's own hits; from point and spot lights, the connections to their
// point; from directional and collimated lights, those along their
// direction.
Color sphereCausticLight(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng,
                         TransmittanceEstimator estimator, const CausticLights& lights = {});

// The power-heuristic weight of a path that left x along w (its direction
// density pathPdf), refracted `refractions` times at glass sphere `sphere`
// (into and out of it, or across its surface once) and hit sphere light
// `light` at y, against the connections and the cone directions at x
// (sphereCausticLight); 1 where those do not take that pattern.
float sphereCausticPathWeight(const Scene& scene, int sphere, int refractions, int light, const Vec3& x, const Vec3& w,
                              float pathPdf, const Vec3& y);

// The pattern of a sphere caustic connection along a light path: refractions
// at one glass sphere (into and out of it, or across its surface once) and
// nothing else. After each bending
// surface event (a refraction or reflection at `surface`), `refractions`
// counts the refractions at sphere `sphere`, or is -1 once anything else
// broke the pattern (it stays -1).
inline void followLensPattern(const Scene& scene, bool refraction, int surface, int& sphere, int& refractions) {
    const int s = refraction ? glassSphereOf(scene, surface) : -1;
    if (s < 0 || (sphere >= 0 && sphere != s)) refractions = -1;
    else if (refractions >= 0) {
        sphere = s;
        ++refractions;
    }
}

// The fold (scene.h's CausticFold) of light `light` through sphere s,
// traced through the ball in double precision (the envelope by central differences along the family
// of the light's rays); false when the light is not point-like or parallel,
// or lies inside or on the ball.
bool causticFold(const GlassSphere& s, const Light& light, CausticFold& out);
// The fold's exact point (z, rho) for the light's ray of parameter u;
// false where there is none.
bool causticFoldPoint(const GlassSphere& s, const Light& light, double u, double& z, double& rho);

// True when sphere caustic connections apply (experiments.sphere_caustics, a
// sphere light or Scene::deltaLightCaustics, a glass sphere): every vertex
// then makes them, through each sphere by where it and the light lie, so a
// path's weights (sphereCausticPathWeight) know what its last vertex did.
bool sceneHasSphereCaustics(const Scene& scene);

}  // namespace vdbmarch
