#include "strategies/strategy_set.h"

#include "strategies/beam_directions.h"
#include "strategies/caustic_folds.h"
#include "strategies/light_distances.h"
#include "strategies/sphere_caustics.h"

namespace vdbmarch {

StrategySet::StrategySet() = default;
StrategySet::~StrategySet() = default;

std::shared_ptr<StrategySet> StrategySet::build(const Scene& scene) {
    auto set = std::make_shared<StrategySet>();
    auto distances = std::make_unique<LightDistances>(scene, set->newSlot());
    auto folds = std::make_unique<CausticFolds>(scene, set->newSlot());
    set->mLightDistances = distances.get();
    set->mFolds = folds.get();
    auto beams = std::make_unique<BeamDirections>(scene, *distances, set->newSlot());
    set->add(std::move(distances));
    set->add(std::move(folds));
    set->add(std::move(beams));
    set->add(std::make_unique<SphereCaustics>(scene));
    return set;
}

void StrategySet::add(std::unique_ptr<DistanceStrategy> s) {
    mDistances.push_back(s.get());
    mOwnedDistances.push_back(std::move(s));
}

void StrategySet::add(std::unique_ptr<DirectionStrategy> s) {
    mDirections.push_back(s.get());
    mOwnedDirections.push_back(std::move(s));
}

void StrategySet::add(std::unique_ptr<ConnectionStrategy> s) {
    mConnections.push_back(s.get());
    mOwnedConnections.push_back(std::move(s));
}

bool StrategySet::needsSegmentEnd(int region, bool skipPointLights) const {
    for (const DistanceStrategy* s : mDistances)
        if (s->needsSegmentEnd(region, skipPointLights)) return true;
    return false;
}

}  // namespace vdbmarch
