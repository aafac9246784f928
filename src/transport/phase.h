// The phase function where several media overlap: the sigma_s-weighted
// mixture of their Henyey-Greenstein lobes, written once for every path loop
// (marchers, reference, photons) and for the cache's projection (eq. 26/27).
// Directions follow the light: cosTheta is between the arriving light's
// travel direction and the scattered direction.
#pragma once

#include "core/math.h"

namespace vdbmarch {

constexpr int MaxMediaPerPoint = 8;

struct PhaseMixture {
    int count = 0;  // media that scatter here
    Color sigmaS[MaxMediaPerPoint];
    float g[MaxMediaPerPoint];

    void clear() { count = 0; }
    bool empty() const { return count == 0; }
    // Adds one medium's lobe (ignored past MaxMediaPerPoint).
    void add(const Color& sigma_s, float gi) {
        if (count >= MaxMediaPerPoint || isBlack(sigma_s)) return;
        sigmaS[count] = sigma_s;
        g[count] = gi;
        ++count;
    }

    // f(cos) per channel: sum_i sigma_s,i p_i(cos) / sum_i sigma_s,i.
    Color eval(float cosTheta) const;
    // The sampling density: lobes picked by average(sigma_s,i), so for a
    // single medium pdf = f. Solid angle measure.
    float pdf(float cosTheta) const;
    // Samples a scattered direction around the travel direction d with
    // u = three uniforms; multiplies `weight` by f / pdf (1 for a single
    // medium) and returns the pdf.
    Vec3 sample(const Vec3& d, float u0, float u1, float u2, Color& weight, float& pdfOut) const;
    // Eq. 26 for the mixture: w'_l = sum_i w_i g_i^l with w_i the lobe
    // weights of pdf() (the HG Legendre coefficients are g^l), l = 0..order.
    void legendreWeights(int order, float* out) const;
    // True when every lobe has g = 0 (the mixture is isotropic).
    bool isotropic() const;
    // The phase value a direction drawn from the phase itself has on
    // average, int f^2 dOmega, in units of the isotropic 1 / (4 pi): for one
    // Henyey-Greenstein lobe (1 + g^2) / (1 - g^2)^2 (1 for g = 0, 12.7 for
    // g = 0.8); for a mixture the lobes' values weighed as in pdf() (a
    // scale for shadow-ray roulette, not an exact moment).
    float meanPhaseValue() const;
};

}  // namespace vdbmarch
