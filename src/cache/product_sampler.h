// Product sampling of a path continuation direction: the phase function
// times the cached incident radiance, held as a few von Mises-Fisher lobes
// per cache cell (direction_lobes.h), with a defensive phase share.
//
// This goes beyond the paper: Tokuyoshi & Maruyama guide only the *distance*
// along the camera ray with the cache (eq. 16). Here the scattering direction
// is drawn from
//     eps p(dot(rayDir, wi)) + (1 - eps) sum_j c_j vMF(wi; mu'_j, kappa'_j),
// where each lobe j of the cell's incident radiance (mean direction mu_j, the
// way a path goes to find that light, concentration kappa_j) is multiplied
// by each of three lobes m around rayDir that together stand in for the
// phase function (a fit of Henyey-Greenstein by tools/fit_hg_vmf.py): the
// product of two vMF lobes is a vMF lobe, kappa' mu' = kappa_j mu_j +
// kappa_m mu_g, of mass C(kappa_j) C(kappa_m) / C(kappa') (C the
// normalisation), so c_jm is the lobe's radiance times the phase lobe's
// weight times that mass (the product of Herholz et al. 2019 and Open PGL,
// with three lobes for the phase function: one lobe of the same mean cosine
// misses a g = 0.8 peak, and the second moment of the weight phase / pdf
// is 3.3 per vertex for light from everywhere, which multiplies along a
// path; three give 1.002). The approximation
// shapes only the density: the weight evaluates the phase function exactly
// (f / pdf, at most 1 / eps for one lobe), and pdf() is the exact density of
// the mixture, so next-event estimation weighs its light samples against it
// by MIS and the estimator stays unbiased for any lobes. A band-3 SH table
// could not hold a g = 0.8 lobe (its expansion peaks 4.4x too low and goes
// negative); lobes can.
//
// Geometry: the path arrives travelling along rayDir; wi is the direction it
// continues in (light arrives travelling along -wi). The phase factor is
// phase.pdf(dot(rayDir, wi)), as PhaseMixture::sample(rayDir, ...) draws it.
#pragma once

#include <cstdint>

#include "cache/direction_lobes.h"
#include "core/math.h"
#include "transport/phase.h"

namespace vdbmarch {

struct ProductSample {
    enum class From : uint8_t {
        Phase,      // the defensive phase component drew it
        Lobes,      // the product lobes drew it
        PhaseOnly,  // no lobes (no light reaches the cell, or eps = 1): plain phase sampling
    };
    Vec3 wi;
    Color weight{0};  // phase.eval(dot(rayDir, wi)) / pdf per channel
    float pdf = 0;    // solid-angle density of the whole sampler; 0: nothing to sample
    From from = From::PhaseOnly;
};

class ProductDirectionSampler {
public:
    // Probability of the defensive phase component. It bounds the weight by
    // 1 / eps for one lobe whatever the cache says, which matters because
    // the lobes are fitted to a few photons and what a path finds differs.
    static constexpr float DefaultDefensive = 0.3f;

    explicit ProductDirectionSampler(float defensive = DefaultDefensive);

    // Prepares the product of the phase function for a path travelling along
    // rayDir (unit) with a cell's light lobes (direction_lobes.h). `phase`
    // is kept by pointer: it must outlive the sampler's use. Returns whether
    // lobes were built; false (no lobe with light) means sample() falls back
    // to plain phase sampling.
    bool build(const PreparedLobes& light, const PhaseMixture& phase, const Vec3& rayDir);

    // Draws wi from eps * phase + (1 - eps) * lobes with three uniforms in
    // [0, 1): u0 picks the component (and, rescaled, the phase lobe or the
    // product lobe), u1 and u2 the direction within it. Deterministic in
    // (u0, u1, u2).
    ProductSample sample(float u0, float u1, float u2) const;

    // The density sample() reports for wi (bitwise the same value).
    float pdf(const Vec3& wi) const;

    bool hasLobes() const { return mLobes > 0; }
    int lobeCount() const { return mLobes; }
    float defensive() const { return mEps; }
    // The product lobes' own density (0 without lobes), for tests.
    float lobesPdf(const Vec3& wi) const;

private:
    float mixturePdf(const Vec3& wi, float phasePdf) const;

    float mEps;
    int mLobes = 0;
    const PhaseMixture* mPhase = nullptr;
    Vec3 mRayDir{0, 0, 1};
    // Light lobes x the phase function's three lobes.
    static constexpr int MaxProductLobes = DirectionLobes::MaxLobes * 3;
    VmfLobe mLobe[MaxProductLobes];
    float mCdf[MaxProductLobes + 1];  // running sum of the lobe weights, mCdf[0] = 0, mCdf[mLobes] = 1
};

}  // namespace vdbmarch
