// 8-bit sRGB PNG output for previews and diff images; reading is for tests.
#pragma once

#include "image/image.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vdbmarch {

// The sRGB transfer curve (IEC 61966-2-1) and its inverse, on [0, 1].
float linearToSrgb(float v);
float srgbToLinear(float v);

// 8-bit RGB: each channel is scaled by 2^exposureStops, sRGB-encoded and
// clamped to [0, 1]; non-finite values become 0. Alpha is dropped. Written
// atomically. Throws InputError for an empty image, IoError on write failure.
void writePng(const std::string& path, const Image& img, float exposureStops = 0);

// writePng's tone mapping alone: 3 bytes per pixel, top row first, so other
// layouts (the bench's image strip) show pixels exactly as the PNG preview does.
std::vector<uint8_t> toSrgb8(const Image& img, float exposureStops = 0);

// Writes already display-encoded 8-bit RGB (3 bytes per pixel, top row first).
void writePngRgb8(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb);

// Any PNG, converted to 8-bit sRGB RGBA, then to linear float RGB; alpha is
// linear in [0, 1] (1 when the file has none).
Image readPng(const std::string& path);

}  // namespace vdbmarch
