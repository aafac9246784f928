#include "app/command_line.h"

#include "app/vdb_check.h"

#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "parse/frames.h"
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

SceneDesc loadSceneInput(const std::string& input, const std::vector<std::string>& overrides,
                         std::optional<int> frame) {
    // VDB files are read once, guarded (volume/vdb_read_guard.h): a damaged
    // file is an error naming it, never a crash.
    if (endsWith(input, ".vdb")) {
        if (!frame && hasFrameToken(input))
            throw InputError(str(input, ": the input holds the frame token (a run of '#'): render it with --frames "
                                        "(e.g. --frames 1-100) to replace the token by each frame's number"));
        const std::string path = frame ? substituteFrame(input, *frame) : input;
        return loadAutoScene(path, overrides, frame);
    }
    return loadSceneFile(input, overrides, frame);
}

void checkFrameOutputs(const std::vector<std::pair<std::string, std::string>>& outputs, size_t frameCount,
                       const std::string& framesText) {
    for (const auto& [option, path] : outputs) {
        if (path.empty()) continue;
        if (frameCount == 0 && hasFrameToken(path))
            throw InputError(str(option, " ", path, ": the name holds the frame token (a run of '#'), which only "
                                 "--frames replaces: pass --frames (e.g. --frames 1-100), or leave '#' out of the name"));
        if (frameCount > 1 && !hasFrameToken(path))
            throw InputError(str(option, " ", path, ": --frames ", framesText, " runs ", frameCount,
                                 " frames, and every frame would overwrite this one file: put the frame token in "
                                 "the name (e.g. name.####.ext, #### = the frame number padded to 4 digits)"));
    }
}

void checkFrameInputs(const std::string& input, const std::vector<std::string>& overrides,
                      const std::vector<int>& frames,
                      const std::vector<std::pair<std::string, std::string>>& inputOptions) {
    for (int frame : frames) {
        std::vector<std::pair<std::string, std::string>> files;  // what names it, the path
        for (const auto& [option, pattern] : inputOptions)
            if (!pattern.empty()) files.emplace_back(option, substituteFrame(pattern, frame));
        if (endsWith(input, ".vdb")) {
            files.emplace_back("the input " + input, substituteFrame(input, frame));
        } else {
            // Parsing only (cheap): the files are opened when the frame runs.
            const SceneDesc desc = loadSceneFile(input, overrides, frame);
            for (const auto& [key, path] : sceneFilePaths(desc)) files.emplace_back(str(key, " of ", input), path);
        }
        for (const auto& [what, path] : files) {
            struct stat st;
            if (::stat(path.c_str(), &st) != 0)
                throw InputError(str(path, ": frame ", frame, " (", what, "): ", std::strerror(errno)));
        }
    }
}

}  // namespace vdbmarch
