// The loaded scene: media read from VDB files, surfaces in Embree, lights,
// camera, and the medium regions that say which media fill which space.
#pragma once

#include <memory>
#include <vector>

#include "scene/camera.h"
#include "scene/environment.h"
#include "scene/lights.h"
#include "parse/scene_desc.h"
#include "scene/surfaces.h"
#include "volume/medium.h"

namespace vdbmarch {

// A region is a set of media that add up: the world media (outside closed
// surfaces), vacuum, or the single medium inside a surface.
struct Region {
    std::vector<int> media;
    Color unboundedSigmaT{0, 0, 0};  // summed extinction of its unbounded homogeneous media
    bool gridded = false;            // holds a VDB medium (its rays march a grid)
    // Every medium in it is homogeneous, unbounded and not emissive: the
    // extinction is unboundedSigmaT everywhere in the region.
    bool constant = false;
    bool emits = false;  // some medium in it emits
    // Summed sigma_a + sigma_s of its media: a channel that is zero here
    // has no extinction anywhere in the region.
    Color coefficients{0, 0, 0};
};

struct SurfaceInfo {
    MaterialDesc material;
    int interiorRegion = 1;  // vacuum unless `interior` names a medium
    int exteriorRegion = 0;  // the world media unless `exterior` names one
    bool closed = true;      // a sphere, a box or a watertight mesh
};

// A smooth glass sphere that next-event estimation sees light through
// (strategies/sphere_caustics.h): a sphere surface of refracting dielectric,
// uniformly scaled, with no medium inside.
struct GlassSphere {
    Vec3 center;
    float radius = 1;
    float ior = 1.5f;
    int surface = -1;
    int outside = 0;          // the region around it
    int inside = 0;           // the region it holds (its medium, if any)
    bool emptyInside = true;  // no medium, other surface or sphere light inside: rays cross it unhindered
};

// The fold of the caustic that a glass sphere focuses from a point-like or
// parallel light outside it (the pattern of two refractions): where
// neighbouring exit rays meet, so two of the connections to the light merge
// and their spreading goes to 0 (strategies/caustic_folds.h). The light's
// rays through the ball are symmetric about the axis through the light (or
// along a parallel light's direction) and the centre, so the fold is a
// surface of revolution: the envelope of the exit rays in one plane through
// the axis, a polyline of (z, rho) points, z along `axis` (the light's
// travel) from `center`, rho the distance from the axis, each the meeting
// point of the exit rays about the light's ray of parameter u (an angle off
// the axis from a point light, a height for a parallel one).
struct CausticFold {
    Vec3 center, axis;
    std::vector<float> z, rho;
    std::vector<double> u;  // the parameter of the light's ray whose exit rays meet there
};

// True when a straight shadow ray crosses the surface (interfaces and
// index-matched glass); every other surface blocks it.
bool crossedByShadowRays(const MaterialDesc& material);

class Scene;
// The index in Scene::glassSpheres of surface `surface`'s glass sphere, or -1.
int glassSphereOf(const Scene& scene, int surface);
// True when some surface refracts or reflects (a dielectric with ior != 1):
// light that passes it cannot be followed by shadow rays.
bool hasBendingGlass(const Scene& scene);

class Scene {
public:
    static constexpr int WorldRegion = 0;
    static constexpr int VacuumRegion = 1;

    SceneDesc desc;
    std::unique_ptr<Camera> camera;
    LightList lights;
    std::vector<std::unique_ptr<Medium>> media;
    std::vector<Region> regions;
    std::vector<SurfaceInfo> surfaces;
    std::unique_ptr<SurfaceSet> surfaceSet;
    Environment environment;  // the background colour or the environment map
    float step = 1, shadowStep = 1;  // world units
    float sceneScale = 1;            // size of the scene, for ray offsets
    bool hasSphereLights = false;
    std::vector<GlassSphere> glassSpheres;
    // The caustics of delta lights through the scene's refracting glass are
    // found by sphere caustic connections (sphere_caustics.h), so no photon
    // needs to carry them: experiments.sphere_caustics, every refracting surface
    // one of glassSpheres, at least one delta light, every point or spot off
    // the spheres' surfaces (inside one or outside all), every collimated
    // quad outside them (directional lights always are).
    bool deltaLightCaustics = false;
    // The caustics of sphere lights through refracting glass come from
    // caustic photons where a method gathers them (the marchers' L_i
    // samples; the reference where delta lights make it gather), and a
    // path leaves out every sphere light it reaches through bending glass
    // from such a vertex on (docs/method.md, "Caustics of sphere lights"):
    // experiments.caustic_photons, a sphere light, bending glass, a
    // scattering medium, and no glass sphere that sphere caustic
    // connections already take (experiments.sphere_caustics).
    bool sphereLightCausticPhotons = false;

    // Whether a shadow ray that starts in `region` can ever reach light
    // `light` (lights.size(): the environment). False only where every
    // surface around the region is closed and blocks shadow rays (glass
    // that bends light, opaque objects) and the light is not inside it: a
    // medium in a glass knot never sees a light outside the glass directly,
    // so next-event estimation there would cast shadow rays that are all
    // blocked.
    bool shadowRaysCanReach(int region, size_t light) const {
        return shadowReach.empty() || shadowReach[size_t(region) * (lights.size() + 1) + light] != 0;
    }
    std::vector<char> shadowReach;  // regions x (lights + 1), filled by buildScene
};

// Region that a ray starting at r.o is in, from the first surface it meets.
int regionAtRayStart(const Scene& scene, const Ray& r);

// Loads every file the description names and validates the combination.
std::unique_ptr<Scene> buildScene(const SceneDesc& desc);

}  // namespace vdbmarch
