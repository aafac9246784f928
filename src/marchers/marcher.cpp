#include "marchers/marcher.h"

#include "core/error.h"
#include "marchers/illumination.h"

namespace vdbmarch {

namespace {
struct Entry {
    const char* name;
    std::unique_ptr<Marcher> (*make)(const Scene&, std::shared_ptr<const Illumination>);
};
// The factory table: one line per method.
const Entry kMarchers[] = {
    {"uniform", makeUniformMarcher},
    {"transmittance", makeTransmittanceMarcher},
    {"guided", makeGuidedMarcher},
    {"reference", makeReferenceTracer},
};
}  // namespace

std::vector<std::string> marcherNames() {
    std::vector<std::string> names;
    for (const auto& e : kMarchers) names.push_back(e.name);
    return names;
}

std::unique_ptr<Marcher> makeMarcher(const std::string& method, const Scene& scene,
                                     std::shared_ptr<const Illumination> illumination) {
    for (const auto& e : kMarchers)
        if (method == e.name) {
            if (!illumination) illumination = std::make_shared<Illumination>(prepareIllumination(scene, method));
            return e.make(scene, std::move(illumination));
        }
    std::string known;
    for (const auto& e : kMarchers) known += str(" ", e.name);
    throw InputError(str("unknown method \"", method, "\"; this build implements:", known));
}

}  // namespace vdbmarch
