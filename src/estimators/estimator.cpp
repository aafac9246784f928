#include "estimators/estimator.h"

#include "core/error.h"
#include "illumination/illumination.h"

namespace vdbmarch {

namespace {
struct Entry {
    Method method;
    EstimatorMaker make;
};
// The factory table: one line per method.
const Entry kEstimators[] = {
    {Method::Uniform, makeUniformMarcher},
    {Method::Transmittance, makeTransmittanceMarcher},
    {Method::Guided, makeGuidedMarcher},
    {Method::Reference, makeReferenceTracer},
};
}  // namespace

std::vector<Method> estimatorMethods() {
    std::vector<Method> methods;
    for (const auto& e : kEstimators) methods.push_back(e.method);
    return methods;
}

std::unique_ptr<Estimator> makeEstimator(Method method, const Scene& scene, std::shared_ptr<const Illumination> illumination,
                                         std::shared_ptr<const StrategySet> strategies) {
    for (const auto& e : kEstimators)
        if (method == e.method) {
            if (!illumination) illumination = std::make_shared<Illumination>(prepareIllumination(scene, method));
            if (!strategies) strategies = StrategySet::build(scene);
            return e.make(EstimatorInputs{scene, std::move(illumination), std::move(strategies)});
        }
    throw std::logic_error(str("no marcher for method ", methodName(method)));
}

}  // namespace vdbmarch
