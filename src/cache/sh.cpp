#include "cache/sh.h"

#include <cassert>
#include <cmath>

namespace vdbmarch {

namespace {


// Coefficients of the recurrence for Qbar_l^m = K_lm P_l^m / sin^m theta, a
// polynomial in z whose magnitude stays O(1) (the raw P_m^m = (2m-1)!! would
// not):
//   Qbar_m^m     = -sqrt((2m+1)/(2m)) Qbar_{m-1}^{m-1},  Qbar_0^0 = 1/sqrt(4 pi)
//   Qbar_{m+1}^m = sqrt(2m+3) z Qbar_m^m
//   Qbar_l^m     = a_lm z Qbar_{l-1}^m - b_lm Qbar_{l-2}^m
//   a_lm = sqrt((4l^2-1)/(l^2-m^2)),  b_lm = sqrt((2l+1)((l-1)^2-m^2)/((2l-3)(l^2-m^2)))
// The sqrt(2) of the m != 0 real harmonics is folded into the diagonal.
struct ShRecurrence {
    float diag[MaxShOrder + 1];
    float sub[MaxShOrder + 1];
    float a[MaxShOrder + 1][MaxShOrder + 1];
    float b[MaxShOrder + 1][MaxShOrder + 1];

    ShRecurrence() {
        double q = 1 / std::sqrt(4 * PiD);
        for (int m = 0; m <= MaxShOrder; ++m) {
            if (m > 0) q *= -std::sqrt((2.0 * m + 1) / (2.0 * m));
            diag[m] = float(m > 0 ? std::sqrt(2.0) * q : q);
            sub[m] = float(std::sqrt(2.0 * m + 3));
            for (int l = 0; l <= MaxShOrder; ++l) {
                a[l][m] = b[l][m] = 0;
                if (l < m + 2) continue;
                double l2 = double(l) * l, m2 = double(m) * m, lm1 = double(l - 1);
                a[l][m] = float(std::sqrt((4 * l2 - 1) / (l2 - m2)));
                b[l][m] = float(std::sqrt((2.0 * l + 1) * (lm1 * lm1 - m2) / ((2.0 * l - 3) * (l2 - m2))));
            }
        }
    }
};

// Function-local so evalSh is safe from other translation units' static
// initialisers; the guard is one predictable branch per call.
const ShRecurrence& recurrence() {
    static const ShRecurrence r;
    return r;
}

}  // namespace

void evalShRecurrence(int order, const Vec3& w, float* out) {
    assert(order >= 0 && order <= MaxShOrder);
    const ShRecurrence& r = recurrence();
    const float x = w.x, y = w.y, z = w.z;

    // m = 0: zonal harmonics, no azimuthal factor.
    {
        float q0 = r.diag[0];
        out[0] = q0;
        if (order >= 1) {
            float q1 = r.sub[0] * z * q0;
            out[shIndex(1, 0)] = q1;
            for (int l = 2; l <= order; ++l) {
                float q2 = r.a[l][0] * z * q1 - r.b[l][0] * q0;
                out[shIndex(l, 0)] = q2;
                q0 = q1;
                q1 = q2;
            }
        }
    }

    // c + i s = (x + i y)^m = sin^m theta (cos m phi + i sin m phi).
    float c = 1, s = 0;
    for (int m = 1; m <= order; ++m) {
        float cNext = x * c - y * s;
        s = x * s + y * c;
        c = cNext;
        float q0 = r.diag[m];
        out[shIndex(m, m)] = q0 * c;
        out[shIndex(m, -m)] = q0 * s;
        if (m == order) break;
        float q1 = r.sub[m] * z * q0;
        out[shIndex(m + 1, m)] = q1 * c;
        out[shIndex(m + 1, -m)] = q1 * s;
        for (int l = m + 2; l <= order; ++l) {
            float q2 = r.a[l][m] * z * q1 - r.b[l][m] * q0;
            out[shIndex(l, m)] = q2 * c;
            out[shIndex(l, -m)] = q2 * s;
            q0 = q1;
            q1 = q2;
        }
    }
}

void evalSh(int order, const Vec3& w, float* out) {
    assert(order >= 0 && order <= MaxShOrder);
    if (order > 3) {
        evalShRecurrence(order, w, out);
        return;
    }
    // Expanded forms of the same basis (Sloan 2008, appendix A2), valid for
    // unit w; constants are K_lm times the integer factors of P_l^m.
    const float x = w.x, y = w.y, z = w.z;
    out[0] = 0.28209479177387814f;
    if (order < 1) return;
    out[1] = -0.4886025119029199f * y;
    out[2] = 0.4886025119029199f * z;
    out[3] = -0.4886025119029199f * x;
    if (order < 2) return;
    const float xx = x * x, yy = y * y, zz = z * z;
    out[4] = 1.0925484305920792f * x * y;
    out[5] = -1.0925484305920792f * y * z;
    out[6] = 0.31539156525252005f * (3 * zz - 1);
    out[7] = -1.0925484305920792f * x * z;
    out[8] = 0.5462742152960396f * (xx - yy);
    if (order < 3) return;
    out[9] = -0.5900435899266435f * y * (3 * xx - yy);
    out[10] = 2.890611442640554f * x * y * z;
    out[11] = -0.4570457994644658f * y * (5 * zz - 1);
    out[12] = 0.3731763325901154f * z * (5 * zz - 3);
    out[13] = -0.4570457994644658f * x * (5 * zz - 1);
    out[14] = 1.445305721320277f * z * (xx - yy);
    out[15] = -0.5900435899266435f * x * (xx - 3 * yy);
}

void legendrePolynomials(int order, double x, double* out) {
    out[0] = 1;
    if (order < 1) return;
    out[1] = x;
    // Bonnet: l P_l = (2l-1) x P_{l-1} - (l-1) P_{l-2}.
    for (int l = 2; l <= order; ++l) out[l] = ((2 * l - 1) * x * out[l - 1] - (l - 1) * out[l - 2]) / l;
}

void gaussLegendre(int n, std::vector<double>& x, std::vector<double>& w) {
    assert(n >= 1);
    x.assign(n, 0.0);
    w.assign(n, 0.0);
    // Nodes are symmetric: Newton on P_n for the positive half, from the
    // asymptotic guess cos(pi (i + 3/4) / (n + 1/2)), then mirror.
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double r = std::cos(PiD * (i + 0.75) / (n + 0.5));
        double dp = 1;
        for (int iter = 0; iter < 100; ++iter) {
            double p0 = 1, p1 = r;  // P_{k-1}, P_k at k = 1
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2 * k - 1) * r * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            // P_n'(r) = n (r P_n - P_{n-1}) / (r^2 - 1); r never reaches +-1.
            dp = n * (r * p1 - p0) / (r * r - 1);
            double dr = p1 / dp;
            r -= dr;
            if (std::fabs(dr) <= 1e-15) break;  // quadratic convergence: one more step is noise
        }
        double wi = 2 / ((1 - r * r) * dp * dp);
        x[i] = -r;
        x[n - 1 - i] = r;
        w[i] = w[n - 1 - i] = wi;
    }
    if (n % 2 == 1) x[n / 2] = 0;
}

void phaseLegendreWeights(int order, const std::function<double(double)>& phase, double* out,
                          int nodes) {
    std::vector<double> x, w;
    gaussLegendre(nodes, x, w);
    std::vector<double> p(order + 1);
    std::fill(out, out + order + 1, 0.0);
    for (int i = 0; i < nodes; ++i) {
        legendrePolynomials(order, x[i], p.data());
        double f = w[i] * phase(x[i]);
        for (int l = 0; l <= order; ++l) out[l] += f * p[l];
    }
    for (int l = 0; l <= order; ++l) out[l] *= 2 * PiD;
}

void shConvolvePhase(int order, const float* legendreWeights, const float* radianceCoeffs,
                     float* out) {
    for (int l = 0; l <= order; ++l) {
        const float wl = legendreWeights[l];
        for (int m = -l; m <= l; ++m) out[shIndex(l, m)] = wl * radianceCoeffs[shIndex(l, m)];
    }
}

}  // namespace vdbmarch
