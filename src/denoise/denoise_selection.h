// Steps 7 and 9 of docs/denoise.md: the candidate filters blended per pixel
// by their estimated error (SURE), the output's noise variance, and the
// noisy image's local means and the clamped light given back. Internal to
// src/denoise.
#pragma once

#include "denoise/denoise.h"
#include "denoise/denoise_planes.h"

#include <vector>

namespace vdbmarch::denoising {

// Per pixel, the candidate filter of least estimated error, blended
// smoothly (Rousselle, Manzi and Zwicker 2013, section 5). A candidate F's
// error at p is estimated by Stein's unbiased risk estimate,
//   SURE(p) = |F(p) - y(p)|^2 - s^2(p) + 2 s^2(p) dF(p)/dy(p),
// y the mean of the clamped halves (what the candidates averaged), s^2 its
// variance per channel (half the variance of a half), dF/dy = `inverse` (the pixel's own weight over the sum of the
// weights; the weights' own dependence on y is left out, as in the paper).
// One pixel's estimate is noisy, so it is box-averaged over
// (2 radius + 1)^2 pixels before the choice, and the one-hot choices are
// box-averaged again into blending weights: no seams between regions.
// With `ownWeight`, also the blend's dF/dy per pixel: the weight of the
// pixel's own value in its output (the candidates' `inverse` in the blend's
// proportions).
std::vector<Plane> selectCandidates(const std::vector<std::vector<Plane>>& filtered, const std::vector<Plane>& inverse,
                                    const std::vector<Plane>& clamped, const std::vector<Plane>& variance,
                                    int radius, Plane* ownWeight);

// The output's noise variance per pixel (docs/denoise.md, "The output's
// noise"), RGB summed, into `out`: the noisy mean's (half a half's
// `variance`, step 2) times the pixel's own weight in its output, the
// variance of a mean of equally noisy values with weights 0 and 1; plus
// that of the restored local means, a Gaussian average of the noise
// (1 / (4 pi sigma^2) of it), whose noise at scales beyond the Gaussian is
// the noisy image's own. Both average the same noise over similar
// areas, so the sum counts their overlap twice: that keeps adaptive sampling
// from starving smooth regions, whose low-frequency noise the restored means
// keep (BENCHMARKS.md). The filter's bias is not in it (the blend's SURE,
// tried as this estimate, went negative in flat regions).
void estimateOutputVariance(const std::vector<Plane>& variance, const Plane& ownWeight, float restoreSigma,
                            std::vector<float>& out);

// Step 9 on the colour of `selected`: the noisy image's local means
// (`clamped`) restored, and the light the firefly clamp took
// (`clampedLight`) given back.
void restoreLocalMeans(std::vector<Plane>& selected, const std::vector<Plane>& clamped,
                       const std::vector<Plane>& clampedLight, const DenoiseOptions& options);

}  // namespace vdbmarch::denoising
