// The candidate filters of docs/denoise.md: the two half renders cleaned,
// firefly-clamped and with their variance (steps 1, 2 and 8), and the
// cross-filtered NL-means candidates of several strengths, plus the
// alpha-regression candidate (steps 4 to 7). Internal to src/denoise.
#pragma once

#include "denoise/denoise.h"
#include "denoise/denoise_features.h"
#include "denoise/denoise_planes.h"

#include <vector>

namespace vdbmarch::denoising {

// The colour (and alpha, where the input has it) of both halves, one plane
// per channel.
struct ColourHalves {
    int channels = 3;  // 4 with alpha
    // Each half, cleaned (step 1) and firefly-clamped (step 8), and the
    // variance of one half (step 2), for every channel.
    std::vector<Plane> a, b, variance;
    // `clamped`: the colour's mean of the two halves after the firefly
    // clamp; `clampedLight`: what the clamp took (the mean of the two
    // halves' excess), empty without the clamp.
    std::vector<Plane> clamped, clampedLight;
};

ColourHalves loadColourHalves(const DenoiseInput& in, const DenoiseOptions& options, int pad);

// Every candidate's output, per channel of the halves, and its dF/dy: the
// weight of each pixel's own value in its output, for SURE.
struct Candidates {
    std::vector<std::vector<Plane>> filtered;
    std::vector<Plane> inverse;
};

// The candidates of options.candidates strengths, then the alpha-regression
// candidate where options.alphaRegression is on and the halves have alpha.
Candidates filterCandidates(const ColourHalves& halves, const std::vector<Feature>& features,
                            const DenoiseOptions& options);

}  // namespace vdbmarch::denoising
