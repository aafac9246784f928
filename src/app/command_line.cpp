#include "app/command_line.h"

#include "app/vdb_check.h"

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "scene/auto_scene.h"

namespace vdbmarch {

bool endsWith(const std::string& s, const std::string& suffix) {
    if (s.size() < suffix.size()) return false;
    for (size_t i = 0; i < suffix.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
    return true;
}

std::string resolutionOverride(const std::string& res) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(res.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X'))
        throw InputError(str("--res ", res, ": expected WIDTHxHEIGHT, e.g. 640x480"));
    return str("camera.resolution=[", w, ",", h, "]");
}

std::vector<std::string> splitList(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string item; std::getline(ss, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

std::vector<double> parseNumberList(const std::string& s, const std::string& option) {
    std::vector<double> out;
    for (const auto& item : splitList(s)) {
        char* end = nullptr;
        double v = std::strtod(item.c_str(), &end);
        if (*end != 0) throw InputError(str(option, ": \"", item, "\" is not a number"));
        out.push_back(v);
    }
    return out;
}

SceneDesc loadSceneInput(const std::string& input, const std::vector<std::string>& overrides) {
    // Every VDB file is read once in a child process before this one opens
    // it (app/vdb_check.h): a damaged file is an error, never a crash.
    if (endsWith(input, ".vdb")) {
        checkVdbFilesIsolated({input});
        return loadAutoScene(input, overrides);
    }
    SceneDesc desc = loadSceneFile(input, overrides);
    checkVdbFilesIsolated(vdbFilesOf(desc));
    return desc;
}

}  // namespace vdbmarch
