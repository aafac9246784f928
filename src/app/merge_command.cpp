#include "app/merge_command.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "app/command_line.h"
#include "app/denoise_frame.h"
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
    ExrContents& f = merged.frame;
    // Tiles are denoised here, on the whole frame (render.denoise; docs/denoise.md).
    std::string mode = "off";
    for (const auto& [k, v] : f.attributes)
        if (k == DenoiseAttribute) mode = v;
    Image preview = f.image;
    auto isHalf = [](const ExrLayer& l) { return l.name == EvenHalfLayer || l.name == OddHalfLayer; };
    const bool hasHalves = std::count_if(f.layers.begin(), f.layers.end(), isHalf) == 2;
    if (mode != "off" && (mode == "on" || !a.png.empty())) {
        if (!hasHalves) {
            warn("not denoised: the tiles hold no half renders (rendered with fewer than 2 samples per pixel)");
        } else {
            preview = denoiseFrame(f.image.width, f.image.height, f.layers, 0);
            if (mode == "on") {
                f.layers.push_back(rgbaLayer(NoisyLayer, f.image));
                f.image = preview;
            }
        }
    }
    // The halves stay in the EXR only when it is denoised (as one process writes it).
    if (mode != "on") f.layers.erase(std::remove_if(f.layers.begin(), f.layers.end(), isDenoiserInput), f.layers.end());
    writeExr(a.output, f.image, f.attributes, f.layers);
    if (!a.png.empty()) writePng(a.png, preview, float(a.exposure ? *a.exposure : sceneExposure(f.attributes)));
    if (!a.quiet)
        std::fprintf(stderr, "vdbmarch: merged %zu tiles into %dx%d in %.3f s -> %s%s%s\n", a.tiles.size(), f.image.width,
                     f.image.height, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                     a.output.c_str(), a.png.empty() ? "" : ", ", a.png.c_str());
    return 0;
}

}  // namespace vdbmarch
