// OpenEXR output (the renderer's primary format) and input (reference images).
#pragma once

#include "image/image.h"

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

// Writes FLOAT R, G, B, A with ZIP compression, and the `layers` in the same
// (single-part) file; `attributes` become string attributes in the header
// (render settings, provenance). Written atomically. Throws InputError for an
// empty image, a duplicate / reserved attribute or channel name or a layer
// of the wrong size, IoError when the file cannot be written.
void writeExr(const std::string& path, const Image& img, const StringAttributes& attributes = {},
              const std::vector<ExrLayer>& layers = {});

// Reads R, G, B (and A if present, else 1) of any pixel type as float; the
// image covers the file's data window. Throws IoError if the file cannot be
// opened, InputError if it is not a readable OpenEXR file or lacks R, G or B.
Image readExr(const std::string& path);

// All string attributes of the header, sorted by name.
StringAttributes readExrStringAttributes(const std::string& path);

}  // namespace vdbmarch
