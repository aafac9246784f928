// The phase function where several media overlap: the sigma_s-weighted
// mixture of their Henyey-Greenstein lobes, written once for every path loop
// (marchers, reference, photons) and for the cache's projection (eq. 26/27).
// Directions follow the light: cosTheta is between the arriving light's
// travel direction and the scattered direction.
#pragma once

#include "core/math.h"
#include "core/sampling.h"

namespace vdbmarch {

// Henyey-Greenstein, the lobe every medium scatters by, written once here:
// its value, the sampling of its cosine (pdf = value) and its Legendre
// coefficients for the cache's projection (eq. 26). cosTheta is the cosine
// between the incoming light's travel direction and the outgoing direction
// (g > 0 scatters forward).
inline float hgPhase(float cosTheta, float g) {
    float denom = 1 + g * g - 2 * g * cosTheta;
    return Inv4Pi * (1 - g * g) / (denom * std::sqrt(std::max(denom, 1e-12f)));
}

// Samples the cosine to the travel direction with pdf hgPhase(cos, g) over the
// sphere (times the uniform azimuth). u in [0,1).
inline float sampleHgCosTheta(float u, float g) {
    if (std::fabs(g) < 1e-3f) return 1 - 2 * u;
    float s = (1 - g * g) / (1 - g + 2 * g * u);
    return clamp((1 + g * g - s * s) / (2 * g), -1.f, 1.f);
}

// HG in Legendre series: with the generating function
//   1 / sqrt(1 - 2 g u + g^2) = sum_l g^l P_l(u)
// and its derivative in g one finds
//   (1 - g^2) / (1 - 2 g u + g^2)^{3/2} = sum_l (2l+1) g^l P_l(u),
// so hgPhase(u) = sum_l (2l+1)/(4 pi) g^l P_l(u). With orthogonality,
// Int P_k P_l du = 2/(2l+1) delta_kl, eq. 26 gives
//   w'_l = 2 pi (2l+1)/(4 pi) g^l 2/(2l+1) = g^l.
inline void hgLegendreWeights(int order, float g, float* out) {
    out[0] = 1;
    for (int l = 1; l <= order; ++l) out[l] = out[l - 1] * g;
}

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
