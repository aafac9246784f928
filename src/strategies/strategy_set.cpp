#include "strategies/strategy_set.h"

#include "strategies/beam_directions.h"
#include "strategies/caustic_folds.h"
#include "strategies/glass_splitting.h"
#include "strategies/light_distances.h"
#include "strategies/sphere_caustics.h"

namespace vdbmarch {

namespace {
// Appends an owned strategy to its kind's list, in the order loops iterate.
template <typename S>
void addTo(std::vector<const S*>& list, std::vector<std::unique_ptr<S>>& owned, std::unique_ptr<S> s) {
    list.push_back(s.get());
    owned.push_back(std::move(s));
}
}  // namespace

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
    if (scene.desc.experiments.glassSplitting) set->add(std::make_unique<GlassSplitting>());
    return set;
}

void StrategySet::add(std::unique_ptr<DistanceStrategy> s) { addTo(mDistances, mOwnedDistances, std::move(s)); }
void StrategySet::add(std::unique_ptr<DirectionStrategy> s) { addTo(mDirections, mOwnedDirections, std::move(s)); }
void StrategySet::add(std::unique_ptr<ConnectionStrategy> s) { addTo(mConnections, mOwnedConnections, std::move(s)); }
void StrategySet::add(std::unique_ptr<SurfaceStrategy> s) { addTo(mSurfaces, mOwnedSurfaces, std::move(s)); }
Color StrategySet::connect(ThreadContext& ctx, int region, const ScatterVertex& v, Rng& rng,
                           const ConnectionRequest& request, bool& connected) const {
    Color L(0);
    connected = false;
    for (const ConnectionStrategy* c : mConnections) {
        if (!c->active()) continue;
        L += c->connect(ctx, region, v, rng, request);
        connected = true;
    }
    return L;
}

float StrategySet::pathHitWeight(const SpecularChain& chain, int light, const Vec3& x, const Vec3& w, float pathPdf,
                                 const Vec3& y) const {
    float weight = 1;
    for (const ConnectionStrategy* c : mConnections)
        if (c->active()) weight *= c->pathHitWeight(chain, light, x, w, pathPdf, y);
    return weight;
}

PathSurfaceEvent StrategySet::surfaceEvent(ThreadContext& ctx, const SurfaceHit& hit, const Vec3& d, int region,
                                           const float u[3], const SurfaceRequest& request, Rng& rng) const {
    PathSurfaceEvent out;
    for (const SurfaceStrategy* s : mSurfaces)
        if (s->sample(ctx, hit, d, region, u, request, rng, out)) return out;
    return materialSurfaceEvent(ctx.scene, hit, d, region, u);
}

bool StrategySet::needsSegmentEnd(int region, bool skipPointLights) const {
    for (const DistanceStrategy* s : mDistances)
        if (s->needsSegmentEnd(region, skipPointLights)) return true;
    return false;
}

}  // namespace vdbmarch
