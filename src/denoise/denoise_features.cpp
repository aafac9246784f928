#include "denoise/denoise_features.h"

#include "denoise/denoise_nlmeans.h"

namespace vdbmarch::denoising {

namespace {

// Finite feature values are clamped to this magnitude (the features lie in
// about [0, 1]) so that no square or sum of them overflows.
constexpr float FeatureLimit = 1e3f;
// Depth at or beyond this is "nothing met" (the renderer writes 1e10).
constexpr float FarDepth = 1e9f;
// E[median of the 8 squared differences to the neighbours] / sigma^2 for
// i.i.d. Gaussian noise: 1.407, measured over 2e5 simulated pixels.
constexpr float MedianSquaredDifferenceScale = 1.407f;

Plane featurePlane(const std::vector<float>& v, int w, int h, int pad, float missingValue) {
    Plane p(w, h, pad);
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const float value = v[size_t(y) * size_t(w) + size_t(x)];
            p.at(x, y) = finite(value) ? clampMagnitude(value, FeatureLimit) : missingValue;
        }
    });
    p.replicateEdges();
    return p;
}

// Depth in [0, 1): z / (z + the median depth of the pixels that met
// something), so that the feature scale (tau) is relative to the scene's
// depth and "nothing met" (1e10, non-finite) is 1, the far limit. Empty when
// no pixel met anything.
std::vector<float> normalisedDepth(const std::vector<float>& depth) {
    std::vector<float> met;
    for (float z : depth)
        if (finite(z) && z < FarDepth) met.push_back(std::max(z, 0.f));
    if (met.empty()) return {};
    std::nth_element(met.begin(), met.begin() + met.size() / 2, met.end());
    const float median = met[met.size() / 2];
    const float reference = median > 0 ? median : 1.f;
    std::vector<float> out(depth.size());
    for (size_t i = 0; i < depth.size(); ++i) {
        const float z = depth[i];
        out[i] = finite(z) && z < FarDepth ? std::max(z, 0.f) / (std::max(z, 0.f) + reference) : 1.f;
    }
    return out;
}

// The median of n <= 8 values (the mean of the middle two for even n),
// sorting them in place. Eight values (every pixel but the border ones) go
// through a branch-free sorting network of 19 compare-exchanges (the fewest
// for 8 inputs; Knuth, TAOCP vol. 3, section 5.3.4), as random data defeats
// branch prediction; fewer, by insertion.
float medianOf(float* v, int n) {
    if (n == 8) {
        auto exchange = [v](int i, int j) {
            const float lo = std::min(v[i], v[j]), hi = std::max(v[i], v[j]);
            v[i] = lo, v[j] = hi;
        };
        exchange(0, 2), exchange(1, 3), exchange(4, 6), exchange(5, 7);
        exchange(0, 4), exchange(1, 5), exchange(2, 6), exchange(3, 7);
        exchange(0, 1), exchange(2, 3), exchange(4, 5), exchange(6, 7);
        exchange(2, 4), exchange(3, 5);
        exchange(1, 4), exchange(3, 6);
        exchange(1, 2), exchange(3, 4), exchange(5, 6);
        return 0.5f * (v[3] + v[4]);
    }
    for (int i = 1; i < n; ++i)
        for (int j = i; j > 0 && v[j] < v[j - 1]; --j) std::swap(v[j], v[j - 1]);
    if (n == 0) return 0.f;
    return n % 2 ? v[n / 2] : 0.5f * (v[n / 2 - 1] + v[n / 2]);
}

// Noise variance of a feature channel that comes without halves: the median
// of the squared differences to the 8 neighbours (robust at edges, where at
// most 3 of them lie across), over its value for pure Gaussian noise, then
// box-averaged over 5x5 (one pixel's median is itself noisy).
Plane robustNoiseVariance(const Plane& f) {
    const int w = f.width, h = f.height;
    Plane median(w, h, f.pad);
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            float d[8];
            int n = 0;
            for (int j = -1; j <= 1; ++j)
                for (int i = -1; i <= 1; ++i) {
                    if ((i == 0 && j == 0) || x + i < 0 || x + i >= w || y + j < 0 || y + j >= h) continue;
                    const float diff = f.at(x, y) - f.at(x + i, y + j);
                    d[n++] = diff * diff;
                }
            const float m = medianOf(d, n);
            median.at(x, y) = m / MedianSquaredDifferenceScale;
        }
    });
    return boxAverage(median, 2);
}

// Feature prefilter: NL-means of all the feature channels together, guided by
// themselves (as NFOR, Bitterli et al. 2016, section 5.1, prefilters its
// features; without the two feature halves it has, the guide is the feature
// itself). The variance after filtering is Var[p] sum w^2 / (sum w)^2.
void prefilterFeatures(std::vector<Feature>& features, const DenoiseOptions& o, int w, int h, int pad) {
    Guide guide;
    for (const Feature& f : features)
        for (size_t c = 0; c < f.channels.size(); ++c) {
            guide.values.push_back(&f.channels[c]);
            guide.variances.push_back(&f.variances[c]);
        }
    const int channels = int(guide.values.size());
    const int radius = o.featureSearchRadius, f = o.featurePatchRadius;
    guide.k2 = o.featurePrefilterStrength * o.featurePrefilterStrength;
    guide.norm = 1.f / float(channels * (2 * f + 1) * (2 * f + 1));

    std::vector<Plane> filtered(size_t(channels), Plane(w, h, pad));
    Plane varianceFactor(w, h, pad);  // sum w^2 / (sum w)^2
    forEachTile(w, h, [&](const Rect& tile) {
        const int tw = tile.width(), n = tw * tile.height();
        BoxScratch scratch(TileSize, f);
        std::vector<float> distance(static_cast<size_t>(n)), weight(static_cast<size_t>(tw));
        std::vector<float> sum(size_t(channels) * size_t(n), 0.f), weights(size_t(n), 0.f), squares(size_t(n), 0.f);
        for (int dy = -radius; dy <= radius; ++dy)
            for (int dx = -radius; dx <= radius; ++dx) {
                const Rect r = partnersInside(tile, dx, dy, w, h);
                if (r.empty()) continue;
                patchDistances(guide, r, dx, dy, f, scratch, distance.data(), nullptr);
                for (int y = r.y0; y < r.y1; ++y) {
                    const float* __restrict d = &distance[size_t(y - r.y0) * size_t(r.width())];
                    float* __restrict wr = weight.data();
                    for (int x = 0; x < r.width(); ++x) wr[x] = clampDistance(d[x] * guide.norm);
                    for (int x = 0; x < r.width(); ++x) wr[x] = expMinus(wr[x]);
                    const size_t base = size_t(y - tile.y0) * size_t(tw) + size_t(r.x0 - tile.x0);
                    float* __restrict ws = &weights[base];
                    float* __restrict w2 = &squares[base];
                    for (int x = 0; x < r.width(); ++x) ws[x] += wr[x], w2[x] += wr[x] * wr[x];
                    for (int c = 0; c < channels; ++c) {
                        const float* __restrict q = guide.values[size_t(c)]->row(y + dy) + r.x0 + dx;
                        float* __restrict s = &sum[size_t(c) * size_t(n) + base];
                        for (int x = 0; x < r.width(); ++x) s[x] += wr[x] * q[x];
                    }
                }
            }
        for (int y = tile.y0; y < tile.y1; ++y)
            for (int x = tile.x0; x < tile.x1; ++x) {
                const size_t i = size_t(y - tile.y0) * size_t(tw) + size_t(x - tile.x0);
                for (int c = 0; c < channels; ++c)
                    filtered[size_t(c)].at(x, y) = sum[size_t(c) * size_t(n) + i] / weights[i];
                varianceFactor.at(x, y) = squares[i] / (weights[i] * weights[i]);
            }
    });

    int c = 0;
    for (Feature& feature : features) {
        feature.varianceSum = Plane(w, h, pad);
        for (size_t k = 0; k < feature.channels.size(); ++k, ++c) {
            feature.channels[k] = std::move(filtered[size_t(c)]);
            feature.channels[k].replicateEdges();
            forEachRow(h, [&](int y) {
                for (int x = 0; x < w; ++x)
                    feature.varianceSum.at(x, y) += feature.variances[k].at(x, y) * varianceFactor.at(x, y);
            });
        }
        feature.varianceSum.replicateEdges();
        feature.variances.clear();
    }
}

// 1 / (k_f^2 max(tau, Var_j[p], |grad f_j(p)|^2)): the scale of feature j's
// distance (Rousselle, Manzi and Zwicker 2013). The gradient term keeps smooth
// ramps (depth of a slanted surface) from reading as edges.
void featureScales(std::vector<Feature>& features, const DenoiseOptions& o, int w, int h, int pad) {
    const float k2 = o.featureStrength * o.featureStrength;
    for (Feature& feature : features) {
        feature.inverseScale = Plane(w, h, pad);
        forEachRow(h, [&](int y) {
            for (int x = 0; x < w; ++x) {
                float gradient2 = 0;
                for (const Plane& c : feature.channels) {
                    const float gx = 0.5f * (c.at(x + 1, y) - c.at(x - 1, y));
                    const float gy = 0.5f * (c.at(x, y + 1) - c.at(x, y - 1));
                    gradient2 += gx * gx + gy * gy;
                }
                const float scale = std::max(o.featureThreshold, std::max(feature.varianceSum.at(x, y), gradient2));
                feature.inverseScale.at(x, y) = 1.f / (k2 * scale);
            }
        });
        feature.inverseScale.replicateEdges();
    }
}

}  // namespace

std::vector<Feature> loadFeatures(const DenoiseInput& in, const DenoiseOptions& options, int pad) {
    const int w = in.width, h = in.height;
    std::vector<Feature> features;
    if (!options.useFeatures) return features;
    auto add = [&](const std::vector<std::vector<float>>& channelValues, float missingValue) {
        Feature f;
        for (const auto& v : channelValues) {
            f.channels.push_back(featurePlane(v, w, h, pad, missingValue));
            f.variances.push_back(robustNoiseVariance(f.channels.back()));
        }
        features.push_back(std::move(f));
    };
    auto channels3 = [](const std::vector<Color>& v) {
        return std::vector<std::vector<float>>{channelOf(v, 0), channelOf(v, 1), channelOf(v, 2)};
    };
    if (!in.albedo.empty()) add(channels3(in.albedo), 0.f);
    if (!in.normal.empty()) add(channels3(in.normal), 0.f);
    if (!in.depth.empty()) {
        std::vector<float> depth = normalisedDepth(in.depth);
        if (!depth.empty()) add({depth}, 1.f);
    }
    if (!features.empty()) {
        prefilterFeatures(features, options, w, h, pad);
        featureScales(features, options, w, h, pad);
    }
    return features;
}

void featureRowDistance(const std::vector<Feature>& features, int y, int dx, int dy, int x0, int x1,
                        float* __restrict out, float* __restrict scratch) {
    const int n = x1 - x0;
    for (int x = 0; x < n; ++x) out[x] = 0;
    for (const Feature& feature : features) {
        // |f_j(p) - f_j(q)|^2: one pass for the three channels of a colour
        // or vector feature, else channel by channel.
        const std::vector<Plane>& c = feature.channels;
        if (c.size() == 3) {
            const float* __restrict p0 = c[0].row(y) + x0;
            const float* __restrict q0 = c[0].row(y + dy) + x0 + dx;
            const float* __restrict p1 = c[1].row(y) + x0;
            const float* __restrict q1 = c[1].row(y + dy) + x0 + dx;
            const float* __restrict p2 = c[2].row(y) + x0;
            const float* __restrict q2 = c[2].row(y + dy) + x0 + dx;
            for (int x = 0; x < n; ++x) {
                const float d0 = p0[x] - q0[x], d1 = p1[x] - q1[x], d2 = p2[x] - q2[x];
                scratch[x] = d0 * d0 + d1 * d1 + d2 * d2;
            }
        } else {
            for (int x = 0; x < n; ++x) scratch[x] = 0;
            for (const Plane& channel : c) {
                const float* __restrict fp = channel.row(y) + x0;
                const float* __restrict fq = channel.row(y + dy) + x0 + dx;
                for (int x = 0; x < n; ++x) {
                    const float d = fp[x] - fq[x];
                    scratch[x] += d * d;
                }
            }
        }
        const float* __restrict vp = feature.varianceSum.row(y) + x0;
        const float* __restrict vq = feature.varianceSum.row(y + dy) + x0 + dx;
        const float* __restrict s = feature.inverseScale.row(y) + x0;
        for (int x = 0; x < n; ++x) {
            const float vmin = vp[x] < vq[x] ? vp[x] : vq[x];
            const float d = (scratch[x] - (vp[x] + vmin)) * s[x];
            out[x] = d > out[x] ? d : out[x];
        }
    }
}

}  // namespace vdbmarch::denoising
