// Real spherical harmonics for the directional radiance cache of Tokuyoshi &
// Maruyama, "Fast rendering of participating media with anisotropic
// scattering" (section 3.2, appendix eqs. 20-27).
//
// Convention (Sloan, "Stupid Spherical Harmonics (SH) Tricks", 2008): real,
// orthonormal over the unit sphere, Condon-Shortley phase included, z is the
// polar axis (theta = acos z, phi = atan2(y, x)):
//   Y_l0  =          K_l0 P_l^0(cos theta)
//   Y_lm  = sqrt(2)  K_lm P_l^m(cos theta) cos( m phi)   m > 0
//   Y_lm  = sqrt(2)  K_l|m| P_l^|m|(cos theta) sin(|m| phi)  m < 0
//   K_lm  = sqrt((2l+1)/(4 pi) (l-|m|)!/(l+|m|)!)
// with P_l^m carrying the (-1)^m phase, so e.g. Y_1,-1 = -0.4886 y,
// Y_10 = 0.4886 z, Y_11 = -0.4886 x. Coefficients are stored band by band at
// shIndex(l, m) = l (l + 1) + m. Being real, Y* = Y in eqs. 15, 20-27.
//
// Directions: the cache stores the incident radiance L(w') over the light's
// *travel* direction w'; the phase function argument is dot(w', w) with w the
// scattered direction, matching hgPhase() in transport/phase.h.
#pragma once

#include <algorithm>
#include <functional>
#include <vector>

#include "core/math.h"

namespace vdbmarch {

// Highest band the recurrence tables cover (81 coefficients).
constexpr int MaxShOrder = 8;

// Number of coefficients of an expansion up to band `order` (eq. 14: (K+1)^2).
constexpr int shCount(int order) { return (order + 1) * (order + 1); }

// Flat index of Y_lm, -l <= m <= l.
constexpr int shIndex(int l, int m) { return l * (l + 1) + m; }

// Band l of flat index c, the inverse of shIndex (then m = c - l (l + 1)).
constexpr int shBand(int c) {
    int l = 0;
    while ((l + 1) * (l + 1) <= c) ++l;
    return l;
}

// Y_lm(w) for all l <= order (0 <= order <= MaxShOrder) into
// out[0 .. shCount(order)); w must be unit length. Runs once per camera ray
// and per photon per cell, so orders <= 3 use the expanded polynomials and
// higher orders the recurrence below (no trigonometric calls either way).
void evalSh(int order, const Vec3& w, float* out);

// The general path on its own: normalised associated Legendre recurrence in
// z = cos theta, and cos/sin(m phi) sin^m theta as Re/Im of (x + i y)^m.
// Exposed so tests can hold the expanded low-order path against it.
void evalShRecurrence(int order, const Vec3& w, float* out);

// Legendre polynomials P_0(x) .. P_order(x) by Bonnet's recurrence.
void legendrePolynomials(int order, double x, double* out);

// n-point Gauss-Legendre nodes (ascending) and weights on [-1, 1]; exact for
// polynomials of degree <= 2n - 1.
void gaussLegendre(int n, std::vector<double>& x, std::vector<double>& w);

// Eq. 26, w'_l = 2 pi Int_{-1}^{1} p(u) P_l(u) du, by Gauss-Legendre
// quadrature for any phase function p(u) normalised over the sphere
// (so w'_0 = 1). The quadrature converges geometrically for analytic p; 256
// nodes resolve Henyey-Greenstein to double precision up to |g| ~ 0.95, more
// peaked lobes need more nodes.
void phaseLegendreWeights(int order, const std::function<double(double)>& phase, double* out,
                          int nodes = 256);

// Eqs. 25 and 27 (Funk-Hecke): if radianceCoeffs are the projections F_lm of
// the incident radiance L(w') (eq. 15; for photons sum_p dPhi_p Y_lm(w'_p)),
// then the in-scattered radiance
//   L_i(w) = Int p(dot(w', w)) L(w') dw' = sum_l w'_l sum_m F_lm Y_lm(w),
// i.e. band l is scaled by legendreWeights[l]. out may alias radianceCoeffs.
void shConvolvePhase(int order, const float* legendreWeights, const float* radianceCoeffs,
                     float* out);

// Reconstruction (eq. 14): sum_i coeffs[i] Y[i].
inline float evalShSum(int count, const float* coeffs, const float* Y) {
    float sum = 0;
    for (int i = 0; i < count; ++i) sum += coeffs[i] * Y[i];
    return sum;
}

// max(0, eq. 14). A truncated expansion of a peaked phase lobe (or of a few
// photons) rings and goes negative away from the lobe, and negative radiance is
// meaningless as a sampling pdf. Clamping rather than windowing the bands
// (Hanning, Lanczos) keeps the exact truncated value wherever it is positive,
// instead of blurring every lobe; the zeroed regions are covered by the guided
// marcher, which mixes a transmittance-only pdf in defensively so cells clamped
// to zero keep non-zero probability.
inline float evalShNonNegative(int count, const float* coeffs, const float* Y) {
    return std::max(0.f, evalShSum(count, coeffs, Y));
}

}  // namespace vdbmarch
