// exp(-tau) without bias from estimates of tau: the power series of
// Kettunen et al. 2021 ("An unbiased ray-marching transmittance estimator",
// TOG 40(4)). About a pivot tau_p,
//     exp(-tau) = exp(-tau_p) sum_k (tau_p - tau)^k / k!,
// each power estimated by the elementary symmetric mean of independent
// estimates of (tau_p - tau), the order cut by Russian roulette. Every one of
// the n = K + 1 optical-depth estimates serves as the pivot in turn and the
// results are averaged (a U-statistic), so the first-order terms nearly cancel
// and the estimate is close to exp(-mean) when the estimates agree.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math.h"

namespace vdbmarch {

// The order K of the series: 0 with probability pZero (the pivot alone,
// one optical-depth estimate), otherwise at least MinOrder and beyond that
// Bhanot & Kennedy roulette, going on from k - 1 to k with probability
// min(1, 2 / k). Capped at MaxOrder, which the roulette reaches with
// probability below 1e-30.
class SeriesOrder {
public:
    static constexpr int MinOrder = 2;
    static constexpr int MaxOrder = 40;

    explicit SeriesOrder(double pZero) : pZero_(pZero) {}

    // P(K >= k).
    double atLeast(int k) const {
        if (k <= 0) return 1.0;
        double p = 1.0 - pZero_;
        for (int j = MinOrder + 1; j <= k; ++j) p *= std::min(1.0, 2.0 / j);
        return p;
    }

    // K for a uniform u in [0, 1): the largest k with u < P(K >= k).
    int sample(double u) const {
        int k = 0;
        double next = 1.0 - pZero_;  // P(K >= 1)
        while (k < MaxOrder && u < next) {
            ++k;
            if (k + 1 > MinOrder) next *= std::min(1.0, 2.0 / (k + 1));
        }
        return k;
    }

private:
    double pZero_;
};

// The transmittance per channel from n = order + 1 independent, unbiased
// estimates of an optical depth in density units (d[0..n), each an estimate
// of the same integral of the density), the extinction k per unit density,
// and the order's distribution. Unbiased for exp(-k D); may be negative or
// above 1 for one sample. `means` is scratch of at least n doubles.
inline Color powerSeriesTransmittance(const double* d, int order, const Color& k, const SeriesOrder& dist,
                                      double* means) {
    const int n = order + 1;
    double weight[SeriesOrder::MaxOrder + 1];  // 1 / (m! P(K >= m))
    double factorial = 1;
    for (int m = 0; m <= order; ++m) {
        if (m > 0) factorial *= m;
        weight[m] = 1.0 / (factorial * dist.atLeast(m));
    }
    double T[3] = {0, 0, 0};
    for (int p = 0; p < n; ++p) {
        // Elementary symmetric means S_m of y_j = d[p] - d[j], j != p: the
        // mean over all m-subsets of their products, updated one value at a
        // time (S_m += m / (i + 1) (S_{m-1} y - S_m)).
        means[0] = 1;
        for (int m = 1; m <= order; ++m) means[m] = 0;
        int i = 0;
        for (int j = 0; j < n; ++j) {
            if (j == p) continue;
            const double y = d[p] - d[j];
            for (int m = i + 1; m >= 1; --m) means[m] += double(m) / (i + 1) * (means[m - 1] * y - means[m]);
            ++i;
        }
        for (int c = 0; c < 3; ++c) {
            const double kc = k[c];
            if (!(kc > 0)) {
                T[c] += 1;  // no extinction in this channel
                continue;
            }
            double sum = 0, kPow = 1;
            for (int m = 0; m <= order; ++m) {
                sum += kPow * means[m] * weight[m];
                kPow *= kc;
            }
            const double term = std::exp(-kc * d[p]) * sum;
            if (std::isfinite(term)) T[c] += term;  // exp(-huge) x a huge polynomial: light is gone
        }
    }
    return Color(float(T[0] / n), float(T[1] / n), float(T[2] / n));
}

}  // namespace vdbmarch
