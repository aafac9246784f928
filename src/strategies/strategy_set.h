// The sampling strategies of one render, built once from the scene with
// their tables, in the order every path loop iterates them: distance
// strategies (light distances, then the folds of sphere caustics), direction
// strategies (beams), connections (sphere caustics), surface strategies
// (glass splitting). A strategy a scene does
// not need is built empty and costs a table lookup per segment or vertex.
// Each strategy keeps its per-thread scratch in its own thread-context slot,
// numbered here from 1 (slot 0 is the estimator's).
#pragma once

#include <memory>
#include <vector>

#include "strategies/strategy.h"

namespace vdbmarch {

class LightDistances;
class CausticFolds;
class BeamDirections;
class SphereCaustics;

class StrategySet {
public:
    // The default strategies for `scene` (experiments.* switch them off).
    static std::shared_ptr<StrategySet> build(const Scene& scene);

    const std::vector<const DistanceStrategy*>& distances() const { return mDistances; }
    const std::vector<const DirectionStrategy*>& directions() const { return mDirections; }
    const std::vector<const ConnectionStrategy*>& connections() const { return mConnections; }
    const std::vector<const SurfaceStrategy*>& surfaces() const { return mSurfaces; }

    // The light vertex v receives through specular surfaces: the sum of the
    // active connections; `connected` says whether any was made.
    Color connect(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng, const ConnectionRequest& request,
                  bool& connected) const;
    // The MIS weight of a path's own hit of light `light` after the
    // connections made at its last vertex (ConnectionStrategy::pathHitWeight).
    float pathHitWeight(const SpecularChain& chain, int light, const Vec3& x, const Vec3& w, float pathPdf,
                        const Vec3& y) const;
    // The event of a radiance path at a surface: the first surface strategy
    // that takes the hit, else the material's own sampling.
    PathSurfaceEvent surfaceEvent(ThreadContext& ctx, const SurfaceHit& hit, const Vec3& d, int region,
                                  const float u[3], const SurfaceRequest& request, Rng& rng) const;

    // The built-in strategies, for the guided marcher's per-ray pdf, which
    // mixes their densities into its own.
    const LightDistances& lightDistances() const { return *mLightDistances; }
    const CausticFolds& causticFolds() const { return *mFolds; }

    // A thread-context slot for a strategy added from outside (tests).
    size_t newSlot() { return mNextSlot++; }
    // Adds a strategy after the built-in ones of its kind; the set owns it.
    void add(std::unique_ptr<DistanceStrategy> s);
    void add(std::unique_ptr<DirectionStrategy> s);
    void add(std::unique_ptr<ConnectionStrategy> s);
    void add(std::unique_ptr<SurfaceStrategy> s);

    // True when segments in `region` must run to their true end for some
    // distance strategy (no probe cut).
    bool needsSegmentEnd(int region, bool skipPointLights) const;

    StrategySet();
    ~StrategySet();
    StrategySet(const StrategySet&) = delete;
    StrategySet& operator=(const StrategySet&) = delete;

private:
    std::vector<std::unique_ptr<DistanceStrategy>> mOwnedDistances;
    std::vector<std::unique_ptr<DirectionStrategy>> mOwnedDirections;
    std::vector<std::unique_ptr<ConnectionStrategy>> mOwnedConnections;
    std::vector<std::unique_ptr<SurfaceStrategy>> mOwnedSurfaces;
    std::vector<const DistanceStrategy*> mDistances;
    std::vector<const DirectionStrategy*> mDirections;
    std::vector<const ConnectionStrategy*> mConnections;
    std::vector<const SurfaceStrategy*> mSurfaces;
    const LightDistances* mLightDistances = nullptr;
    const CausticFolds* mFolds = nullptr;
    size_t mNextSlot = 1;
};

}  // namespace vdbmarch
