// Step 3 of docs/denoise.md: the first-event features (albedo, normal,
// depth) as planes, prefiltered, with the scales of their distances, and the
// feature distance the candidate filters weigh by. Internal to src/denoise.
#pragma once

#include "denoise/denoise.h"
#include "denoise/denoise_planes.h"

#include <vector>

namespace vdbmarch::denoising {

// A feature: its channels, denoised, with their summed variance and the
// inverse scale of the feature distance.
struct Feature {
    std::vector<Plane> channels;  // raw, then prefiltered
    std::vector<Plane> variances; // per channel, of the raw values
    Plane varianceSum;            // over the channels, after prefiltering
    Plane inverseScale;           // 1 / (k_f^2 max(tau, Var, |grad|^2))
};

// The features of `in`, normalised to about [0, 1]: albedo and normal as
// they are (0 where nothing was met), depth relative to the median depth;
// prefiltered, with their scales. Empty when options.useFeatures is off or
// `in` has none.
std::vector<Feature> loadFeatures(const DenoiseInput& in, const DenoiseOptions& options, int pad);

// max over the features j of their distance (Rousselle et al. 2013):
//   (|f_j(p) - f_j(q)|^2 - (Var_j[p] + min(Var_j[p], Var_j[q]))) / (k_f^2 max(...)),
// pixel to pixel (the features are prefiltered), for row y, pixels x0 <= x < x1.
void featureRowDistance(const std::vector<Feature>& features, int y, int dx, int dy, int x0, int x1,
                        float* __restrict out, float* __restrict scratch);

}  // namespace vdbmarch::denoising
