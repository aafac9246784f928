// Chi-square goodness of fit for the sampler tests.
#pragma once

#include <cmath>

namespace vdbmarch {
namespace testing {

// Upper-tail probability of the chi-square distribution (regularised
// incomplete gamma Q(k/2, x/2)) by series / continued fraction.
inline double chiSquareQ(double x, double dof) {
    double a = dof / 2, xx = x / 2;
    if (xx <= 0) return 1;
    double gln = std::lgamma(a);
    if (xx < a + 1) {
        double sum = 1 / a, del = sum, ap = a;
        for (int n = 0; n < 1000; ++n) {
            ap += 1;
            del *= xx / ap;
            sum += del;
            if (std::fabs(del) < std::fabs(sum) * 1e-14) break;
        }
        return 1 - sum * std::exp(-xx + a * std::log(xx) - gln);
    }
    double b = xx + 1 - a, c = 1e300, d = 1 / b, h = d;
    for (int i = 1; i < 1000; ++i) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::fabs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (std::fabs(c) < 1e-300) c = 1e-300;
        d = 1 / d;
        double del = d * c;
        h *= del;
        if (std::fabs(del - 1) < 1e-14) break;
    }
    return std::exp(-xx + a * std::log(xx) - gln) * h;
}

}  // namespace testing
}  // namespace vdbmarch
