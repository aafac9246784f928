// Image comparison for convergence and regression checks against references.
#pragma once

#include "image/image.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace vdbmarch {

// Statistics over the RGB channels (alpha is ignored) of the pixels that are
// finite in both images. With no such pixel the means are NaN.
struct ImageErrorStats {
    double rmse = 0;             // sqrt(mean (a-b)^2)
    double relMse = 0;           // mean (a-b)^2 / (b^2 + 1e-2)
    double meanAbsRelError = 0;  // mean |a-b| / (|b| + 1e-2)
    size_t nonFiniteA = 0;       // pixels with a NaN/inf RGB value in the test image
    size_t nonFiniteB = 0;       // ... in the reference image
    double meanA = 0, meanB = 0; // mean RGB value of each image over the compared pixels
    size_t pixels = 0;           // pixels compared (finite in both images)
};

// Throws InputError if the sizes differ.
ImageErrorStats compareImages(const Image& test, const Image& reference);

// PNG of the per-pixel error |a-b| averaged over RGB, divided by its 99th
// percentile (so a few fireflies do not wash out the rest) and mapped through
// the viridis ramp: dark purple = no error, yellow = at or above the 99th
// percentile. Pixels non-finite in either image are magenta.
void writeFalseColorDiff(const std::string& path, const Image& test, const Image& reference);

// matplotlib's viridis colour map at t in [0, 1] (clamped), as 8-bit sRGB.
void viridisColor(double t, uint8_t out[3]);

}  // namespace vdbmarch
