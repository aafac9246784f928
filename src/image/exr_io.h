// OpenEXR output (the renderer's primary format) and input (reference images).
#pragma once

#include "image/image.h"

#include <string>
#include <utility>
#include <vector>

namespace vdbmarch {

using StringAttributes = std::vector<std::pair<std::string, std::string>>;

// Writes FLOAT R, G, B, A with ZIP compression; `attributes` become string
// attributes in the header (render settings, provenance). Written atomically.
// Throws InputError for an empty image or a duplicate / reserved attribute
// name, IoError when the file cannot be written.
void writeExr(const std::string& path, const Image& img, const StringAttributes& attributes = {});

// Reads R, G, B (and A if present, else 1) of any pixel type as float; the
// image covers the file's data window. Throws IoError if the file cannot be
// opened, InputError if it is not a readable OpenEXR file or lacks R, G or B.
Image readExr(const std::string& path);

// All string attributes of the header, sorted by name.
StringAttributes readExrStringAttributes(const std::string& path);

}  // namespace vdbmarch
