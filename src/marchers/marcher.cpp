#include "marchers/marcher.h"

#include "core/error.h"

namespace vdbmarch {

namespace {
struct Entry {
    const char* name;
    std::unique_ptr<Marcher> (*make)(const Scene&);
};
// The factory table: one line per method.
const Entry kMarchers[] = {
    {"uniform", makeUniformMarcher},
    {"reference", makeReferenceTracer},
};
}  // namespace

std::vector<std::string> marcherNames() {
    std::vector<std::string> names;
    for (const auto& e : kMarchers) names.push_back(e.name);
    return names;
}

std::unique_ptr<Marcher> makeMarcher(const std::string& method, const Scene& scene) {
    for (const auto& e : kMarchers)
        if (method == e.name) return e.make(scene);
    std::string known;
    for (const auto& e : kMarchers) known += str(" ", e.name);
    throw InputError(str("unknown method \"", method, "\"; this build implements:", known));
}

}  // namespace vdbmarch
