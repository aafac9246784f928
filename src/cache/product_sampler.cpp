#include "cache/product_sampler.h"

#include <algorithm>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cache/sh.h"

namespace vdbmarch {

namespace {

using PS = ProductDirectionSampler;
constexpr float Dz = 2.f / PS::Nz;
constexpr float Dphi = 2 * Pi / PS::Nphi;
constexpr float BinSolidAngle = 4 * Pi / PS::Bins;
constexpr int MaxCoeffs = shCount(PS::MaxOrder);
// Largest float below 1: rescaled uniforms stay in [0, 1).
constexpr float OneMinus = 0x1.fffffep-1f;

// Bin centres and the SH basis there, once per process. Structure of arrays,
// coefficient-major, so the per-build loops run over bins and vectorise.
struct BinTable {
    float x[PS::Bins], y[PS::Bins], z[PS::Bins];
    // Y_k at -centre: the light seen when looking along the centre travels
    // the other way (L is over the travel direction).
    float Y[MaxCoeffs][PS::Bins];

    BinTable() {
        for (int b = 0; b < PS::Bins; ++b) {
            float z0, z1, p0, p1;
            PS::binBounds(b, z0, z1, p0, p1);
            const float zc = 0.5f * (z0 + z1), pc = 0.5f * (p0 + p1), r = safeSqrt(1 - zc * zc);
            x[b] = r * std::cos(pc);
            y[b] = r * std::sin(pc);
            z[b] = zc;
            float basis[MaxCoeffs];
            evalSh(PS::MaxOrder, Vec3(-x[b], -y[b], -z[b]), basis);
            for (int k = 0; k < MaxCoeffs; ++k) Y[k][b] = basis[k];
        }
    }
};

const BinTable& binTable() {
    static const BinTable table;
    return table;
}

// out[b] (+)= w * hgPhase(cosB[b], g) over all bins. std::sqrt keeps the
// loop scalar (errno semantics without -fno-math-errno), and the phase is
// most of a build, so SSE2 does four bins at a time where it exists.
void addHgRow(const float* cosB, float g, float w, bool accumulate, float* out) {
    const float a = 1 + g * g, b = -2 * g, c = w * Inv4Pi * (1 - g * g);
    int i = 0;
#if defined(__SSE2__)
    const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(b), vc = _mm_set1_ps(c), tiny = _mm_set1_ps(1e-12f);
    for (; i + 4 <= PS::Bins; i += 4) {
        const __m128 d = _mm_add_ps(va, _mm_mul_ps(vb, _mm_loadu_ps(cosB + i)));
        __m128 p = _mm_div_ps(vc, _mm_mul_ps(d, _mm_sqrt_ps(_mm_max_ps(d, tiny))));
        if (accumulate) p = _mm_add_ps(p, _mm_loadu_ps(out + i));
        _mm_storeu_ps(out + i, p);
    }
#endif
    for (; i < PS::Bins; ++i) {
        const float d = a + b * cosB[i];
        const float p = c / (d * std::sqrt(std::max(d, 1e-12f)));
        out[i] = accumulate ? out[i] + p : p;
    }
}

}  // namespace

ProductDirectionSampler::ProductDirectionSampler(float defensive) : mEps(clamp(defensive, 0.f, 1.f)) {
    mCdf[0] = 0;
}

int ProductDirectionSampler::binOf(const Vec3& w) {
    const int iz = clamp(int((w.z + 1) * (0.5f * Nz)), 0, Nz - 1);
    float phi = std::atan2(w.y, w.x);
    if (phi < 0) phi += 2 * Pi;
    const int ip = clamp(int(phi * (1 / Dphi)), 0, Nphi - 1);
    return iz * Nphi + ip;
}

void ProductDirectionSampler::binBounds(int bin, float& z0, float& z1, float& phi0, float& phi1) {
    const int iz = bin / Nphi, ip = bin % Nphi;
    z0 = -1 + iz * Dz;
    z1 = iz + 1 == Nz ? 1.f : z0 + Dz;
    phi0 = ip * Dphi;
    phi1 = phi0 + Dphi;
}

bool ProductDirectionSampler::build(int order, const float* coeffs, const PhaseMixture& phase,
                                    const Vec3& rayDir) {
    mPhase = &phase;
    mRayDir = rayDir;
    mTable = false;
    if (phase.empty() || order < 0 || mEps >= 1) return false;
    const BinTable& t = binTable();
    const int n = shCount(std::min(order, MaxOrder));

    // L at the bin centres (one matrix-vector product), clamped at zero; a
    // NaN coefficient gives NaN here and max(0, NaN) = 0 drops the bin.
    float value[Bins];
    for (int b = 0; b < Bins; ++b) value[b] = coeffs[0] * t.Y[0][b];
    for (int k = 1; k < n; ++k) {
        const float c = coeffs[k];
        for (int b = 0; b < Bins; ++b) value[b] += c * t.Y[k][b];
    }
    // Times the phase pdf at the centre (the lobes by average(sigma_s), as
    // PhaseMixture::pdf); inlined per lobe so the loop over bins vectorises.
    float cosB[Bins], ph[Bins];
    for (int b = 0; b < Bins; ++b) cosB[b] = rayDir.x * t.x[b] + rayDir.y * t.y[b] + rayDir.z * t.z[b];
    if (phase.count == 1) {
        addHgRow(cosB, phase.g[0], 1, false, ph);
    } else {
        float total = 0;
        for (int i = 0; i < phase.count; ++i) total += average(phase.sigmaS[i]);
        for (int i = 0; i < phase.count; ++i) addHgRow(cosB, phase.g[i], average(phase.sigmaS[i]) / total, i > 0, ph);
    }
    for (int b = 0; b < Bins; ++b) value[b] = std::max(0.f, value[b]) * ph[b];
    // Prefix sum in two levels: the Nz rows side by side (independent chains
    // that vectorise, not one 128-long chain of dependent adds), then the row
    // offsets.
    float row[Nz][Nphi + 1], offset = 0;
    for (int iz = 0; iz < Nz; ++iz) row[iz][0] = 0;
    for (int ip = 0; ip < Nphi; ++ip)
        for (int iz = 0; iz < Nz; ++iz) row[iz][ip + 1] = row[iz][ip] + value[iz * Nphi + ip];
    for (int iz = 0; iz < Nz; ++iz) {
        for (int ip = 0; ip < Nphi; ++ip) mCdf[iz * Nphi + ip + 1] = offset + row[iz][ip + 1];
        offset += row[iz][Nphi];
    }
    const float sum = mCdf[Bins];
    if (!(sum > 0) || !std::isfinite(sum)) return false;
    // The bin probabilities are the CDF steps, so sample() and pdf() read the
    // same numbers.
    mInvNorm = 1 / (sum * BinSolidAngle);
    mTable = true;
    return true;
}

float ProductDirectionSampler::tablePdf(const Vec3& wi) const {
    if (!mTable) return 0;
    const int b = binOf(wi);
    return (mCdf[b + 1] - mCdf[b]) * mInvNorm;
}

float ProductDirectionSampler::mixturePdf(const Vec3& wi, float phasePdf) const {
    if (!mTable) return phasePdf;
    return mEps * phasePdf + (1 - mEps) * tablePdf(wi);
}

float ProductDirectionSampler::pdf(const Vec3& wi) const {
    if (!mPhase || mPhase->empty()) return 0;
    return mixturePdf(wi, mPhase->pdf(dot(mRayDir, wi)));
}

ProductSample ProductDirectionSampler::sample(float u0, float u1, float u2) const {
    ProductSample s;
    if (!mPhase || mPhase->empty()) return s;
    if (!mTable || u0 < mEps) {
        // Phase component: u0 rescaled picks the lobe (PhaseMixture::sample).
        const float v0 = mTable ? std::min(u0 / mEps, OneMinus) : u0;
        Color unused(1);
        float phasePdf;
        s.wi = mPhase->sample(mRayDir, v0, u1, u2, unused, phasePdf);
        s.from = mTable ? ProductSample::From::Phase : ProductSample::From::PhaseOnly;
    } else {
        // Table component: u0 rescaled against the CDF picks a bin with
        // non-zero value (upper_bound skips empty bins), u1 and u2 the point.
        const float v0 = std::min((u0 - mEps) / (1 - mEps), OneMinus);
        const float target = std::min(v0 * mCdf[Bins], std::nextafter(mCdf[Bins], 0.f));
        const int b = int(std::upper_bound(mCdf + 1, mCdf + Bins + 1, target) - (mCdf + 1));
        float z0, z1, p0, p1;
        binBounds(b, z0, z1, p0, p1);
        const float z = clamp(z0 + u1 * (z1 - z0), -1.f, 1.f), phi = p0 + u2 * (p1 - p0);
        const float r = safeSqrt(1 - z * z);
        s.wi = Vec3(r * std::cos(phi), r * std::sin(phi), z);
        s.from = ProductSample::From::Table;
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
