// What the vdbmarch commands (src/app/*_command.cpp) share: file-name and
// list checks, loading the scene an input names, and the tables of options
// that override scene keys. One table per command drives both the option's
// registration (tools/vdbmarch.cpp) and the "key=value" override it becomes.
#pragma once

#include <optional>
#include <cstdio>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "core/error.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

// True when s ends with suffix, ignoring the case of s (suffix: lower case).
bool endsWith(const std::string& s, const std::string& suffix);

// "--res WxH" as the override of camera.resolution (validated by the parser).
std::string resolutionOverride(const std::string& res);

// The non-empty items of a comma-separated list.
std::vector<std::string> splitList(const std::string& s);

// A comma-separated list of numbers; `option` names it in the error.
std::vector<double> parseNumberList(const std::string& s, const std::string& option);

// A scene file, or the automatic scene of a bare .vdb, with the overrides
// applied. With a `frame` (--frames), the frame token of a bare .vdb input
// and of the scene's file paths becomes the frame number (parse/frames.h);
// without one, a token in them is an error that asks for --frames.
SceneDesc loadSceneInput(const std::string& input, const std::vector<std::string>& overrides,
                         std::optional<int> frame = std::nullopt);

// --frames, shared by render and bake (docs/farm.md, "Frames").
//
// The path options of a run (option name and path; an empty path is an
// option not given): with `frameCount` 0 (no --frames), a path holding the
// frame token is an error that asks for --frames; with several frames, every
// one must hold the token (pass outputs only: each frame would overwrite the
// one file).
void checkFrameOutputs(const std::vector<std::pair<std::string, std::string>>& outputs, size_t frameCount,
                       const std::string& framesText);
// Before the first frame runs: every frame's scene parses and every file it
// names (and each per-frame input option, such as render --cache) exists; a
// missing one is an InputError naming the file, the frame and the key.
void checkFrameInputs(const std::string& input, const std::vector<std::string>& overrides,
                      const std::vector<int>& frames,
                      const std::vector<std::pair<std::string, std::string>>& inputOptions = {});
// Runs one frame's job; its error is rethrown with "frame N: " in front.
template <class Job>
void runFrame(int frame, Job&& job) {
    try {
        job();
    } catch (const InputError& e) {
        throw InputError(str("frame ", frame, ": ", e.what()));
    } catch (const IoError& e) {
        throw IoError(str("frame ", frame, ": ", e.what()));
    }
}

// A command-line option that overrides one scene key: `--spp 4` is the
// override render.spp=4, validated by the scene parser like any other key.
// `field` is the member of the command's arguments that holds the value: an
// empty optional or string means the option was not given and the scene's
// value stands.
template <class Args>
struct SceneOption {
    using Field = std::variant<std::optional<int> Args::*, std::optional<long long> Args::*,
                               std::optional<double> Args::*, std::string Args::*>;
    const char* flag;  // "--spp"
    const char* key;   // "render.spp"
    std::string help;
    Field field;
};

template <class Args>
using SceneOptionTable = std::vector<SceneOption<Args>>;

namespace detail {
template <class T>
const T* givenValue(const std::optional<T>& v) { return v ? &*v : nullptr; }
inline const std::string* givenValue(const std::string& s) { return s.empty() ? nullptr : &s; }
template <class T>
std::string jsonValue(const T& v) { return str(v); }
// Doubles round-trip: 17 significant digits, so --step 0.0012345678 stays that.
inline std::string jsonValue(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}
inline std::string jsonValue(const std::string& s) { return "\"" + s + "\""; }
}  // namespace detail

// Appends "key=value" (text as a JSON string) for every option of the table
// the user gave, in table order.
template <class Args>
void appendSceneOverrides(const Args& args, const SceneOptionTable<Args>& table, std::vector<std::string>& out) {
    for (const SceneOption<Args>& o : table)
        std::visit(
            [&](auto field) {
                if (const auto* v = detail::givenValue(args.*field)) out.push_back(str(o.key, "=", detail::jsonValue(*v)));
            },
            o.field);
}

}  // namespace vdbmarch
