// OpenEXR output (the renderer's primary format) and input (reference images).
#pragma once

#include "image/image.h"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vdbmarch {

using StringAttributes = std::vector<std::pair<std::string, std::string>>;

// An extra layer of the same size as the image (an AOV): channels named
// "<name>.<channel>" in the file, as compositors group them ("depth.Z",
// "albedo.R"); FLOAT like the beauty.
struct ExrLayer {
    std::string name;                   // "albedo"
    std::vector<std::string> channels;  // {"R", "G", "B"}
    std::vector<float> pixels;          // channels.size() floats per pixel, row-major, top row first
};

// Where an image's pixels lie in the frame: OpenEXR's data window inside its
// display window (a tile of a render: `render --tile`, `merge`).
struct ExrWindow {
    PixelRect data;     // the pixels held; its size is the image's
    PixelRect display;  // the whole frame, from (0, 0)
};

// The window of an image that is the whole frame.
inline ExrWindow wholeFrame(const Image& img) {
    const PixelRect r{0, 0, img.width, img.height};
    return {r, r};
}

// Writes FLOAT R, G, B, A with ZIP compression, and the `layers` in the same
// (single-part) file; `attributes` become string attributes in the header
// (render settings, provenance). Written atomically. Throws InputError for an
// empty image, a duplicate / reserved attribute or channel name or a layer
// of the wrong size, IoError when the file cannot be written.
// `window` places the image in a larger frame (default: the whole frame);
// InputError when its data window is not the image's size or lies outside
// the display window.
void writeExr(const std::string& path, const Image& img, const StringAttributes& attributes = {},
              const std::vector<ExrLayer>& layers = {}, const std::optional<ExrWindow>& window = std::nullopt);

// Reads R, G, B (and A if present, else 1) of any pixel type as float; the
// image covers the file's data window. Throws IoError if the file cannot be
// opened, InputError if it is not a readable OpenEXR file or lacks R, G or B.
Image readExr(const std::string& path);

// Everything a vdbmarch EXR holds: RGBA, the other channels as layers
// (grouped by the name before their last '.', channels in the file's
// order), both windows and the string attributes.
struct ExrContents {
    Image image;
    ExrWindow window;
    std::vector<ExrLayer> layers;
    StringAttributes attributes;
};
ExrContents readExrContents(const std::string& path);

// The layer named `name` among `layers`, or null.
const ExrLayer* findLayer(const std::vector<ExrLayer>& layers, const std::string& name);
// Channel `c` of each of a layer's `pixels` pixels (a file stores its
// channels in name order); empty when the layer has no such channel.
std::vector<float> layerChannel(const ExrLayer& layer, const std::string& c, size_t pixels);

// All string attributes of the header, sorted by name.
StringAttributes readExrStringAttributes(const std::string& path);

}  // namespace vdbmarch
