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
#include "strategies/sphere_connections.h"
#include "strategies/strategy.h"

namespace vdbmarch {

// The caustic light at vertex v (in `region`) through every glass sphere:
// from sphere lights, the connections to one light point (and through the
// ball, one direction in its cone), each weighed against the other and the
// path's own hits; from point and spot lights, the connections to their
// point; from directional and collimated lights, those along their
// direction.
Color sphereCausticLight(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng,
                         TransmittanceEstimator estimator, const ConnectionRequest& lights = {});

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

// True when sphere caustic connections apply (experiments.sphere_caustics, a
// sphere light or Scene::deltaLightCaustics, a glass sphere): every vertex
// then makes them, through each sphere by where it and the light lie, so a
// path's weights (sphereCausticPathWeight) know what its last vertex did.
bool sceneHasSphereCaustics(const Scene& scene);

// Sphere caustic connections as a connection strategy of the path loops.
class SphereCaustics final : public ConnectionStrategy {
public:
    explicit SphereCaustics(const Scene& scene) : mScene(scene), mActive(sceneHasSphereCaustics(scene)) {}
    bool active() const override { return mActive; }
    Color connect(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng,
                  const ConnectionRequest& request) const override {
        return sphereCausticLight(ctx, region, v, rng, TransmittanceEstimator::UnbiasedMarching, request);
    }
    float pathHitWeight(const SpecularChain& chain, int light, const Vec3& x, const Vec3& w, float pathPdf,
                        const Vec3& y) const override;

private:
    const Scene& mScene;
    const bool mActive;
};

}  // namespace vdbmarch
