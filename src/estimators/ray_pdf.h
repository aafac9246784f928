// The per-ray pdf of the transmittance and guided marchers (eqs. 9, 16 and
// 17), over the steps of one ray segment. Within step k the medium is taken
// as constant (the paper's homogeneous segment), so its share of the
// integrand T sigma_s L_i is base_k = sigma_s T(t0) S(kappa, len) (eq. 7)
// times L_i, and positions inside it follow the transmittance e^{-kappa t}
// (eq. 10). The guided pdf weights each step by the cached radiance h_k (the
// histogram of section 3.3) and is mixed with the transmittance pdf:
//
//   P_k = (1 - eps) base_k h_k / sum(base h) + eps base_k / sum(base),
//
// so a step where the cache says "dark" (h = 0, or negative ringing clamped
// to 0) keeps probability eps base_k / sum(base): the estimator stays
// unbiased, and with a useless cache its variance is at most 1/eps times the
// transmittance sampler's.
#pragma once

#include <cstddef>
#include <vector>

#include "strategies/caustic_folds.h"
#include "strategies/light_distances.h"
#include "transport/thread_context.h"

namespace vdbmarch {

struct PdfStep {
    float t0 = 0, len = 0;  // the step [t0, t0 + len) along the ray
    float kappa = 0;        // extinction for the exponential shape inside the step
    float base = 0;         // sigma_s T(t0) S(kappa, len), >= 0
};

class RayPdf {
public:
    // Defensive weight of the transmittance pdf in the guided mixture.
    static constexpr float DefaultDefensive = 0.2f;

    // h: cached radiance per step (>= 0), or null for the transmittance pdf.
    void build(const std::vector<PdfStep>& steps, const float* h, float defensive = DefaultDefensive);

    // False when no step can scatter (sum of base is 0): nothing to sample.
    bool valid() const { return mBase > 0; }
    // sum(base h): the histogram's estimate of the segment's in-scattering,
    // S_h sigma of eq. 17 (0 without a cache).
    double guidedIntegral() const { return mGuided; }

    // Inverts the CDF at u in [0, 1): the step, the position in it (offset
    // from its t0, in [0, len)) and the density there.
    void sample(double u, int& step, float& offset, double& pdf) const;
    // Density at `offset` from the start of `step`.
    double pdf(int step, float offset) const;
    // Probability of `step` (the histogram bin).
    double stepProbability(int step) const { return mCdf[std::size_t(step) + 1] - mCdf[std::size_t(step)]; }

    // Towards lights near the segment (the guided marcher), and towards the
    // folds of caustics behind glass spheres that it crosses: the mixture
    //   P'(t) = (1 - a - b) P(t) + a sum_l c_l p_l(t) + b p_f(t),
    // p_l the equiangular densities of `lights` (LightDistances::prepare), c_l
    // their odds, p_f the folds' density (caustic_folds.h), inverted at u:
    // [0, 1 - a - b) draws from P, then a light by its odds and its sampler,
    // then the folds. False when the drawn t lies in no step (nothing
    // scatters there, or the walk ended before it): that sample adds nothing.
    using Lights = std::vector<LightDistance>;
    struct Mixture {
        double lightShare = 0;
        const Lights* lights = nullptr;
        double foldShare = 0;
        const FoldSampler* folds = nullptr;
    };
    // t: the position along the ray, t0 + offset of the step, except for a
    // fold's draw, which keeps the t it drew (its density is sharpest there).
    bool sampleMixture(double u, const Mixture& mix, int& step, float& offset, double& pdf, float& t) const;
    // P'(t) at t, `offset` from the start of `step`.
    double mixturePdf(int step, float offset, const Mixture& mix, float t) const;
    double mixturePdf(int step, float offset, const Mixture& mix) const {
        return mixturePdf(step, offset, mix, (*mSteps)[std::size_t(step)].t0 + offset);
    }
    // The mixture with lights alone (b = 0).
    bool sampleWithLights(double u, double a, const Lights& lights, int& step, float& offset, double& pdf) const {
        float t;
        return sampleMixture(u, {a, &lights}, step, offset, pdf, t);
    }
    double pdfWithLights(int step, float offset, double a, const Lights& lights) const {
        return mixturePdf(step, offset, {a, &lights});
    }
    // The step holding t, and t's offset in it.
    bool locate(float t, int& step, float& offset) const;

private:
    bool stepOffCrossing(const FoldSampler& folds, float& t, int& step, float& offset) const;

    const std::vector<PdfStep>* mSteps = nullptr;
    std::vector<double> mCdf;  // size steps + 1, mCdf[0] = 0, last = 1
    double mBase = 0, mGuided = 0;
};

// Density of the truncated exponential kappa e^{-kappa x} / (1 - e^{-kappa len})
// on [0, len) (uniform when kappa len is tiny), and its inverse CDF.
double truncatedExponentialPdf(float kappa, float len, float x);
float sampleTruncatedExponential(float kappa, float len, double v);

}  // namespace vdbmarch
