#include "cache/product_sampler.h"

#include <algorithm>
#include <cmath>

namespace vdbmarch {

namespace {

// Largest float below 1: rescaled uniforms stay in [0, 1).
constexpr float OneMinus = 0x1.fffffep-1f;

// A Henyey-Greenstein lobe of mean cosine g as three vMF lobes about its
// axis, fitted by tools/fit_hg_vmf.py (least chi-square divergence, E[w^2]
// of HG / mixture at most 1.002 up to g = 0.8, 1.012 at 0.9; a single lobe
// of the same mean cosine gives 3.3 at g = 0.8, and the weights of a path's
// vertices multiply). Rows are interpolated linearly in g; g = 0 is the
// uniform lobe.
struct HgFit {
    float g;
    float w[3];
    float kappa[3];
};
constexpr HgFit HgAsVmf[] = {
    {0.00f, {1.f, 0.f, 0.f}, {0.f, 0.f, 0.f}},
    {0.20f, {0.02835f, 0.36256f, 0.60909f}, {2.9553f, 1.1401f, 0.26693f}},
    {0.25f, {0.03631f, 0.37160f, 0.59209f}, {3.8027f, 1.4401f, 0.33405f}},
    {0.30f, {0.04662f, 0.38161f, 0.57177f}, {4.7362f, 1.7522f, 0.40163f}},
    {0.35f, {0.05955f, 0.39207f, 0.54838f}, {5.7883f, 2.0809f, 0.46997f}},
    {0.40f, {0.07537f, 0.40243f, 0.52220f}, {7.004f, 2.4326f, 0.53952f}},
    {0.45f, {0.09431f, 0.41216f, 0.49353f}, {8.4471f, 2.8162f, 0.6109f}},
    {0.50f, {0.11657f, 0.42076f, 0.46267f}, {10.211f, 3.2447f, 0.68502f}},
    {0.55f, {0.14231f, 0.42776f, 0.42993f}, {12.439f, 3.7373f, 0.76315f}},
    {0.60f, {0.17169f, 0.43271f, 0.39560f}, {15.358f, 4.3234f, 0.84714f}},
    {0.65f, {0.20484f, 0.43521f, 0.35994f}, {19.356f, 5.0514f, 0.93978f}},
    {0.70f, {0.24195f, 0.43483f, 0.32322f}, {25.14f, 6.0049f, 1.0455f}},
    {0.75f, {0.28330f, 0.43109f, 0.28562f}, {34.125f, 7.3421f, 1.1717f}},
    {0.80f, {0.32951f, 0.42333f, 0.24716f}, {49.521f, 9.3949f, 1.3313f}},
    {0.85f, {0.38205f, 0.41041f, 0.20755f}, {80.107f, 12.983f, 1.55f}},
    {0.90f, {0.44430f, 0.38977f, 0.16593f}, {158.56f, 20.775f, 1.8883f}},
    {0.95f, {0.52533f, 0.35425f, 0.12043f}, {518.24f, 48.195f, 2.5519f}},
    {0.97f, {0.56918f, 0.33043f, 0.10039f}, {1257.9f, 91.982f, 3.1002f}},
    {0.99f, {0.63116f, 0.28902f, 0.07983f}, {8762.5f, 389.68f, 4.3786f}},
};

// The three lobes of HG(|g|) (about the axis, or against it for g < 0).
void hgLobes(float g, float w[3], float kappa[3]) {
    constexpr int Rows = int(sizeof(HgAsVmf) / sizeof(HgAsVmf[0]));
    const float a = clamp(std::fabs(g), 0.f, HgAsVmf[Rows - 1].g);
    int r = 0;
    while (r + 2 < Rows && HgAsVmf[r + 1].g < a) ++r;
    const HgFit &lo = HgAsVmf[r], &hi = HgAsVmf[r + 1];
    const float t = clamp((a - lo.g) / (hi.g - lo.g), 0.f, 1.f);
    for (int i = 0; i < 3; ++i) {
        w[i] = lo.w[i] + t * (hi.w[i] - lo.w[i]);
        kappa[i] = lo.kappa[i] + t * (hi.kappa[i] - lo.kappa[i]);
    }
}

}  // namespace

ProductDirectionSampler::ProductDirectionSampler(float defensive) : mEps(clamp(defensive, 0.f, 1.f)) {
    mCdf[0] = 0;
}

bool ProductDirectionSampler::build(const PreparedLobes& light, const PhaseMixture& phase, const Vec3& rayDir) {
    mPhase = &phase;
    mRayDir = rayDir;
    mLobes = 0;
    if (phase.empty() || mEps >= 1 || light.count == 0) return false;
    // The phase function's stand-in: three lobes around rayDir (or against
    // it) of the mixture's mean cosine (lobes picked by average(sigma_s), as
    // PhaseMixture::pdf does).
    float total = 0, gSum = 0;
    for (int i = 0; i < phase.count; ++i) {
        total += average(phase.sigmaS[i]);
        gSum += average(phase.sigmaS[i]) * phase.g[i];
    }
    const float g = total > 0 ? gSum / total : 0.f;
    float phaseW[3], phaseKappa[3], logPhase[3];
    hgLobes(g, phaseW, phaseKappa);
    for (int m = 0; m < 3; ++m)
        logPhase[m] = phaseW[m] > 0 ? std::log(phaseW[m]) + VmfLobe::logNormalisation(phaseKappa[m]) : -INFINITY;
    const Vec3 muG = g >= 0 ? rayDir : -1.f * rayDir;

    // Product of each light lobe with each phase lobe: one vMF lobe, whose
    // mass is the integral of the product, W C_j C_m / C(kappa').
    Vec3 v[MaxProductLobes];
    float kappa[MaxProductLobes], logWeight[MaxProductLobes], top = -INFINITY;
    int n = 0;
    for (int j = 0; j < light.count; ++j)
        for (int m = 0; m < 3; ++m) {
            if (!(phaseW[m] > 0)) continue;
            v[n] = light.mu[j] * light.kappa[j] + muG * phaseKappa[m];
            kappa[n] = length(v[n]);
            logWeight[n] = light.logWeightNorm[j] + logPhase[m] - VmfLobe::logNormalisation(kappa[n]);
            if (!std::isfinite(logWeight[n]) || !std::isfinite(kappa[n])) continue;
            top = std::max(top, logWeight[n]);
            ++n;
        }
    // Lobes under 1e-4 of the largest are left out (their share goes to the
    // others; the density stays that of the mixture sampled).
    float sum = 0;
    for (int i = 0; i < n; ++i) {
        if (logWeight[i] < top - 9.2f) continue;
        const float w = std::exp(logWeight[i] - top);
        mLobe[mLobes++] = VmfLobe::make(kappa[i] > 0 ? v[i] / kappa[i] : Vec3(0, 0, 1), kappa[i], w);
        sum += w;
    }
    if (mLobes == 0 || !(sum > 0) || !std::isfinite(sum)) {
        mLobes = 0;
        return false;
    }
    for (int j = 0; j < mLobes; ++j) {
        mLobe[j].weight /= sum;
        mCdf[j + 1] = mCdf[j] + mLobe[j].weight;
    }
    mCdf[mLobes] = 1;
    return true;
}

float ProductDirectionSampler::lobesPdf(const Vec3& wi) const {
    float p = 0;
    for (int j = 0; j < mLobes; ++j) p += mLobe[j].weight * mLobe[j].pdf(wi);
    return p;
}

float ProductDirectionSampler::mixturePdf(const Vec3& wi, float phasePdf) const {
    if (mLobes == 0) return phasePdf;
    return mEps * phasePdf + (1 - mEps) * lobesPdf(wi);
}

float ProductDirectionSampler::pdf(const Vec3& wi) const {
    if (!mPhase || mPhase->empty()) return 0;
    return mixturePdf(wi, mPhase->pdf(dot(mRayDir, wi)));
}

ProductSample ProductDirectionSampler::sample(float u0, float u1, float u2) const {
    ProductSample s;
    if (!mPhase || mPhase->empty()) return s;
    if (mLobes == 0 || u0 < mEps) {
        // Phase component: u0 rescaled picks the lobe (PhaseMixture::sample).
        const float v0 = mLobes > 0 ? std::min(u0 / mEps, OneMinus) : u0;
        Color unused(1);
        float phasePdf;
        s.wi = mPhase->sample(mRayDir, v0, u1, u2, unused, phasePdf);
        s.from = mLobes > 0 ? ProductSample::From::Phase : ProductSample::From::PhaseOnly;
    } else {
        // Lobe component: u0 rescaled against the CDF picks a lobe.
        const float v0 = std::min((u0 - mEps) / (1 - mEps), OneMinus);
        int j = 0;
        while (j + 1 < mLobes && !(v0 < mCdf[j + 1])) ++j;
        s.wi = mLobe[j].sample(u1, u2);
        s.from = ProductSample::From::Lobes;
    }
    // The density of the whole mixture at wi, from wi alone (as pdf() does).
    const float c = dot(mRayDir, s.wi);
    const float phasePdf = mPhase->pdf(c);
    s.pdf = mixturePdf(s.wi, phasePdf);
    // One lobe: f = pdf, no second evaluation.
    if (s.pdf > 0) s.weight = (mPhase->count == 1 ? Color(phasePdf) : mPhase->eval(c)) / s.pdf;
    return s;
}

}  // namespace vdbmarch
