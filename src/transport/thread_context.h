// Per-thread state of every path loop: one medium query per medium (VDB
// accessors), scratch vectors reused across rays, and the render counters.
// An estimator that needs scratch of its own keeps it in `extension`, made
// on first use, so this layer knows nothing of the estimators above it.
#pragma once

#include <memory>
#include <vector>

#include "core/sampling.h"
#include "core/stats.h"
#include "scene/scene.h"
#include "transport/majorant_segment.h"

namespace vdbmarch {

struct ThreadContextExtension {
    virtual ~ThreadContextExtension() = default;
};

struct ThreadContext {
    explicit ThreadContext(const Scene& s);
    const Scene& scene;
    std::vector<std::unique_ptr<MediumQuery>> queries;  // one per medium
    std::vector<Interval> intervals, shadowIntervals;
    std::vector<Interval> mediaIntervals;  // every medium's intervals before regionIntervals merges them
    std::vector<MajorantSegment> majorants;  // sigma_maj (tracking.h)
    // Shadow rays' unbiased ray marching (transmittance.cpp): the blocks
    // not sampled yet, and the optical-depth estimates.
    std::vector<DensityBound> shadowBounds;
    std::vector<double> marchDepths;
    // Distance sampling towards lights along the current path segment
    // (light_distance.h), and next-event weights per light.
    struct LightDistance {
        int light;
        EquiangularSampler sampler;
        float choice = 1;  // probability that the segment samples this light
    };
    std::vector<LightDistance> lightDistances;
    std::vector<float> lightWeights;
    // Made on first use by light_distance.cpp: per region, the bounds of
    // its scattering media, and per (region, light) whether the light can
    // ever get distance samples there.
    std::vector<BBox> scatterBounds;
    std::vector<char> lightDistanceCandidate;
    // Per light, the last ray's part inside its reach (lightReach): a beam
    // direction's density and the next segment's distance samplers ask for
    // the same ray. Held in place: as a heap vector written on every ray it
    // made two-thread renders of fig3b_spots 1.15x slower.
    struct ReachMemo {
        Vec3 o, d;
        float t0 = 0, t1 = 0;
        bool reaches = false, valid = false;
    };
    static constexpr int ReachMemoLights = 4;  // the first lights only
    ReachMemo reachMemo[ReachMemoLights];
    // Made on first use by beam_directions.cpp: per region, the beams of
    // spot lights (cones) and collimated quads (prisms) its medium vertices
    // draw directions towards.
    struct Beam {
        int light;
        Vec3 apex, axis, e1, e2;  // a prism's "apex" is its quad's centre
        float tanCone = 0;
        float s0, s1;     // the axial range sampled (the region's media)
        float power = 1;  // scattered power per unit length of beam
        // A collimated quad's prism: the quad's edges u, v and their axial
        // parts, the dual vectors that give a point's quad coordinates
        // (|a|, |b| <= 1/2 inside) along the beam, and the cross-section's
        // area perpendicular to the axis.
        bool prism = false;
        Vec3 u, v, dualA, dualB;
        float uAxial = 0, vAxial = 0, area = 0;
    };
    struct BeamRegion {
        std::vector<Beam> beams;
        // The integral of the media's phase function over the scattering
        // angle, G(theta) = int_0^theta p(cos a) da, at BeamAngleSteps + 1
        // angles over [0, pi] (beam_directions.cpp, shared by all threads).
        const std::vector<float>* angleIntegral = nullptr;
    };
    std::vector<BeamRegion> beamRegions;
    // Made on first use by caustic_folds.cpp: the folds of the caustics of
    // point-like and parallel lights through glass spheres (shared by all
    // threads), with a bounding sphere and the half-width of the density
    // drawn around a crossing.
    struct FoldSurface {
        int sphere = -1, light = -1;
        std::shared_ptr<const CausticFold> fold;
        Vec3 boundCenter;
        float boundRadius = 0, halfWidth = 0;
    };
    std::vector<FoldSurface> foldSurfaces;
    bool foldSurfacesMade = false;
    RenderCounters counters;
    std::unique_ptr<ThreadContextExtension> extension;

    // The extension as type T, made on first use.
    template <typename T, typename... Args>
    T& extensionAs(Args&&... args) {
        if (!extension) extension = std::make_unique<T>(std::forward<Args>(args)...);
        return static_cast<T&>(*extension);
    }
};

}  // namespace vdbmarch
