// Tiles of a render for farms (docs/farm.md): `render --tile I/N` or
// `--crop` renders part of the frame into an EXR whose data window is that
// part; `merge` checks that a set of such files belongs together and
// assembles the frame. What makes tiles "belong together" is written into
// each tile's header here and checked there.
#pragma once

#include <string>
#include <vector>

#include "image/exr_io.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

// Header attributes of a tile (besides the render's own vdbmarch:* ones).
inline constexpr const char* TileSplitAttribute = "vdbmarch:split";  // "4 bands" or "crop"
inline constexpr const char* TileAttribute = "vdbmarch:tile";        // "2/4" or "x0,y0,x1,y1"
// Hash of everything that decides the pixels: the effective scene without
// render.threads (which never changes a pixel), the version and the cache.
inline constexpr const char* RenderHashAttribute = "vdbmarch:renderHash";

// What part of the frame a render covers: the whole frame, a tile of a
// fixed split, or a crop.
struct TileRequest {
    int index = -1, count = 0;  // --tile index/count (count 0: none)
    bool cropped = false;       // --crop
    PixelRect crop;
    bool any() const { return count > 0 || cropped; }
};

// Parses "--tile I/N" and "--crop x0,y0,x1,y1" (either, not both; empty
// strings: not given). Ranges are checked against the frame by windowOf.
TileRequest parseTileRequest(const std::string& tile, const std::string& crop);

// The pixels `request` covers in a width x height frame; InputError naming
// the option when they are not inside it.
PixelRect windowOf(const TileRequest& request, int width, int height);

// The attributes that mark a tile: split, tile.
StringAttributes tileAttributes(const TileRequest& request);

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
