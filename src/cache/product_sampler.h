// Product sampling of a path continuation direction: phase function x cached
// incident radiance (spherical harmonics), with a defensive mixture.
//
// This goes beyond the paper: Tokuyoshi & Maruyama guide only the *distance*
// along the camera ray with the cache (and mix that distance pdf defensively,
// eq. 16). The issue asks for the same idea on the scattering direction: draw
// wi from a tabulated approximation of
//     p(dot(rayDir, wi)) * max(0, L(-wi))
// (L over the light's travel direction w' = -wi, sh.h), mixed with plain phase
// sampling so that every direction the phase function reaches keeps a pdf of
// at least eps * phasePdf. The weight f / pdf is then bounded by 1 / eps (one
// lobe) and the estimator stays unbiased for any coefficients, including SH
// ringing below zero (clamped to zero in the table, covered by the phase part).
//
// Geometry: the camera ray travels along rayDir; wi is the direction the path
// continues in (light arrives travelling along -wi). The phase factor is
// phase.pdf(dot(rayDir, wi)), exactly as PhaseMixture::sample(rayDir, ...)
// draws wi in SegmentMarcher::inScattered; the weight uses phase.eval.
//
// The table: an equal-area grid over the sphere in world coordinates, z =
// cos(theta) uniform in [-1, 1] (Nz rows) x phi uniform in [0, 2 pi) (Nphi
// columns), so every bin has solid angle 4 pi / (Nz Nphi) and a uniform point
// in (z, phi) inside a bin is uniform in solid angle. Bin values are the target
// at the bin centre; the SH basis at the (fixed) bin centres is a static table,
// so a build is one small matrix-vector product plus one phase evaluation per
// bin. Everything lives in fixed-size arrays: no allocation per use.
#pragma once

#include <cstdint>

#include "core/math.h"
#include "transport/phase.h"

namespace vdbmarch {

struct ProductSample {
    enum class From : uint8_t {
        Phase,      // the defensive phase component drew it
        Table,      // the product table drew it
        PhaseOnly,  // no table (no light reaches the point, or eps = 1): plain phase sampling
    };
    Vec3 wi;
    Color weight{0};  // phase.eval(dot(rayDir, wi)) / pdf per channel
    float pdf = 0;    // solid-angle density of the whole sampler; 0: nothing to sample
    From from = From::PhaseOnly;
};

class ProductDirectionSampler {
public:
    // Bands the table reads (16 coefficients); higher bands are ignored, which
    // only changes the proposal, never the expected value.
    static constexpr int MaxOrder = 3;
    // 8 x 16 bins (0.098 sr each, about 18 degrees across). Measured with
    // the VarianceAgainstPhaseSampling cases of test_product_sampler.cpp
    // (variance relative to phase sampling at eps 0.3 / order-3 build time):
    //   4 x 8:   0.11-0.30 /   53 ns
    //   8 x 16:  0.045-0.155 / 240 ns
    //   16 x 32: 0.033-0.115 / 1.0 us
    // An order-3 expansion has no detail finer than ~45 degrees; 16 x 32
    // mostly resolves the phase peak better, for 4x the build.
    static constexpr int Nz = 8, Nphi = 16, Bins = Nz * Nphi;
    // Probability of the defensive phase component. It bounds the weight by
    // 1 / eps for one lobe (3.3 here) whatever the cache says, which matters
    // because the cached L is only an approximation of what the path finds.
    // With an exact cache (the tests) variance is flat over 0.2-0.3 (0.2 is
    // 8-20% lower at 8 x 16) and grows past 0.4; 0.3 takes the safer bound.
    static constexpr float DefaultDefensive = 0.3f;

    explicit ProductDirectionSampler(float defensive = DefaultDefensive);

    // Tabulates phase x max(0, L) for a camera ray travelling along rayDir
    // (unit). coeffs: shCount(order) SH coefficients of L over the light's
    // travel direction (sh.h). `phase` is kept by pointer: it must outlive the
    // sampler's use. Returns whether a table was built; false (no positive
    // radiance, non-finite coefficients, order < 0) means sample() falls back
    // to plain phase sampling.
    bool build(int order, const float* coeffs, const PhaseMixture& phase, const Vec3& rayDir);

    // Draws wi from eps * phase + (1 - eps) * table with three uniforms in
    // [0, 1): u0 picks the component (and, rescaled, the lobe or the bin), u1
    // and u2 the direction within it. Deterministic in (u0, u1, u2).
    ProductSample sample(float u0, float u1, float u2) const;

    // The density sample() reports for wi (bitwise the same value).
    float pdf(const Vec3& wi) const;

    bool hasTable() const { return mTable; }
    float defensive() const { return mEps; }
    // The table component's own density (0 without a table), for tests.
    float tablePdf(const Vec3& wi) const;
    // Bin of a direction, and the [z0, z1) x [phi0, phi1) ranges of a bin.
    static int binOf(const Vec3& w);
    static void binBounds(int bin, float& z0, float& z1, float& phi0, float& phi1);

private:
    float mixturePdf(const Vec3& wi, float phasePdf) const;

    float mEps;
    bool mTable = false;
    const PhaseMixture* mPhase = nullptr;
    Vec3 mRayDir{0, 0, 1};
    float mInvNorm = 0;    // 1 / (total * binSolidAngle)
    float mCdf[Bins + 1];  // running sum of the bin values, mCdf[0] = 0
};

}  // namespace vdbmarch
