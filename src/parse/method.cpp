#include "parse/method.h"

namespace vdbmarch {

namespace {
struct MethodName {
    Method method;
    const char* name;
};
const MethodName kMethods[] = {
    {Method::Uniform, "uniform"},
    {Method::Transmittance, "transmittance"},
    {Method::Guided, "guided"},
    {Method::Reference, "reference"},
};
}  // namespace

const std::vector<Method>& allMethods() {
    static const std::vector<Method> methods = [] {
        std::vector<Method> v;
        for (const auto& m : kMethods) v.push_back(m.method);
        return v;
    }();
    return methods;
}

const char* methodName(Method m) {
    for (const auto& e : kMethods)
        if (e.method == m) return e.name;
    return "?";
}

bool parseMethod(const std::string& name, Method& out) {
    for (const auto& e : kMethods)
        if (name == e.name) {
            out = e.method;
            return true;
        }
    return false;
}

std::string methodList() {
    std::string s;
    for (const auto& e : kMethods) s += (s.empty() ? "" : ", ") + std::string(e.name);
    return s;
}

const char* liSourceName(LiSource s) {
    switch (s) {
        case LiSource::Path: return "path";
        case LiSource::Photons: return "photons";
        case LiSource::Cache: return "cache";
    }
    return "?";
}

bool parseLiSource(const std::string& name, LiSource& out) {
    if (name == "path") out = LiSource::Path;
    else if (name == "photons") out = LiSource::Photons;
    else if (name == "cache") out = LiSource::Cache;
    else return false;
    return true;
}

}  // namespace vdbmarch
