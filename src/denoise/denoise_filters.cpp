#include "denoise/denoise_filters.h"

#include "denoise/denoise_nlmeans.h"

#include <cmath>
#include <cstdint>

namespace vdbmarch::denoising {

namespace {

// Finite inputs are clamped to this magnitude so that no square, sum or
// product below overflows (4e30 squared differences, sums of a few thousand).
constexpr float ColorLimit = 1e15f;
// The least colour weight squared (toNextWeakerCandidate): its square is
// still a normal float.
constexpr float SquarableWeight = 1e-18f;

// One channel of the two halves. A value non-finite in one half takes the
// other half's; non-finite in both, the mean of the finite 3x3 neighbours
// (of both halves), else 0. Finite values are clamped to +-ColorLimit.
void loadHalves(const std::vector<float>& a, const std::vector<float>& b, int w, int h, int pad, Plane& outA,
                Plane& outB) {
    outA = Plane(w, h, pad);
    outB = Plane(w, h, pad);
    std::vector<float> meanOfHalves(a.size());
    std::vector<uint8_t> missing(a.size());
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            float va = a[i], vb = b[i];
            if (!finite(va)) va = vb;
            if (!finite(vb)) vb = va;
            missing[i] = !finite(va);
            outA.at(x, y) = missing[i] ? 0.f : clampMagnitude(va, ColorLimit);
            outB.at(x, y) = missing[i] ? 0.f : clampMagnitude(vb, ColorLimit);
            meanOfHalves[i] = 0.5f * (outA.at(x, y) + outB.at(x, y));
        }
    });
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            if (!missing[size_t(y) * size_t(w) + size_t(x)]) continue;
            float sum = 0;
            int count = 0;
            for (int j = std::max(0, y - 1); j <= std::min(h - 1, y + 1); ++j)
                for (int i = std::max(0, x - 1); i <= std::min(w - 1, x + 1); ++i) {
                    const size_t k = size_t(j) * size_t(w) + size_t(i);
                    if (!missing[k]) sum += meanOfHalves[k], ++count;
                }
            outA.at(x, y) = outB.at(x, y) = count ? sum / float(count) : 0.f;
        }
    });
    outA.replicateEdges();
    outB.replicateEdges();
}

// Fireflies: a rare, bright path lands in one half render only, and
// cross-filtering would spread it over the whole search window of every
// neighbour (a square blotch), since the other half's patches look normal
// there. A real feature shows in both halves, so each half is clamped to
// twice the other half's 3x3 maximum plus the other half's image mean (the
// floor for dark surroundings) before filtering. Returns what the clamp took
// (the mean of the two halves' excess): restoreLocalMeans spreads it back as
// a faint haze after filtering, so no light is lost.
Plane suppressFireflies(Plane& a, Plane& b) {
    const int w = a.width, h = a.height;
    auto mean = [&](const Plane& p) {
        double sum = 0;  // serial: the same sum for any thread count
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) sum += double(p.at(x, y));
        return float(sum / std::max(1.0, double(w) * double(h)));
    };
    const float meanA = mean(a), meanB = mean(b);
    auto bounds = [&](const Plane& other, float floor) {
        Plane bound(w, h, 0);
        forEachRow(h, [&](int y) {
            for (int x = 0; x < w; ++x) {
                float m = 0;
                for (int j = std::max(0, y - 1); j <= std::min(h - 1, y + 1); ++j)
                    for (int i = std::max(0, x - 1); i <= std::min(w - 1, x + 1); ++i) m = std::max(m, other.at(i, j));
                bound.at(x, y) = 2.f * m + std::max(0.f, floor);
            }
        });
        return bound;
    };
    const Plane boundA = bounds(b, meanB), boundB = bounds(a, meanA);
    Plane excess(w, h, 0);
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const float ca = std::min(a.at(x, y), boundA.at(x, y)), cb = std::min(b.at(x, y), boundB.at(x, y));
            excess.at(x, y) = 0.5f * ((a.at(x, y) - ca) + (b.at(x, y) - cb));
            a.at(x, y) = ca;
            b.at(x, y) = cb;
        }
    });
    a.replicateEdges();
    b.replicateEdges();
    return excess;
}

// Per-pixel variance of one half: E[(A - B)^2] = 2 Var[half] for independent
// halves of equal variance; (A - B)^2 has one degree of freedom, so it is
// box-smoothed first (the two-buffer variance of Rousselle et al. 2012).
Plane halfVariance(const Plane& a, const Plane& b, int radius) {
    Plane sq(a.width, a.height, a.pad);
    forEachRow(a.height, [&](int y) {
        const float* pa = a.row(y);
        const float* pb = b.row(y);
        float* out = sq.row(y);
        for (int x = 0; x < a.width; ++x) out[x] = 0.5f * (pa[x] - pb[x]) * (pa[x] - pb[x]);
    });
    return boxAverage(sq, radius);
}

// A colour weight e^-d of one candidate to that of the candidate of half
// its strength, e^-4d: squared twice. SquarableWeight is added before each
// square, so none underflows into denormals (which are slow); it changes no
// weight above 1e-10 by more than a part in 1e8, and a weight of 1e-36
// weighs nothing next to the centre's 1. (Branch-free: GCC vectorises
// neither a clamp nor a select at this threshold.)
void toNextWeakerCandidate(float* __restrict e, int n) {
    for (int x = 0; x < n; ++x) {
        float v = e[x] + SquarableWeight;
        v = v * v + SquarableWeight;
        e[x] = v * v;
    }
}

// The alpha-regression candidate: per pixel p, a weighted least-squares fit
// of the half's values over the search window to a line in
// alpha'(q) - alpha'(p), alpha' the other half's alpha (so the fit's
// feature is independent of the values fitted, as in cross-filtering),
// with the NL-means weights; its value at p is the intercept. In a volume
// the colour follows alpha (1 - transmittance: how much medium the pixel
// sees) closely, and alpha is smooth and nearly noise-free, so where the
// weights take in neighbours of more or less medium (the rim of a cloud, a
// thin strand), the line carries their values over to p's alpha instead of
// averaging them in as a weighted mean does. First-order regression on
// features is NFOR's model (Bitterli et al. 2016); here the feature is
// alpha.

// Adds one offset's sums of w a and w a^2 (a = alpha'(q) - alpha'(p)) into
// moments[0], [1] and of w a q per channel c into targets[c], for a row of
// n pixels; planes `planeSize` apart; wa: scratch of n. The sums of w and
// w q are the weighted mean's (the same weights).
void accumulateAlphaRegression(const float* __restrict w, const float* __restrict alphaP,
                               const float* __restrict alphaQ, const float* const* values, int n, float* moments,
                               float* targets, size_t planeSize, float* __restrict wa) {
    float* __restrict m1 = moments;
    float* __restrict m2 = moments + planeSize;
    for (int x = 0; x < n; ++x) {
        const float fa = alphaQ[x] - alphaP[x];
        wa[x] = w[x] * fa;
        m1[x] += wa[x];
        m2[x] += wa[x] * fa;
    }
    for (int c = 0; c < 3; ++c) {
        const float* __restrict q = values[c];
        float* __restrict t1 = targets + size_t(c) * planeSize;
        for (int x = 0; x < n; ++x) t1[x] += wa[x] * q[x];
    }
}

// Solves one pixel's 2x2 normal equations [s0 s1; s1 s2] [b0 b1]^T =
// [t0 t1]^T per channel (s0 = sum w, s1 = sum w a, s2 = sum w a^2; t0 =
// sum w q, t1 = sum w a q), with `ridge` x s0 added to s2 (a window whose
// alpha hardly varies cannot fit a slope, and falls back to the weighted
// mean): the intercepts b0 into value[0..2], and (M^-1)_00 = s2 / det, the
// weight of the pixel's own value (its weight 1, its feature 0) in its
// intercept, dF/dy for SURE, into hat. False where that is not finite.
bool solveAlphaRegression(double s0, double s1, double s2, const double* t0, const double* t1, double ridge,
                          float* value, float* hat) {
    s2 += ridge * s0;
    const double det = s0 * s2 - s1 * s1;
    if (!(s0 > 0) || !(det > 1e-12 * s0 * s2)) return false;
    for (int c = 0; c < 3; ++c) {
        value[c] = float((s2 * t0[c] - s1 * t1[c]) / det);
        if (!std::isfinite(value[c])) return false;
    }
    *hat = float(s2 / det);
    return std::isfinite(*hat);
}

// What every tile of the candidate filters reads. Cross-filtering
// (Rousselle et al. 2012 and 2013): half A is averaged with weights from half
// B's patches and vice versa, so the weights' residual noise is independent
// of the values they average; the output is the mean of the two. The final
// weight is min(colour weight, feature weight) (Rousselle et al. 2013), one
// exponential of the larger distance.
struct FilterSetup {
    FilterSetup(const ColourHalves& halves, const std::vector<Feature>& features, const DenoiseOptions& options);

    const ColourHalves& halves;
    const std::vector<Feature>& features;
    const DenoiseOptions& options;
    int w, h, channels, f, radius;
    // The patch distance is the colour's alone; alpha is averaged with the
    // colour's weights. In a volume, alpha (1 - transmittance) has strong
    // structure and little noise (the marchers estimate it smoothly), so a
    // distance that held it rejected nearly every neighbour (BENCHMARKS.md).
    Guide guide;
    // Candidate filters (Rousselle, Manzi and Zwicker 2013): the same
    // distances at colour strengths k_j = k_c 2^j. The colour distance
    // scales as 1/k^2, so a candidate's colour weight is the fourth power
    // of the next stronger one's: one exponential (of the strongest)
    // serves them all. `inverse[j]` gets 1/2 (1/sum wA + 1/sum wB), the
    // derivative of the output with respect to the pixel's own value
    // (its centre weight is 1), for SURE.
    size_t candidates;
    float strongestScale;
    bool withFeatures;
    // The alpha-regression candidate, when there is alpha, comes after the
    // weighted means and takes the weights of the strongest.
    bool regression;
    size_t regressionAt, filters;
};

FilterSetup::FilterSetup(const ColourHalves& halves_, const std::vector<Feature>& features_,
                         const DenoiseOptions& options_)
    : halves(halves_), features(features_), options(options_), w(halves_.a[0].width), h(halves_.a[0].height),
      channels(halves_.channels), f(options_.patchRadius), radius(options_.searchRadius) {
    for (int c = 0; c < 3; ++c) {
        guide.values.push_back(&halves.a[size_t(c)]);
        guide.secondValues.push_back(&halves.b[size_t(c)]);
        guide.variances.push_back(&halves.variance[size_t(c)]);
    }
    guide.norm = 1.f / float(3 * (2 * f + 1) * (2 * f + 1));
    candidates = size_t(options.candidates);
    guide.k2 = options.colorStrength * options.colorStrength;
    strongestScale = std::ldexp(1.f, -2 * (options.candidates - 1));
    withFeatures = !features.empty();
    regression = options.alphaRegression && channels == 4;
    regressionAt = candidates - 1;
    filters = candidates + (regression ? 1 : 0);
}

// One tile's running sums. Per candidate: sums of w * value per channel (A
// filtered with B's weights, and B with A's), then the sums of the weights;
// the alpha regression's moments and targets where it runs.
struct TileSums {
    TileSums(const FilterSetup& s, const Rect& tile)
        : tw(tile.width()), n(tw * tile.height()), tilePixels(static_cast<size_t>(n)),
          sumSize(size_t(s.channels) * size_t(n)), sumA(s.candidates * sumSize, 0.f),
          sumB(s.candidates * sumSize, 0.f), weightsA(s.candidates * tilePixels, 0.f),
          weightsB(s.candidates * tilePixels, 0.f) {
        if (s.regression) {
            momentsA.assign(2 * tilePixels, 0.f);
            momentsB.assign(2 * tilePixels, 0.f);
            targetsA.assign(3 * tilePixels, 0.f);
            targetsB.assign(3 * tilePixels, 0.f);
        }
    }

    int tw, n;
    size_t tilePixels, sumSize;
    std::vector<float> sumA, sumB, weightsA, weightsB;
    std::vector<float> momentsA, momentsB, targetsA, targetsB;
};

// A tile's patch distances of one offset, and one row's weights.
struct TileScratch {
    TileScratch(const FilterSetup& s, const TileSums& sums)
        : box(TileSize, s.f), distanceA(sums.tilePixels), distanceB(sums.tilePixels),
          featureScratch(size_t(sums.tw)), weightA(size_t(sums.tw)), weightB(size_t(sums.tw)),
          colourA(size_t(sums.tw)), colourB(size_t(sums.tw)), featureWeight(size_t(sums.tw)),
          regressionScratch(size_t(sums.tw)) {}

    BoxScratch box;
    std::vector<float> distanceA, distanceB, featureScratch, weightA, weightB, colourA, colourB, featureWeight,
        regressionScratch;
};

// Candidate j's weights of row y of `r` at offset (dx, dy), the smaller of
// its colour weights (eA, eB) and the feature weight (ef), added into the
// tile's sums with the values they weigh (and into the alpha regression's
// at its candidate). `base`: the row's first pixel in the tile's sums.
void accumulateCandidate(const FilterSetup& s, size_t j, const Rect& r, int y, int dx, int dy, size_t base,
                         const float* __restrict eA, const float* __restrict eB, const float* __restrict ef,
                         TileScratch& t, TileSums& sums) {
    const std::vector<Plane>& a = s.halves.a;
    const std::vector<Plane>& b = s.halves.b;
    const int rw = r.width();
    const float* __restrict wA = eA;
    const float* __restrict wB = eB;
    if (s.withFeatures) {
        for (int x = 0; x < rw; ++x) {
            t.weightA[size_t(x)] = eA[x] < ef[x] ? eA[x] : ef[x];
            t.weightB[size_t(x)] = eB[x] < ef[x] ? eB[x] : ef[x];
        }
        wA = t.weightA.data();
        wB = t.weightB.data();
    }
    float* __restrict sa = &sums.weightsA[j * sums.tilePixels + base];
    float* __restrict sb = &sums.weightsB[j * sums.tilePixels + base];
    for (int x = 0; x < rw; ++x) sa[x] += wA[x], sb[x] += wB[x];
    if (s.regression && j == s.regressionAt) {
        // A is fitted on B's alpha and B on A's.
        const float* qa[3];
        const float* qb[3];
        for (int c = 0; c < 3; ++c) {
            qa[c] = a[size_t(c)].row(y + dy) + r.x0 + dx;
            qb[c] = b[size_t(c)].row(y + dy) + r.x0 + dx;
        }
        accumulateAlphaRegression(wA, b[3].row(y) + r.x0, b[3].row(y + dy) + r.x0 + dx, qa, rw,
                                  &sums.momentsA[base], &sums.targetsA[base], sums.tilePixels,
                                  t.regressionScratch.data());
        accumulateAlphaRegression(wB, a[3].row(y) + r.x0, a[3].row(y + dy) + r.x0 + dx, qb, rw,
                                  &sums.momentsB[base], &sums.targetsB[base], sums.tilePixels,
                                  t.regressionScratch.data());
    }
    for (int c = 0; c < s.channels; ++c) {
        const float* __restrict qa = a[size_t(c)].row(y + dy) + r.x0 + dx;
        const float* __restrict qb = b[size_t(c)].row(y + dy) + r.x0 + dx;
        const size_t offset = j * sums.sumSize + size_t(c) * size_t(sums.n) + base;
        float* __restrict accA = &sums.sumA[offset];
        float* __restrict accB = &sums.sumB[offset];
        for (int x = 0; x < rw; ++x) accA[x] += wA[x] * qa[x], accB[x] += wB[x] * qb[x];
    }
}

// Row y of `r` at offset (dx, dy), its patch distances in t.distanceA/B:
// the colour weights of the strongest candidate and the feature weight, then
// per candidate from the strongest down, the colour weight squared twice.
void accumulateRow(const FilterSetup& s, const Rect& tile, const Rect& r, int y, int dx, int dy, TileScratch& t,
                   TileSums& sums) {
    const int rw = r.width();
    const float* __restrict dB = &t.distanceB[size_t(y - r.y0) * size_t(rw)];
    const float* __restrict dA = &t.distanceA[size_t(y - r.y0) * size_t(rw)];
    const size_t base = size_t(y - tile.y0) * size_t(sums.tw) + size_t(r.x0 - tile.x0);
    float* __restrict eA = t.colourA.data();
    float* __restrict eB = t.colourB.data();
    float* __restrict ef = t.featureWeight.data();
    const float norm = s.guide.norm * s.strongestScale;
    for (int x = 0; x < rw; ++x) {
        eA[x] = clampDistance(dB[x] * norm);
        eB[x] = clampDistance(dA[x] * norm);
    }
    for (int x = 0; x < rw; ++x) eA[x] = expMinus(eA[x]), eB[x] = expMinus(eB[x]);
    if (s.withFeatures) {
        featureRowDistance(s.features, y, dx, dy, r.x0, r.x1, ef, t.featureScratch.data());
        for (int x = 0; x < rw; ++x) ef[x] = clampDistance(ef[x]);
        for (int x = 0; x < rw; ++x) ef[x] = expMinus(ef[x]);
    }
    for (size_t j = s.candidates; j-- > 0;) {
        if (j + 1 < s.candidates) {
            toNextWeakerCandidate(eA, rw);
            toNextWeakerCandidate(eB, rw);
        }
        accumulateCandidate(s, j, r, y, dx, dy, base, eA, eB, ef, t, sums);
    }
}

// The weighted means of the tile's pixels, per candidate, and their dF/dy.
// The centre weight is 1 (its distances are <= 0; to the rounding of the
// running sums), so the sums of the weights are about >= 1.
void writeMeans(const FilterSetup& s, const Rect& tile, const TileSums& sums, Candidates& out) {
    const std::vector<Plane>& a = s.halves.a;
    const std::vector<Plane>& b = s.halves.b;
    for (size_t j = 0; j < s.candidates; ++j)
        for (int y = tile.y0; y < tile.y1; ++y)
            for (int x = tile.x0; x < tile.x1; ++x) {
                const size_t i = size_t(y - tile.y0) * size_t(sums.tw) + size_t(x - tile.x0);
                const float sa = sums.weightsA[j * sums.tilePixels + i], sb = sums.weightsB[j * sums.tilePixels + i];
                for (int c = 0; c < s.channels; ++c) {
                    const size_t k = j * sums.sumSize + size_t(c) * size_t(sums.n) + i;
                    float v = 0.5f * (sums.sumA[k] / sa + sums.sumB[k] / sb);
                    if (!finite(v)) v = 0.5f * (a[size_t(c)].at(x, y) + b[size_t(c)].at(x, y));
                    out.filtered[j][size_t(c)].at(x, y) = v;
                }
                out.inverse[j].at(x, y) = 0.5f * (1.f / std::max(sa, 1.f) + 1.f / std::max(sb, 1.f));
            }
}

// The regression's intercepts of the tile's pixels; where a solution is not
// finite, the weighted mean of its weights. Alpha itself is the mean's.
void writeRegression(const FilterSetup& s, const Rect& tile, const TileSums& tileSums, Candidates& out) {
    const size_t regressionAt = s.regressionAt, sumSize = tileSums.sumSize, tilePixels = tileSums.tilePixels;
    const int n = tileSums.n;
    for (int y = tile.y0; y < tile.y1; ++y)
        for (int x = tile.x0; x < tile.x1; ++x) {
            const size_t i = size_t(y - tile.y0) * size_t(tileSums.tw) + size_t(x - tile.x0);
            // The slope's ridge: a constant, and the expected square of the
            // feature's own noise (a difference of two pixels' alpha), scaled.
            const double ridge = double(s.options.regressionRidge) +
                                 double(s.options.regressionNoiseRidge) * 2.0 * double(s.halves.variance[3].at(x, y));
            auto solve = [&](const std::vector<float>& weights, const std::vector<float>& sums,
                             const std::vector<float>& moments, const std::vector<float>& targets, float* value,
                             float* hat) {
                double t0[3], t1[3];
                for (size_t c = 0; c < 3; ++c) {
                    t0[c] = sums[regressionAt * sumSize + c * size_t(n) + i];
                    t1[c] = targets[c * tilePixels + i];
                }
                return solveAlphaRegression(weights[regressionAt * tilePixels + i], moments[i],
                                            moments[tilePixels + i], t0, t1, ridge, value, hat);
            };
            float va[3], vb[3], ha = 0, hb = 0;
            const bool ok = solve(tileSums.weightsA, tileSums.sumA, tileSums.momentsA, tileSums.targetsA, va, &ha) &&
                            solve(tileSums.weightsB, tileSums.sumB, tileSums.momentsB, tileSums.targetsB, vb, &hb);
            for (int c = 0; c < s.channels; ++c)
                out.filtered[s.candidates][size_t(c)].at(x, y) =
                    ok && c < 3 ? 0.5f * (va[c] + vb[c]) : out.filtered[regressionAt][size_t(c)].at(x, y);
            out.inverse[s.candidates].at(x, y) = ok ? 0.5f * (ha + hb) : out.inverse[regressionAt].at(x, y);
        }
}

// Every candidate's output for the pixels of one tile: the sums over the
// search window's offsets, then their means and intercepts.
void filterTile(const FilterSetup& s, const Rect& tile, Candidates& out) {
    TileSums sums(s, tile);
    TileScratch scratch(s, sums);
    for (int dy = -s.radius; dy <= s.radius; ++dy)
        for (int dx = -s.radius; dx <= s.radius; ++dx) {
            const Rect r = partnersInside(tile, dx, dy, s.w, s.h);
            if (r.empty()) continue;
            patchDistances(s.guide, r, dx, dy, s.f, scratch.box, scratch.distanceA.data(), scratch.distanceB.data());
            for (int y = r.y0; y < r.y1; ++y) accumulateRow(s, tile, r, y, dx, dy, scratch, sums);
        }
    writeMeans(s, tile, sums, out);
    if (s.regression) writeRegression(s, tile, sums, out);
}

}  // namespace

ColourHalves loadColourHalves(const DenoiseInput& in, const DenoiseOptions& options, int pad) {
    const int w = in.width, h = in.height;
    const int channels = in.alphaA.empty() ? 3 : 4;
    const size_t planes = static_cast<size_t>(channels);
    std::vector<Plane> a(planes), b(planes), variance(planes), clamped(3), clampedLight(3);
    for (int c = 0; c < channels; ++c) {
        if (c < 3) {
            const size_t k = size_t(c);
            loadHalves(channelOf(in.halfA, c), channelOf(in.halfB, c), w, h, pad, a[k], b[k]);
            if (options.suppressFireflies) clampedLight[k] = suppressFireflies(a[k], b[k]);
            clamped[k] = Plane(w, h, 0);
            forEachRow(h, [&](int y) {
                for (int x = 0; x < w; ++x) clamped[k].at(x, y) = 0.5f * (a[k].at(x, y) + b[k].at(x, y));
            });
        } else
            loadHalves(in.alphaA, in.alphaB, w, h, pad, a[3], b[3]);
        variance[size_t(c)] = halfVariance(a[size_t(c)], b[size_t(c)], options.varianceRadius);
    }
    return {channels, std::move(a), std::move(b), std::move(variance), std::move(clamped), std::move(clampedLight)};
}

Candidates filterCandidates(const ColourHalves& halves, const std::vector<Feature>& features,
                            const DenoiseOptions& options) {
    const FilterSetup s(halves, features, options);
    Candidates out;
    out.filtered.assign(s.filters, std::vector<Plane>(size_t(s.channels), Plane(s.w, s.h, 0)));
    out.inverse.assign(s.filters, Plane(s.w, s.h, 0));
    forEachTile(s.w, s.h, [&](const Rect& tile) { filterTile(s, tile, out); });
    return out;
}

}  // namespace vdbmarch::denoising
