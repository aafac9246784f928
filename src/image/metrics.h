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

// How evenly the error is spread over the image (the paper's "almost
// homogeneous image quality"): per pixel, the relative error
// e = mean over RGB of |a-b| / (|b| + eps), eps = RelSpreadEpsilonFraction x
// the reference's mean RGB value over the compared pixels (1e-2 absolute when
// that mean is not positive), then nearest-rank percentiles of e (the value at
// sorted index ceil(p n) - 1). Compared pixels: finite in both images, with
// reference alpha >= minReferenceAlpha; all finite pixels when none qualifies.
struct RelErrorSpread {
    double p50 = 0, p95 = 0;
    double ratio = 0;    // p95 / p50; 0 when p95 = 0 (no error at all), inf when only p50 = 0
    double eps = 0;      // the epsilon used
    size_t pixels = 0;   // pixels compared
};
constexpr double RelSpreadEpsilonFraction = 1e-2;

// Throws InputError if the sizes differ. With no pixel to compare, all NaN.
RelErrorSpread relativeErrorSpread(const Image& test, const Image& reference, float minReferenceAlpha = 0.f);

// Low-frequency error: both images averaged over blocks of `block` x `block`
// pixels (per RGB channel; partial blocks at the edges too), the RMSE of the
// block means over the reference's mean RGB value. Blotches and bias show
// here; pixel noise averages out (by 1/block). NaN when the reference mean is
// not positive. Throws InputError if the sizes differ.
double lowFrequencyError(const Image& test, const Image& reference, int block = 8);

// Whether two renders of one scene whose random numbers differ (two
// unbiased estimators, or one drawn in another order) agree: the per-pixel
// differences test - reference over the whole image (region 0) and each
// quadrant (1-4, row by row), per channel (R, G, B, A), as z = their mean
// over its standard error. Pixels non-finite in either image are left out;
// a region whose differences are all zero has z = 0.
struct PairedAgreement {
    static constexpr int Regions = 5, Channels = 4;
    double z[Regions][Channels] = {};
    double maxAbsZ = 0;      // the largest |z|
    int region = 0, channel = 0;  // where
};
// Throws InputError if the sizes differ.
PairedAgreement pairedAgreement(const Image& test, const Image& reference);

// PNG of the per-pixel error |a-b| averaged over RGB, divided by its 99th
// percentile (so a few fireflies do not wash out the rest) and mapped through
// the viridis ramp: dark purple = no error, yellow = at or above the 99th
// percentile. Pixels non-finite in either image are magenta.
void writeFalseColorDiff(const std::string& path, const Image& test, const Image& reference);

// matplotlib's viridis colour map at t in [0, 1] (clamped), as 8-bit sRGB.
void viridisColor(double t, uint8_t out[3]);

}  // namespace vdbmarch
