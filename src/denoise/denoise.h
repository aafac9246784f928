// Feature-guided NL-means denoiser for Monte Carlo volume renders: two
// half renders (the means over the even and the odd samples of each pixel)
// give a per-pixel variance and cross-filtered estimates (Rousselle, Knaus
// and Zwicker 2012), optional first-event features sharpen the weights at
// edges the colour cannot see (Rousselle, Manzi and Zwicker 2013).
// docs/denoise.md describes the algorithm, its parameters and its figures.
#pragma once

#include "core/math.h"
#include "image/image.h"

#include <vector>

namespace vdbmarch {

// Per pixel of a width x height frame (row-major, top row first). Every
// vector has width*height entries, or is empty when absent.
struct DenoiseInput {
    int width = 0, height = 0;
    // The means of the beauty over the even-index and the odd-index samples
    // of each pixel (two independent half renders): RGB and alpha. The halves
    // are required; alpha may be absent (both empty: the output is opaque).
    std::vector<Color> halfA, halfB;
    std::vector<float> alphaA, alphaB;
    // Optional (both or neither): the part of each half emitted by media and
    // lights and seen with no scattering (sharp, and nearly noise-free where
    // the renderer integrates emission smoothly). The rest, the scattered
    // light, is denoised apart from it, and the emitted part on its own: a
    // fire's sharp base is not averaged with the smoke's noisy glow.
    std::vector<Color> emittedA, emittedB;
    // Optional features, each the mean over all the pixel's samples (noisy
    // in volumes: the first event is stochastic), see docs/aovs.md.
    std::vector<Color> albedo;  // first-event albedo (0: nothing met)
    std::vector<Color> normal;  // first-event normal (not renormalised)
    std::vector<float> depth;   // camera-space depth; 1e10 where nothing was met
};

struct DenoiseOptions {
    int threads = 0;  // 0: all cores
    // NL-means of the colour (Rousselle et al. 2012): the search window is
    // (2 searchRadius + 1)^2 pixels, a patch (2 patchRadius + 1)^2.
    int searchRadius = 9;
    int patchRadius = 3;
    // k_c: how far two patches may differ, in standard deviations of their
    // noise, and still be averaged. Larger smooths more.
    float colorStrength = 0.45f;
    // Candidate filters of strengths k_c, 2 k_c, 4 k_c, ..., blended per
    // pixel by their estimated error (SURE, Rousselle et al. 2013) over boxes
    // of (2 selectionRadius + 1)^2 pixels; 1: the k_c filter alone.
    int candidates = 2;
    // One more candidate for that choice, where the input has alpha: the
    // intercept of a weighted line fit of the values against the other
    // half's alpha (first-order regression, as NFOR fits its features),
    // with the strongest candidate's weights. The slope's ridge is
    // (regressionRidge + regressionNoiseRidge x 2 Var[alpha'](p)) x the sum
    // of the weights: the second term scales the expected square of the
    // feature's own noise (a difference of two pixels' alpha), so where
    // alpha varies no more than its noise (inside a cloud at a few samples
    // per pixel) the slope is shrunk to 0 and the fit is the weighted mean.
    bool alphaRegression = true;
    float regressionRidge = 1e-3f;
    float regressionNoiseRidge = 4.f;
    int selectionRadius = 2;
    // Radius of the box that smooths the two-half variance estimate (1
    // degree of freedom per pixel on its own): 2 is 5x5.
    int varianceRadius = 2;
    // Feature weights (Rousselle et al. 2013): k_f, the tolerance in feature
    // noise standard deviations, and tau, the floor of the squared feature
    // difference scale (features are normalised to about [0, 1]).
    bool useFeatures = true;
    // Clamp each half to twice the other half's 3x3 maximum plus its mean
    // before filtering: a firefly in one half would otherwise spread over a
    // search window.
    bool suppressFireflies = true;
    // The denoised image keeps the noisy image's local means: the Gaussian
    // average (this standard deviation, in pixels) of what filtering changed
    // is added back, so the denoiser adds no bias at larger scales. 0: off.
    float restoreSigma = 4.f;
    // What the firefly clamp took is added back spread by a Gaussian of this
    // standard deviation (pixels): a faint haze, and no light lost. 0: the
    // clamp's light is dropped (biased).
    float fireflySigma = 32.f;
    float featureStrength = 0.6f;
    float featureThreshold = 1e-3f;
    // The features are first denoised by NL-means guided by themselves
    // (search radius, patch radius, k), as NFOR (Bitterli et al. 2016) does.
    int featureSearchRadius = 5;
    int featurePatchRadius = 1;
    float featurePrefilterStrength = 0.5f;
};

// Returns the denoised RGBA image (width x height). Deterministic:
// bit-identical for any thread count. Never outputs NaN or Inf: non-finite
// inputs are replaced (a half by the other half, else by its finite
// neighbours; a feature by "nothing met"). Throws std::invalid_argument when
// a vector's size is not width*height (or not empty where that is allowed),
// on a negative size and on options out of range.
// With `variances`, also each pixel's estimated noise variance in the
// output (RGB summed, width*height entries): the noisy mean's variance (from
// the halves, step 2) times the weight of the pixel's own value in its
// output, plus the variance of the local means it restores, plus the
// emitted part's. The filter's bias is not in it. Adaptive
// sampling weighs a block's noise by what the denoiser leaves of it
// (docs/noise.md, "Timed renders").
Image denoise(const DenoiseInput& in, const DenoiseOptions& options = {}, std::vector<float>* variances = nullptr);

}  // namespace vdbmarch
