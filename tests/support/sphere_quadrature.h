// Quadrature over the unit sphere for tests of direction samplers: cells of
// equal area in (z, phi), Gauss-Legendre nodes in each.
#pragma once

#include <cmath>
#include <vector>

#include "cache/sh.h"
#include "core/math.h"

namespace vdbmarch::test {

inline Vec3 fromZPhi(double z, double phi) {
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    return Vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
}

// Integral of f(w) over the sphere: nz x 2 nz cells in (z, phi), n x n
// Gauss-Legendre nodes per cell.
template <typename F>
double sphereIntegral(F&& f, int nz, int n) {
    std::vector<double> x, w;
    gaussLegendre(n, x, w);
    const int np = 2 * nz;
    const double dz = 2.0 / nz, dp = 2 * PiD / np;
    double sum = 0;
    for (int iz = 0; iz < nz; ++iz)
        for (int ip = 0; ip < np; ++ip)
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    const double z = -1 + (iz + 0.5 + 0.5 * x[size_t(a)]) * dz;
                    const double phi = (ip + 0.5 + 0.5 * x[size_t(b)]) * dp;
                    sum += f(fromZPhi(z, phi)) * w[size_t(a)] * w[size_t(b)] * 0.25 * dz * dp;
                }
    return sum;
}

}  // namespace vdbmarch::test
