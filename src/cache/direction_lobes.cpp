#include "cache/direction_lobes.h"

#include <algorithm>
#include <cmath>

namespace vdbmarch {

namespace {

// Below this concentration a lobe is uniform (its formulas lose precision).
constexpr float TinyKappa = 1e-4f;
constexpr int KMeansIterations = 6;

int closestLobe(const Vec3* mu, int lobes, const Vec3& w) {
    int best = 0;
    float bestCos = -2;
    for (int j = 0; j < lobes; ++j) {
        const float c = dot(mu[j], w);
        if (c > bestCos) {
            bestCos = c;
            best = j;
        }
    }
    return best;
}

// Statistics of the photons assigned to the closest of `lobes` means; `slot`
// maps a mean to its lobe index in out.
void accumulate(const Vec3* mu, const int* slot, int lobes, const Vec3* wi, const float* w, int n, float* out) {
    for (int p = 0; p < n; ++p) {
        if (!(w[p] > 0)) continue;
        float* s = out + slot[closestLobe(mu, lobes, wi[p])] * DirectionLobes::LobeFloats;
        s[0] += w[p];
        s[1] += w[p] * wi[p].x;
        s[2] += w[p] * wi[p].y;
        s[3] += w[p] * wi[p].z;
        s[4] += 1;
    }
}

// 1 - the mean resultant length of statistics (W, S): the lobe's spread.
float spread(float W, float Sx, float Sy, float Sz) {
    return W > 0 ? 1 - std::min(1.f, std::sqrt(Sx * Sx + Sy * Sy + Sz * Sz) / W) : 1.f;
}

// k-means cuts one broad light into several lobes as readily as it parts
// two lights. Two lobes are one light when together they spread less than
// twice the wider of them (the halves of one lobe are each narrower than
// it; two lights apart by more than their widths spread far more): merge
// the closest such pair until none is left.
void mergeCloseLobes(float* out) {
    constexpr int F = DirectionLobes::LobeFloats;
    for (;;) {
        int bestA = -1, bestB = -1;
        float best = 2;
        for (int a = 0; a < DirectionLobes::MaxLobes; ++a) {
            const float* la = out + a * F;
            if (!(la[0] > 0)) continue;
            for (int b = a + 1; b < DirectionLobes::MaxLobes; ++b) {
                const float* lb = out + b * F;
                if (!(lb[0] > 0)) continue;
                const float merged = spread(la[0] + lb[0], la[1] + lb[1], la[2] + lb[2], la[3] + lb[3]);
                const float wider = std::max(spread(la[0], la[1], la[2], la[3]), spread(lb[0], lb[1], lb[2], lb[3]));
                if (merged < 2 * wider && merged < best) {
                    best = merged;
                    bestA = a;
                    bestB = b;
                }
            }
        }
        if (bestA < 0) return;
        for (int i = 0; i < F; ++i) {
            out[bestA * F + i] += out[bestB * F + i];
            out[bestB * F + i] = 0;
        }
    }
}

}  // namespace

float VmfLobe::logNormalisation(float kappa) {
    if (kappa < TinyKappa) return -std::log(4 * Pi);
    const float log2Pi = 1.8378770664f;
    // Past kappa = 9, 1 - e^{-2 kappa} is 1 in float.
    if (kappa > 9) return std::log(kappa) - log2Pi - kappa;
    return std::log(kappa) - log2Pi - kappa - std::log(-std::expm1(-2 * kappa));
}

VmfLobe VmfLobe::make(const Vec3& mu, float kappa, float weight) {
    VmfLobe l;
    l.mu = mu;
    l.kappa = kappa;
    l.weight = weight;
    l.norm = kappa < TinyKappa ? Inv4Pi : kappa / (2 * Pi * -std::expm1(-2 * kappa));
    return l;
}

float VmfLobe::pdf(const Vec3& w) const {
    if (kappa < TinyKappa) return Inv4Pi;
    return norm * std::exp(kappa * (dot(mu, w) - 1));
}

Vec3 VmfLobe::sample(float u1, float u2) const {
    float cosTheta;
    if (kappa < TinyKappa)
        cosTheta = 1 - 2 * u1;
    else
        cosTheta = 1 + std::log(u1 + (1 - u1) * std::exp(-2 * kappa)) / kappa;
    cosTheta = clamp(cosTheta, -1.f, 1.f);
    const float sinTheta = safeSqrt(1 - cosTheta * cosTheta), phi = 2 * Pi * u2;
    Vec3 s, t;
    coordinateSystem(mu, s, t);
    return normalize(mu * cosTheta + (s * std::cos(phi) + t * std::sin(phi)) * sinTheta);
}

void DirectionLobes::fit(const Vec3* wi, const float* w, int n, float* out) {
    std::fill(out, out + Floats, 0.f);
    int heaviest = -1;
    for (int p = 0; p < n; ++p)
        if (w[p] > 0 && (heaviest < 0 || w[p] > w[heaviest])) heaviest = p;
    if (heaviest < 0) return;
    // Seeds: the heaviest photon, then the photon farthest from the seeds by
    // weight x (1 - cosine) while one is farther than nothing.
    Vec3 mu[MaxLobes];
    int lobes = 0;
    mu[lobes++] = wi[heaviest];
    while (lobes < MaxLobes) {
        int far = -1;
        float farScore = 0;
        for (int p = 0; p < n; ++p) {
            if (!(w[p] > 0)) continue;
            float cosMax = -1;
            for (int j = 0; j < lobes; ++j) cosMax = std::max(cosMax, dot(mu[j], wi[p]));
            const float score = w[p] * (1 - cosMax);
            if (score > farScore) {
                farScore = score;
                far = p;
            }
        }
        // Closer than about 8 degrees to a seed is the same light.
        if (far < 0 || farScore <= w[far] * 0.01f) break;
        mu[lobes++] = wi[far];
    }
    const int slot[MaxLobes] = {0, 1, 2, 3};
    for (int it = 0; it < KMeansIterations; ++it) {
        std::fill(out, out + Floats, 0.f);
        accumulate(mu, slot, lobes, wi, w, n, out);
        bool moved = false;
        for (int j = 0; j < lobes; ++j) {
            const float* s = out + j * LobeFloats;
            const Vec3 S(s[1], s[2], s[3]);
            const float len = length(S);
            if (!(len > 0)) continue;
            const Vec3 m = S / len;
            moved |= dot(m, mu[j]) < 0.99999f;
            mu[j] = m;
        }
        if (!moved) break;
    }
    std::fill(out, out + Floats, 0.f);
    accumulate(mu, slot, lobes, wi, w, n, out);
    mergeCloseLobes(out);
}

void DirectionLobes::assign(const float* means, const Vec3* wi, const float* w, int n, float* out) {
    Vec3 mu[MaxLobes];
    int slot[MaxLobes], lobes = 0;
    for (int j = 0; j < MaxLobes; ++j) {
        const float* s = means + j * LobeFloats;
        if (!(s[0] > 0)) continue;
        const Vec3 S(s[1], s[2], s[3]);
        const float len = length(S);
        mu[lobes] = len > 0 ? S / len : Vec3(0, 0, 1);
        slot[lobes++] = j;
    }
    if (lobes == 0) {
        fit(wi, w, n, out);
        return;
    }
    accumulate(mu, slot, lobes, wi, w, n, out);
}

bool DirectionLobes::lobe(const float* stats, int j, VmfLobe& out) {
    const float* s = stats + j * LobeFloats;
    const float W = s[0], N = s[4];
    if (!(W > 0) || !std::isfinite(W)) return false;
    const Vec3 S(s[1], s[2], s[3]);
    const float len = length(S);
    if (!std::isfinite(len)) return false;
    // The mean resultant length of N directions drawn uniformly is about
    // 1 / sqrt(N), not 0: remove that bias before reading a concentration.
    const float r = std::min(len / W, 1.f);
    const float r2 = N > 1 ? std::max(0.f, (N * r * r - 1) / (N - 1)) : 0.f;
    const float rc = std::min(std::sqrt(r2), 0.999f);
    out = VmfLobe::make(len > 0 ? S / len : Vec3(0, 0, 1), std::min(rc * (3 - rc * rc) / (1 - rc * rc), MaxKappa), W);
    return true;
}

PreparedLobes DirectionLobes::prepare(const float* stats) {
    PreparedLobes p;
    for (int j = 0; j < MaxLobes; ++j) {
        VmfLobe l;
        if (!lobe(stats, j, l)) continue;
        const float lw = std::log(l.weight) + VmfLobe::logNormalisation(l.kappa);
        if (!std::isfinite(lw)) continue;
        p.mu[p.count] = l.mu;
        p.kappa[p.count] = l.kappa;
        p.logWeightNorm[p.count++] = lw;
    }
    return p;
}

void DirectionLobes::average(float* stats, const float* fresh, float keep, float add) {
    for (int j = 0; j < MaxLobes; ++j) {
        float* s = stats + j * LobeFloats;
        const float* f = fresh + j * LobeFloats;
        for (int i = 0; i < 4; ++i) s[i] = keep * s[i] + add * f[i];
        s[4] += f[4];
    }
}

}  // namespace vdbmarch
