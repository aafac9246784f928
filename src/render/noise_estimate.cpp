#include "render/noise_estimate.h"

#include <algorithm>
#include <cmath>

namespace vdbmarch {

bool pixelNoise(const Color& L, const Color& oddL, int first, int n, Color& mean, Color& variance) {
    int ne, no;
    halfCounts(first, n, ne, no);
    if (ne == 0 || no == 0) return false;
    mean = L / float(n);
    const Color d = (L - oddL) / float(ne) - oddL / float(no);
    variance = d * d * float(double(ne) * double(no) / (double(n) * double(n)));
    return true;
}

NoiseEstimate NoiseTotals::estimate() const {
    NoiseEstimate e;
    const double n = 3.0 * double(std::max<size_t>(1, pixels));
    e.valid = pixels > 0;
    e.rmse = std::sqrt(variance / n);
    e.mean = mean / n;
    return e;
}

NoiseEstimate estimateNoise(const PixelSums& sums, int firstSample) {
    NoiseTotals totals;
    for (size_t p = 0; p < sums.L.size(); ++p) {
        Color mean, var;
        if (!pixelNoise(sums.L[p], sums.oddL[p], firstSample, sums.samplesOf(p), mean, var)) return {};
        totals.add(mean, var);
    }
    return totals.estimate();
}

}  // namespace vdbmarch
