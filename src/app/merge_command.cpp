#include "app/merge_command.h"

#include <chrono>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "app/command_line.h"
#include "app/tiles.h"
#include "core/atomic_file.h"
#include "image/exr_io.h"
#include "image/png_io.h"

namespace vdbmarch {

namespace {

// render.exposure of the effective scene a tile records; 0 when absent.
double sceneExposure(const StringAttributes& attributes) {
    for (const auto& [k, v] : attributes)
        if (k == "vdbmarch:scene") {
            const nlohmann::json j = nlohmann::json::parse(v, nullptr, false);
            if (j.is_object() && j.contains("render") && j["render"].is_object() && j["render"].contains("exposure") &&
                j["render"]["exposure"].is_number())
                return j["render"]["exposure"].get<double>();
        }
    return 0;
}

}  // namespace

int runMerge(const MergeArgs& a) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!endsWith(a.output, ".exr")) throw InputError(str("-o ", a.output, ": the output must be an .exr file"));
    if (!a.png.empty() && !endsWith(a.png, ".png"))
        throw InputError(str("--png ", a.png, ": the preview must be a .png file"));
    for (const std::string& t : a.tiles)
        if (t == a.output) throw InputError(str("-o ", a.output, ": the output is also one of the tiles"));
    checkWritable(a.output);
    if (!a.png.empty()) checkWritable(a.png);
    MergedTiles merged = mergeTiles(a.tiles);
    for (const std::string& w : merged.warnings) warn(w);
    const ExrContents& f = merged.frame;
    writeExr(a.output, f.image, f.attributes, f.layers);
    if (!a.png.empty()) writePng(a.png, f.image, float(a.exposure ? *a.exposure : sceneExposure(f.attributes)));
    if (!a.quiet)
        std::fprintf(stderr, "vdbmarch: merged %zu tiles into %dx%d in %.3f s -> %s%s%s\n", a.tiles.size(), f.image.width,
                     f.image.height, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                     a.output.c_str(), a.png.empty() ? "" : ", ", a.png.c_str());
    return 0;
}

}  // namespace vdbmarch
