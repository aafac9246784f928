// The noise of a render estimated from its two half renders (even- and
// odd-index samples), without a reference (docs/noise.md, "The estimate").
#pragma once

#include <cstddef>

#include "core/math.h"
#include "render/film.h"

namespace vdbmarch {

// The noise of a render estimated from its two halves, without a
// reference: per pixel the variance of the mean is (m_even - m_odd)^2
// n_even n_odd / n^2, and rmse is its root mean over pixels and RGB, the
// figure `vdbmarch compare` prints against the truth (docs/noise.md).
struct NoiseEstimate {
    bool valid = false;  // at least 2 samples per pixel
    double rmse = 0;     // estimated RMSE of the RGB against the converged image
    double mean = 0;     // mean of the RGB
    double relative() const { return mean > 0 ? rmse / mean : 0.0; }
};
// `firstSample`: the index of the sums' first sample (a part by photon
// passes starts mid-render), which says which samples are the odd ones.
NoiseEstimate estimateNoise(const PixelSums& sums, int firstSample = 0);

// Mean and variance of the mean of one pixel from its sums over n samples
// starting at sample `first` (the two halves' difference, NoiseEstimate).
// False where one half has no sample.
bool pixelNoise(const Color& L, const Color& oddL, int first, int n, Color& mean, Color& variance);

// The image's NoiseEstimate from its pixels' means and variances, RGB summed.
struct NoiseTotals {
    double variance = 0, mean = 0;
    size_t pixels = 0;
    void add(const Color& m, const Color& v) {
        variance += double(v.x) + double(v.y) + double(v.z);
        mean += double(m.x) + double(m.y) + double(m.z);
        ++pixels;
    }
    NoiseEstimate estimate() const;
};

}  // namespace vdbmarch
