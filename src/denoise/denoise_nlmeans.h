// The NL-means core that the feature prefilter and the candidate filters
// share: patch distances of one offset over a tile, and distances to weights.
// Internal to src/denoise.
#pragma once

#include "denoise/denoise_planes.h"

#include <cstdint>
#include <cstring>
#include <vector>

namespace vdbmarch::denoising {

// Distances are clamped to [0, 87] before expMinus: a negative distance
// (two values closer than their noise) weighs 1, and e^-87 < 2e-38 is as good
// as 0. A loop of its own, since a clamp in the loop of the exponential keeps
// GCC from vectorising it (the conversion to int may trap).
inline float clampDistance(float d) {
    d = d > 0.f ? d : 0.f;
    return d < 87.f ? d : 87.f;
}

// e^-d for d in [0, 87] without a library call, so the weight loops
// vectorise: -d = (i + f) / log2(e) with f in [-1/2, 1/2], 2^f by its Taylor
// series to degree 6, 2^i in the exponent bits. Relative error below 7e-7
// for d < 10 and 4e-6 near 87 (the rounding of d log2(e) dominates).
inline float expMinus(float d) {
    const float t = d * -1.44269504f;
    const int i = int(t - 0.5f);  // t <= 0: truncation rounds to nearest
    const float f = (t - float(i)) * 0.693147181f;
    const float p =
        1.f + f * (1.f + f * (0.5f + f * (1.f / 6 + f * (1.f / 24 + f * (1.f / 120 + f * (1.f / 720))))));
    const int32_t bits = (i + 127) << 23;
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return p * scale;
}

// Patch distances: the NL-means distance of Rousselle, Knaus and Zwicker
// 2012, with the variance cancellation, as Rousselle, Manzi and Zwicker 2013
// use it for their colour weights. Per channel i
//   d_i^2(p, q) = ((u_i(p) - u_i(q))^2 - (Var_i[p] + min(Var_i[p], Var_i[q])))
//                 / (eps + k^2 (Var_i[p] + Var_i[q])),
// averaged over the channels and over the (2f+1)^2 pixel pairs (p+n, q+n) of
// the two patches; the weight is exp(-max(0, d^2)). The variance terms cancel
// the expected squared difference of two noisy values, so equal means give a
// distance of about 0 whatever the noise.

// The values whose patches are compared, one plane per channel, with their
// variances. `secondValues`, when given, are the other half render: both
// halves' distances come from one pass, as they share the variances and so
// the division.
struct Guide {
    std::vector<const Plane*> values, secondValues, variances;
    float k2 = 1;    // k^2
    float norm = 1;  // 1 / (channels (2f+1)^2)
};

// Scratch of the box filter, sized for one tile and two sets of values.
struct BoxScratch {
    std::vector<float> rowDistance, horizontal, column;
    BoxScratch(int tile, int f)
        : rowDistance(2 * size_t(tile + 2 * f) * size_t(tile + 2 * f)),
          horizontal(2 * size_t(tile + 2 * f) * size_t(tile)), column(size_t(tile)) {}
};

// Patch distances of one offset for every pixel of `r`: the pixel distances
// of the rectangle grown by f, box-filtered by running sums along the rows,
// then down the columns, so the cost per pixel does not depend on the patch
// size. out[(y - r.y0) * r.width() + (x - r.x0)] = the (unnormalised) sum;
// second[] the same for the guide's second values.
void patchDistances(const Guide& g, const Rect& r, int dx, int dy, int f, BoxScratch& s, float* out,
                    float* second);

}  // namespace vdbmarch::denoising
