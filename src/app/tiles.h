// Parts of a render for farms (docs/farm.md): `render --tile I/N` or
// `--crop` renders part of the frame into an EXR whose data window is that
// part, `--passes` some of the photon passes of the whole frame (the sums of
// each pass kept as layers); `merge` checks that a set of such files belongs
// together and assembles the frame, or folds the passes in order. What makes tiles "belong together" is written into
// each tile's header here and checked there.
#pragma once

#include <string>
#include <vector>

#include "image/exr_io.h"
#include "parse/scene_desc.h"
#include "render/render.h"

namespace vdbmarch {

// Header attributes of a tile (besides the render's own vdbmarch:* ones).
inline constexpr const char* TileSplitAttribute = "vdbmarch:split";  // "4 bands", "crop" or "6 passes"
inline constexpr const char* TileAttribute = "vdbmarch:tile";        // "2/4", "x0,y0,x1,y1" or "0-4" (passes)
inline constexpr const char* PassSamplesAttribute = "vdbmarch:passSamples";  // "0:5,1:5": samples of each pass
// Hash of everything that decides the pixels: the effective scene without
// render.threads (which never changes a pixel), the version and the cache.
inline constexpr const char* RenderHashAttribute = "vdbmarch:renderHash";
// The noise estimate from the two halves (render/noise_estimate.h NoiseEstimate):
// its relative value, RMSE and mean, which merge combines over tiles.
inline constexpr const char* NoiseAttribute = "vdbmarch:noiseEstimate";
inline constexpr const char* NoiseRmseAttribute = "vdbmarch:noiseRmse";
inline constexpr const char* NoiseMeanAttribute = "vdbmarch:noiseMean";
inline constexpr const char* NoiseTargetAttribute = "vdbmarch:noiseTarget";  // render.noise, or "none"

// render.denoise ("on", "preview" or "off"): merge denoises the frame so.
inline constexpr const char* DenoiseAttribute = "vdbmarch:denoise";
const char* denoiseModeName(RenderSettings::Denoise mode);

// The three noise attributes of an estimate (none when it is not valid).
StringAttributes noiseAttributes(const NoiseEstimate& e);

// What part of the frame a render covers: the whole frame, a tile of a
// fixed split, or a crop.
struct TileRequest {
    int index = -1, count = 0;  // --tile index/count (count 0: none)
    bool cropped = false;       // --crop
    PixelRect crop;
    // --passes FIRST-END: photon passes [first, end) of the whole frame.
    int firstPass = -1, endPass = -1;
    bool byPasses() const { return firstPass >= 0; }
    bool any() const { return count > 0 || cropped || byPasses(); }
};

// Parses "--tile I/N", "--crop x0,y0,x1,y1" and "--passes FIRST-END" (one
// of them; empty strings: not given). Ranges are checked against the frame
// by windowOf, and against the render's passes by the renderer.
TileRequest parseTileRequest(const std::string& tile, const std::string& crop, const std::string& passes = "");

// The pixels `request` covers in a width x height frame; InputError naming
// the option when they are not inside it.
PixelRect windowOf(const TileRequest& request, int width, int height);

// The attributes that mark a tile (split, tile), and for a part by passes
// the per-pass sample counts.
StringAttributes tileAttributes(const TileRequest& request, const RenderResult& result);

// The EXR layers of a part by passes: "pass<j>" with channels R, G, B (the
// radiance sums) and T (the transmittance sums) for each pass j.
std::vector<ExrLayer> passLayers(const RenderResult& result);

// vdbmarch:renderHash of a render of `desc` (with the cache file it reads, if any).
std::string renderHash(const SceneDesc& desc, const std::string& cacheFile);

// The frame assembled from tiles, and what the caller should warn about.
struct MergedTiles {
    ExrContents frame;
    std::vector<std::string> warnings;
};

// Reads the tiles and assembles the frame. InputError (nothing written)
// naming the file when one is not a vdbmarch tile, belongs to another render
// (another scene, settings, frame or split: the differing attribute and both
// values), duplicates or overlaps another, or when the tiles leave part of
// the frame uncovered (the missing tile indices, or the first hole).
MergedTiles mergeTiles(const std::vector<std::string>& paths);

}  // namespace vdbmarch
