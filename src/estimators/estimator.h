// One interface for every way of estimating the radiance along a camera ray
// (the render's methods: the paper's three marchers and the path tracer), and one factory table. Per-thread state lives in a
// ThreadContext.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/rng.h"
#include "parse/method.h"
#include "paths/path_tracer.h"
#include "transport/thread_context.h"

namespace vdbmarch {

class Scene;
struct Illumination;

class Estimator {
public:
    virtual ~Estimator() = default;
    virtual PathRadiance radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const = 0;
};

// Methods the factory table implements, in the order `--method` lists them
// (every Method: a test checks it). Method-parameterised tests run over it.
std::vector<Method> estimatorMethods();
// The marchers estimate L_i from `illumination` (photon map, cache); when
// null it is prepared here from the scene (prepareIllumination). Every
// path the estimator traces iterates `strategies`, built once per render
// (null: built here from the scene, StrategySet::build).
std::unique_ptr<Estimator> makeEstimator(Method method, const Scene& scene,
                                         std::shared_ptr<const Illumination> illumination = nullptr,
                                         std::shared_ptr<const StrategySet> strategies = nullptr);

// What every estimator is made from.
struct EstimatorInputs {
    const Scene& scene;
    std::shared_ptr<const Illumination> illumination;
    std::shared_ptr<const StrategySet> strategies;
};

// Constructors behind the factory table.
using EstimatorMaker = std::unique_ptr<Estimator> (*)(const EstimatorInputs&);
std::unique_ptr<Estimator> makeUniformMarcher(const EstimatorInputs& in);
std::unique_ptr<Estimator> makeTransmittanceMarcher(const EstimatorInputs& in);
std::unique_ptr<Estimator> makeGuidedMarcher(const EstimatorInputs& in);
std::unique_ptr<Estimator> makeReferenceTracer(const EstimatorInputs& in);

}  // namespace vdbmarch
