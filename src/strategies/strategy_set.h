// The sampling strategies of one render, built once from the scene with
// their tables, in the order every path loop iterates them: distance
// strategies (light distances, then the folds of sphere caustics), direction
// strategies (beams), connections (sphere caustics). A strategy a scene does
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
    std::vector<const DistanceStrategy*> mDistances;
    std::vector<const DirectionStrategy*> mDirections;
    std::vector<const ConnectionStrategy*> mConnections;
    const LightDistances* mLightDistances = nullptr;
    const CausticFolds* mFolds = nullptr;
    size_t mNextSlot = 1;
};

}  // namespace vdbmarch
