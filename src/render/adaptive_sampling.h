// Adaptive sampling (docs/noise.md): which pixels stop receiving samples,
// decided per block of pixels from the two halves' noise, towards a noise
// target (render.noise) or within a timed render's budget
// (experiments.adaptive). The decisions depend only on the sums and the
// measured times, never on the thread count.
#pragma once

#include <vector>

#include "render/film.h"

namespace vdbmarch {

// The sample counts at which adaptive sampling decides: 16, then every
// quarter more (at least 4). nextNoiseCheck(n) is the first one above n.
int nextNoiseCheck(int n);
bool isNoiseCheck(int n);

// The noise target (render.noise) at a check after n samples of a
// ww x wh window whose photon pass `open` is not yet folded into `sums`:
// true once the estimated RMSE is below noise x the mean; until then it
// stops the blocks that have their share (sums.convergedAt = n).
bool noiseTargetStep(PixelSums& sums, const PhotonPassSums& open, float noise, int ww, int wh, int n);

// Each pixel's camera time in a timed adaptive render: seconds summed over
// the samples this process rendered, and how many.
struct PixelTimes {
    std::vector<double> seconds;
    std::vector<int> samples;
};

// What the denoiser leaves of each block's noise, from a denoised frame's
// estimated variance per pixel (`denoised`): K_b = the block's summed pixel
// variance over its summed denoised variance, at least 1 and at most
// MaxDenoiserGain.
std::vector<double> denoiserGains(const PixelSums& frame, const std::vector<float>& denoised, int ww, int wh);

// Adaptive sampling of a timed render at a check after n samples, with
// `secondsLeft` of camera time left (summed over the threads) and the
// denoiser's gains per block (empty: none). True when every pixel stopped.
bool timedAdaptiveStep(PixelSums& sums, const PhotonPassSums& open, const PixelTimes& times,
                       const std::vector<double>& gains, int ww, int wh, int n, double secondsLeft);

// A timed render's last sample, when the time left buys only part of one:
// keeps about `share` of the blockSize x blockSize blocks that still sample
// (those with a pixel whose convergedAt is 0), taken in a fixed order spread
// over the frame, and stops the still-sampling pixels of the others at n
// samples (convergedAt = n). False, changing nothing, when it keeps none.
bool keepShareOfBlocks(std::vector<int>& convergedAt, int width, int height, int blockSize, double share, int n);

}  // namespace vdbmarch
