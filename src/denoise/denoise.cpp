#include "denoise/denoise.h"

#include "core/error.h"
#include "core/threads.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace vdbmarch {

namespace {

// Output tiles of the NL-means passes. Fixed (not derived from the thread
// count) so that the running sums start at the same pixels and the result is
// bit-identical for any number of threads.
constexpr int TileSize = 64;
// Keeps the distance finite where both variances are 0 (noise-free input):
// there only (nearly) identical values are averaged.
constexpr float DistanceEpsilon = 1e-10f;
// The least colour weight squared (toNextWeakerCandidate): its square is
// still a normal float.
constexpr float SquarableWeight = 1e-18f;
// A pixel distance this large already makes the weight of any patch that
// holds it negligible (1e4 / 49 > 87 for a 7x7 patch of one channel); the
// clamp keeps the running sums of the box filter precise.
constexpr float DistanceClamp = 1e4f;
// Finite inputs are clamped to this magnitude so that no square, sum or
// product below overflows (4e30 squared differences, sums of a few thousand).
constexpr float ColorLimit = 1e15f;
constexpr float FeatureLimit = 1e3f;
// Depth at or beyond this is "nothing met" (the renderer writes 1e10).
constexpr float FarDepth = 1e9f;
// E[median of the 8 squared differences to the neighbours] / sigma^2 for
// i.i.d. Gaussian noise: 1.407, measured over 2e5 simulated pixels.
constexpr float MedianSquaredDifferenceScale = 1.407f;
// An emitted part (DenoiseInput::emittedA/B) whose halves differ by at most
// this share of the image's half-difference variance is added unfiltered.
constexpr double EmittedNoiseShare = 0.05;

// ---------------------------------------------------------------------------
// A float plane with `pad` replicated pixels on every side, so that patch
// reads near the border need no clamping in the inner loops.
struct Plane {
    int width = 0, height = 0, pad = 0, stride = 0;
    std::vector<float> data;

    Plane() = default;
    Plane(int w, int h, int p) : width(w), height(h), pad(p), stride(w + 2 * p) {
        data.assign(size_t(stride) * size_t(h + 2 * p), 0.f);
    }
    // Row y (-pad <= y < height + pad); index it with -pad <= x < width + pad.
    float* row(int y) { return data.data() + size_t(y + pad) * size_t(stride) + size_t(pad); }
    const float* row(int y) const { return data.data() + size_t(y + pad) * size_t(stride) + size_t(pad); }
    float& at(int x, int y) { return row(y)[x]; }
    float at(int x, int y) const { return row(y)[x]; }

    // Copies the edge pixels into the padding (clamp-to-edge).
    void replicateEdges() {
        for (int y = 0; y < height; ++y) {
            float* r = row(y);
            for (int x = -pad; x < 0; ++x) r[x] = r[0];
            for (int x = width; x < width + pad; ++x) r[x] = r[width - 1];
        }
        for (int y = -pad; y < 0; ++y) std::memcpy(row(y) - pad, row(0) - pad, sizeof(float) * size_t(stride));
        for (int y = height; y < height + pad; ++y)
            std::memcpy(row(y) - pad, row(height - 1) - pad, sizeof(float) * size_t(stride));
    }
};

template <class RowFunction>
void forEachRow(int height, const RowFunction& f) {
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& r) {
        for (int y = r.begin(); y != r.end(); ++y) f(y);
    });
}

// A box of `radius` around each pixel, averaged over the pixels inside the
// image (separable, direct sums: cheap next to the NL-means passes).
Plane boxAverage(const Plane& in, int radius) {
    const int w = in.width, h = in.height;
    Plane horizontal(w, h, in.pad), out(w, h, in.pad);
    forEachRow(h, [&](int y) {
        const float* src = in.row(y);
        float* dst = horizontal.row(y);
        for (int x = 0; x < w; ++x) {
            const int x0 = std::max(0, x - radius), x1 = std::min(w - 1, x + radius);
            float sum = 0;
            for (int i = x0; i <= x1; ++i) sum += src[i];
            dst[x] = sum / float(x1 - x0 + 1);
        }
    });
    forEachRow(h, [&](int y) {
        const int y0 = std::max(0, y - radius), y1 = std::min(h - 1, y + radius);
        float* dst = out.row(y);
        for (int x = 0; x < w; ++x) dst[x] = 0;
        for (int i = y0; i <= y1; ++i) {
            const float* src = horizontal.row(i);
            for (int x = 0; x < w; ++x) dst[x] += src[x];
        }
        const float scale = 1.f / float(y1 - y0 + 1);
        for (int x = 0; x < w; ++x) dst[x] *= scale;
    });
    out.replicateEdges();
    return out;
}

// A separable Gaussian of standard deviation `sigma` pixels, cut at 3 sigma.
// Per axis, W(i) is the kernel's weight inside the image around pixel i (the
// same for a pixel gathering and a pixel giving, the kernel being
// symmetric). Average: each pixel becomes its neighbours' weighted sum
// divided by its own W (a constant stays that constant). Spread:
// each pixel gives its value to its neighbours, divided by its W first (the
// sum over the image stays that sum).
enum class GaussianMode { Average, Spread };

Plane gaussian(const Plane& in, float sigma, GaussianMode mode) {
    const int w = in.width, h = in.height, radius = int(std::ceil(3.f * sigma));
    std::vector<float> kernel(size_t(2 * radius + 1));
    for (int i = -radius; i <= radius; ++i)
        kernel[size_t(i + radius)] = std::exp(-0.5f * float(i * i) / (sigma * sigma));
    auto inverseWeights = [&](int size) {
        std::vector<float> inverse(static_cast<size_t>(size));
        for (int i = 0; i < size; ++i) {
            float sum = 0;
            for (int p = std::max(0, i - radius); p <= std::min(size - 1, i + radius); ++p)
                sum += kernel[size_t(p - i + radius)];
            inverse[size_t(i)] = 1.f / sum;
        }
        return inverse;
    };
    const std::vector<float> inverseX = inverseWeights(w), inverseY = inverseWeights(h);
    const bool spread = mode == GaussianMode::Spread;
    Plane horizontal(w, h, in.pad), out(w, h, in.pad);
    forEachRow(h, [&](int y) {
        const float* src = in.row(y);
        float* dst = horizontal.row(y);
        for (int x = 0; x < w; ++x) {
            float sum = 0;
            for (int i = std::max(0, x - radius); i <= std::min(w - 1, x + radius); ++i)
                sum += kernel[size_t(i - x + radius)] * (spread ? src[i] * inverseX[size_t(i)] : src[i]);
            dst[x] = spread ? sum : sum * inverseX[size_t(x)];
        }
    });
    forEachRow(h, [&](int y) {
        float* dst = out.row(y);
        for (int x = 0; x < w; ++x) dst[x] = 0;
        for (int j = std::max(0, y - radius); j <= std::min(h - 1, y + radius); ++j) {
            const float k = kernel[size_t(j - y + radius)] * (spread ? inverseY[size_t(j)] : inverseY[size_t(y)]);
            const float* src = horizontal.row(j);
            for (int x = 0; x < w; ++x) dst[x] += k * src[x];
        }
    });
    return out;
}

// Distances are clamped to [0, 87] before expMinus: a negative distance
// (two values closer than their noise) weighs 1, and e^-87 < 2e-38 is as good
// as 0. A loop of its own, since a clamp in the loop of the exponential keeps
// GCC from vectorising it (the conversion to int may trap).
inline float clampDistance(float d) {
    d = d > 0.f ? d : 0.f;
    return d < 87.f ? d : 87.f;
}

// e^-d for d in [0, 87] without a library call, so the weight loops
// vectorise: -d = (i + f) / log2(e) with f in [-1/2, 1/2], 2^f by its Taylor
// series to degree 6, 2^i in the exponent bits. Relative error below 7e-7
// for d < 10 and 4e-6 near 87 (the rounding of d log2(e) dominates).
inline float expMinus(float d) {
    const float t = d * -1.44269504f;
    const int i = int(t - 0.5f);  // t <= 0: truncation rounds to nearest
    const float f = (t - float(i)) * 0.693147181f;
    const float p =
        1.f + f * (1.f + f * (0.5f + f * (1.f / 6 + f * (1.f / 24 + f * (1.f / 120 + f * (1.f / 720))))));
    const int32_t bits = (i + 127) << 23;
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return p * scale;
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

// ---------------------------------------------------------------------------
// Patch distances: the NL-means distance of Rousselle, Knaus and Zwicker
// 2012, with the variance cancellation, as Rousselle, Manzi and Zwicker 2013
// use it for their colour weights. Per channel i
//   d_i^2(p, q) = ((u_i(p) - u_i(q))^2 - (Var_i[p] + min(Var_i[p], Var_i[q])))
//                 / (eps + k^2 (Var_i[p] + Var_i[q])),
// averaged over the channels and over the (2f+1)^2 pixel pairs (p+n, q+n) of
// the two patches; the weight is exp(-max(0, d^2)). The variance terms cancel
// the expected squared difference of two noisy values, so equal means give a
// distance of about 0 whatever the noise.

// The values whose patches are compared, one plane per channel, with their
// variances. `secondValues`, when given, are the other half render: both
// halves' distances come from one pass, as they share the variances and so
// the division.
struct Guide {
    std::vector<const Plane*> values, secondValues, variances;
    float k2 = 1;    // k^2
    float norm = 1;  // 1 / (channels (2f+1)^2)
};

// d_i^2 summed over the channels of `g` for the pixels x0 <= x < x1 of row y
// and their partners at (x + dx, y + dy), into e[0 .. x1-x0) (and second[]
// for the second values).
void guideRowDistance(const Guide& g, int y, int dx, int dy, int x0, int x1, float* __restrict e,
                      float* __restrict second) {
    const int n = x1 - x0;
    const bool pair = !g.secondValues.empty();
    const float k2 = g.k2;
    for (int x = 0; x < n; ++x) e[x] = 0;
    if (pair)
        for (int x = 0; x < n; ++x) second[x] = 0;
    for (size_t c = 0; c < g.values.size(); ++c) {
        const float* __restrict up = g.values[c]->row(y) + x0;
        const float* __restrict uq = g.values[c]->row(y + dy) + x0 + dx;
        const float* __restrict vp = g.variances[c]->row(y) + x0;
        const float* __restrict vq = g.variances[c]->row(y + dy) + x0 + dx;
        if (!pair) {
            for (int x = 0; x < n; ++x) {
                const float d = up[x] - uq[x];
                const float vmin = vp[x] < vq[x] ? vp[x] : vq[x];
                e[x] += (d * d - (vp[x] + vmin)) / (DistanceEpsilon + k2 * (vp[x] + vq[x]));
            }
            continue;
        }
        const float* __restrict sp = g.secondValues[c]->row(y) + x0;
        const float* __restrict sq = g.secondValues[c]->row(y + dy) + x0 + dx;
        for (int x = 0; x < n; ++x) {
            const float d = up[x] - uq[x], ds = sp[x] - sq[x];
            const float vmin = vp[x] < vq[x] ? vp[x] : vq[x];
            const float cancel = vp[x] + vmin;
            const float scale = 1.f / (DistanceEpsilon + k2 * (vp[x] + vq[x]));
            e[x] += (d * d - cancel) * scale;
            second[x] += (ds * ds - cancel) * scale;
        }
    }
    for (int x = 0; x < n; ++x) e[x] = e[x] < DistanceClamp ? e[x] : DistanceClamp;  // NaN-safe
    if (pair)
        for (int x = 0; x < n; ++x) second[x] = second[x] < DistanceClamp ? second[x] : DistanceClamp;
}

// The rectangle [x0, x1) x [y0, y1) of a tile whose partners (x + dx, y + dy)
// lie inside the image: the search window is clamped to the image.
struct Rect {
    int x0, y0, x1, y1;
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    bool empty() const { return x1 <= x0 || y1 <= y0; }
};

Rect partnersInside(const Rect& tile, int dx, int dy, int width, int height) {
    return {std::max(tile.x0, -dx), std::max(tile.y0, -dy), std::min(tile.x1, width - dx),
            std::min(tile.y1, height - dy)};
}

// Scratch of the box filter, sized for one tile and two sets of values.
struct BoxScratch {
    std::vector<float> rowDistance, horizontal, column;
    BoxScratch(int tile, int f)
        : rowDistance(2 * size_t(tile + 2 * f) * size_t(tile + 2 * f)),
          horizontal(2 * size_t(tile + 2 * f) * size_t(tile)), column(size_t(tile)) {}
};

// Running sums of 2f+1 consecutive values along `rows` rows of `e` (row
// stride `stride`) into h (row stride w): h[x] = e[x] + ... + e[x + 2f].
// Four rows at a time, so that four independent chains of additions overlap
// (one chain alone waits on the latency of each addition).
void horizontalBoxSums(const float* e, int stride, int rows, int w, int f, float* h) {
    const int span = 2 * f + 1;
    int i = 0;
    for (; i + 4 <= rows; i += 4) {
        const float* __restrict e0 = e + size_t(i) * size_t(stride);
        const float* __restrict e1 = e0 + stride;
        const float* __restrict e2 = e1 + stride;
        const float* __restrict e3 = e2 + stride;
        float* __restrict h0 = h + size_t(i) * size_t(w);
        float* __restrict h1 = h0 + w;
        float* __restrict h2 = h1 + w;
        float* __restrict h3 = h2 + w;
        float s0 = 0, s1 = 0, s2 = 0, s3 = 0;
        for (int k = 0; k < span; ++k) s0 += e0[k], s1 += e1[k], s2 += e2[k], s3 += e3[k];
        h0[0] = s0, h1[0] = s1, h2[0] = s2, h3[0] = s3;
        for (int x = 1; x < w; ++x) {
            s0 += e0[x + 2 * f] - e0[x - 1];
            s1 += e1[x + 2 * f] - e1[x - 1];
            s2 += e2[x + 2 * f] - e2[x - 1];
            s3 += e3[x + 2 * f] - e3[x - 1];
            h0[x] = s0, h1[x] = s1, h2[x] = s2, h3[x] = s3;
        }
    }
    for (; i < rows; ++i) {
        const float* __restrict e0 = e + size_t(i) * size_t(stride);
        float* __restrict h0 = h + size_t(i) * size_t(w);
        float s0 = 0;
        for (int k = 0; k < span; ++k) s0 += e0[k];
        h0[0] = s0;
        for (int x = 1; x < w; ++x) {
            s0 += e0[x + 2 * f] - e0[x - 1];
            h0[x] = s0;
        }
    }
}

// Running sums down the columns of `rows` + 2f rows of h (row stride w).
void verticalBoxSums(const float* h, int rows, int w, int f, float* column, float* out) {
    const int span = 2 * f + 1;
    for (int x = 0; x < w; ++x) column[x] = 0;
    for (int k = 0; k < span; ++k) {
        const float* __restrict hk = h + size_t(k) * size_t(w);
        for (int x = 0; x < w; ++x) column[x] += hk[x];
    }
    for (int y = 0; y < rows; ++y) {
        float* __restrict o = out + size_t(y) * size_t(w);
        for (int x = 0; x < w; ++x) o[x] = column[x];
        if (y + 1 == rows) break;
        const float* __restrict enter = h + size_t(y + span) * size_t(w);
        const float* __restrict leave = h + size_t(y) * size_t(w);
        for (int x = 0; x < w; ++x) column[x] += enter[x] - leave[x];
    }
}

// Patch distances of one offset for every pixel of `r`: the pixel distances
// of the rectangle grown by f, box-filtered by running sums along the rows,
// then down the columns, so the cost per pixel does not depend on the patch
// size. out[(y - r.y0) * r.width() + (x - r.x0)] = the (unnormalised) sum;
// second[] the same for the guide's second values.
void patchDistances(const Guide& g, const Rect& r, int dx, int dy, int f, BoxScratch& s, float* out,
                    float* second) {
    const int w = r.width(), rows = r.height() + 2 * f, stride = w + 2 * f;
    const bool pair = !g.secondValues.empty();
    float* e = s.rowDistance.data();
    float* eSecond = e + size_t(rows) * size_t(stride);  // the second set's rows follow the first's
    for (int i = 0; i < rows; ++i)
        guideRowDistance(g, r.y0 - f + i, dx, dy, r.x0 - f, r.x1 + f, e + size_t(i) * size_t(stride),
                         eSecond + size_t(i) * size_t(stride));
    horizontalBoxSums(e, stride, pair ? 2 * rows : rows, w, f, s.horizontal.data());
    verticalBoxSums(s.horizontal.data(), r.height(), w, f, s.column.data(), out);
    if (pair)
        verticalBoxSums(s.horizontal.data() + size_t(rows) * size_t(w), r.height(), w, f, s.column.data(), second);
}

template <class TileFunction>
void forEachTile(int width, int height, const TileFunction& f) {
    const int tilesX = (width + TileSize - 1) / TileSize, tilesY = (height + TileSize - 1) / TileSize;
    tbb::parallel_for(tbb::blocked_range<int>(0, tilesX * tilesY, 1), [&](const tbb::blocked_range<int>& range) {
        for (int t = range.begin(); t != range.end(); ++t) {
            const int tx = t % tilesX, ty = t / tilesX;
            f(Rect{tx * TileSize, ty * TileSize, std::min(width, (tx + 1) * TileSize),
                   std::min(height, (ty + 1) * TileSize)});
        }
    });
}

// ---------------------------------------------------------------------------
// Inputs as planes.

bool finite(float v) { return std::isfinite(v); }
float clampMagnitude(float v, float limit) { return v < -limit ? -limit : (v > limit ? limit : v); }

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

std::vector<float> channelOf(const std::vector<Color>& v, int c) {
    std::vector<float> out(v.size());
    for (size_t i = 0; i < v.size(); ++i) out[i] = v[i][c];
    return out;
}

// Per-pixel variance of one half: E[(A - B)^2] = 2 Var[half] for independent
// halves of equal variance; (A - B)^2 has one degree of freedom, so it is
// box-smoothed first (the two-buffer variance of Rousselle et al. 2012).
// Fireflies: a rare, bright path lands in one half render only, and
// cross-filtering would spread it over the whole search window of every
// neighbour (a square blotch), since the other half's patches look normal
// there. A real feature shows in both halves, so each half is clamped to
// twice the other half's 3x3 maximum plus the other half's image mean (the
// floor for dark surroundings) before filtering. Returns what the clamp took
// (the mean of the two halves' excess): denoise() spreads it back as a
// faint haze after filtering, so no light is lost.
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

// A feature: its channels, denoised, with their summed variance and the
// inverse scale of the feature distance.
struct Feature {
    std::vector<Plane> channels;  // raw, then prefiltered
    std::vector<Plane> variances; // per channel, of the raw values
    Plane varianceSum;            // over the channels, after prefiltering
    Plane inverseScale;           // 1 / (k_f^2 max(tau, Var, |grad|^2))
};

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

// ---------------------------------------------------------------------------
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

// max over the features j of their distance (Rousselle et al. 2013):
//   (|f_j(p) - f_j(q)|^2 - (Var_j[p] + min(Var_j[p], Var_j[q]))) / (k_f^2 max(...)),
// pixel to pixel (the features are prefiltered), for row y, pixels x0 <= x < x1.
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

// ---------------------------------------------------------------------------
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

// Per pixel, the candidate filter of least estimated error, blended
// smoothly (Rousselle, Manzi and Zwicker 2013, section 5). A candidate F's
// error at p is estimated by Stein's unbiased risk estimate,
//   SURE(p) = |F(p) - y(p)|^2 - s^2(p) + 2 s^2(p) dF(p)/dy(p),
// y the mean of the clamped halves (what the candidates averaged), s^2 its
// variance per channel (half the variance of a half), dF/dy = `inverse` (the pixel's own weight over the sum of the
// weights; the weights' own dependence on y is left out, as in the paper).
// One pixel's estimate is noisy, so it is box-averaged over
// (2 radius + 1)^2 pixels before the choice, and the one-hot choices are
// box-averaged again into blending weights: no seams between regions.
// With `ownWeight`, also the blend's dF/dy per pixel: the weight of the
// pixel's own value in its output (the candidates' `inverse` in the blend's
// proportions).
std::vector<Plane> selectCandidates(const std::vector<std::vector<Plane>>& filtered, const std::vector<Plane>& inverse,
                                    const std::vector<Plane>& clamped, const std::vector<Plane>& variance,
                                    int radius, Plane* ownWeight) {
    const size_t candidates = filtered.size(), planes = filtered[0].size();
    const int w = clamped[0].width, h = clamped[0].height;
    std::vector<Plane> risk;
    for (size_t j = 0; j < candidates; ++j) {
        Plane sure(w, h, 0);
        forEachRow(h, [&](int y) {
            for (int x = 0; x < w; ++x) {
                float sum = 0;
                for (size_t c = 0; c < 3; ++c) {
                    const float d = filtered[j][c].at(x, y) - clamped[c].at(x, y);
                    const float s2 = 0.5f * variance[c].at(x, y);
                    sum += d * d - s2 + 2.f * s2 * inverse[j].at(x, y);
                }
                sure.at(x, y) = sum;
            }
        });
        risk.push_back(boxAverage(sure, radius));
    }
    std::vector<Plane> choice(candidates, Plane(w, h, 0));
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            size_t best = 0;
            for (size_t j = 1; j < candidates; ++j)
                if (risk[j].at(x, y) < risk[best].at(x, y)) best = j;
            choice[best].at(x, y) = 1.f;
        }
    });
    for (Plane& c : choice) c = boxAverage(c, radius);
    std::vector<Plane> out(planes, Plane(w, h, 0));
    if (ownWeight) *ownWeight = Plane(w, h, 0);
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            float total = 0;
            for (size_t j = 0; j < candidates; ++j) total += choice[j].at(x, y);
            if (ownWeight) {
                float own = 0;
                for (size_t j = 0; j < candidates; ++j) own += choice[j].at(x, y) * inverse[j].at(x, y);
                ownWeight->at(x, y) = own / total;
            }
            for (size_t c = 0; c < planes; ++c) {
                float v = 0;
                for (size_t j = 0; j < candidates; ++j) v += choice[j].at(x, y) * filtered[j][c].at(x, y);
                out[c].at(x, y) = v / total;
            }
        }
    });
    return out;
}

void checkSize(size_t size, size_t pixels, const char* name, bool optional) {
    if (size == pixels || (optional && size == 0)) return;
    throw std::invalid_argument(str("denoise: ", name, " has ", size, " entries, expected ", pixels,
                                    optional ? " (or none)" : ""));
}

void checkOptions(const DenoiseOptions& o) {
    auto radius = [](int r, const char* name) {
        if (r < 0 || r > 32) throw std::invalid_argument(str("denoise: ", name, " ", r, " is outside [0, 32]"));
    };
    auto positive = [](float v, const char* name) {
        if (!(v > 0) || !finite(v)) throw std::invalid_argument(str("denoise: ", name, " ", v, " must be positive"));
    };
    if (o.threads < 0) throw std::invalid_argument(str("denoise: threads ", o.threads, " is negative"));
    radius(o.searchRadius, "searchRadius");
    radius(o.patchRadius, "patchRadius");
    radius(o.varianceRadius, "varianceRadius");
    radius(o.featureSearchRadius, "featureSearchRadius");
    radius(o.featurePatchRadius, "featurePatchRadius");
    positive(o.colorStrength, "colorStrength");
    if (o.candidates < 1 || o.candidates > 4)
        throw std::invalid_argument(str("denoise: candidates ", o.candidates, " is outside [1, 4]"));
    radius(o.selectionRadius, "selectionRadius");
    if (!(o.regressionRidge >= 0) || !finite(o.regressionRidge))
        throw std::invalid_argument(str("denoise: regressionRidge ", o.regressionRidge, " must be >= 0"));
    if (!(o.regressionNoiseRidge >= 0) || !finite(o.regressionNoiseRidge))
        throw std::invalid_argument(str("denoise: regressionNoiseRidge ", o.regressionNoiseRidge, " must be >= 0"));
    positive(o.featureStrength, "featureStrength");
    positive(o.featureThreshold, "featureThreshold");
    positive(o.featurePrefilterStrength, "featurePrefilterStrength");
    auto sigma = [](float v, const char* name) {
        if (!(v >= 0 && v <= 64)) throw std::invalid_argument(str("denoise: ", name, " ", v, " is outside [0, 64]"));
    };
    sigma(o.restoreSigma, "restoreSigma");
    sigma(o.fireflySigma, "fireflySigma");
}

}  // namespace

namespace {

// Throws std::invalid_argument on a bad size or option (denoise()'s contract).
void checkInput(const DenoiseInput& in, const DenoiseOptions& options) {
    if (in.width < 0 || in.height < 0)
        throw std::invalid_argument(str("denoise: invalid frame size ", in.width, "x", in.height));
    checkOptions(options);
    const size_t pixels = size_t(in.width) * size_t(in.height);
    checkSize(in.halfA.size(), pixels, "halfA", false);
    checkSize(in.halfB.size(), pixels, "halfB", false);
    auto pair = [&](size_t a, size_t b, const char* nameA, const char* nameB) {
        checkSize(a, pixels, nameA, true);
        checkSize(b, pixels, nameB, true);
        if ((a == 0) != (b == 0))
            throw std::invalid_argument(str("denoise: ", nameA, " and ", nameB, " must both be given or both be empty"));
    };
    pair(in.alphaA.size(), in.alphaB.size(), "alphaA", "alphaB");
    pair(in.emittedA.size(), in.emittedB.size(), "emittedA", "emittedB");
    checkSize(in.albedo.size(), pixels, "albedo", true);
    checkSize(in.normal.size(), pixels, "normal", true);
    checkSize(in.depth.size(), pixels, "depth", true);
}

// The whole algorithm on one image (its emitted part, if any, ignored);
// `in` already checked.
Image denoiseWhole(const DenoiseInput& in, const DenoiseOptions& options, std::vector<float>* variances) {
    const int w = in.width, h = in.height;
    const size_t pixels = size_t(w) * size_t(h);
    Image out(w, h);
    if (pixels == 0) return out;

    const bool hasAlpha = !in.alphaA.empty();
    const int pad = std::max({options.patchRadius, options.featurePatchRadius, 1});
    tbb::task_arena arena(resolveThreadCount(options.threads));
    arena.execute([&] {
        // Colour and alpha of both halves, and the variance of one half.
        const int channels = hasAlpha ? 4 : 3;
        const size_t planes = static_cast<size_t>(channels);
        // `clamped`: the colour's mean of the two halves after the firefly
        // clamp; `clampedLight`: what the clamp took (the mean of the two
        // halves' excess).
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

        // Features, normalised to about [0, 1]: albedo and normal as they are
        // (0 where nothing was met), depth relative to the median depth.
        std::vector<Feature> features;
        if (options.useFeatures) {
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
        }

        // Cross-filtering (Rousselle et al. 2012 and 2013): half A is
        // averaged with weights from half B's patches and vice versa, so the
        // weights' residual noise is independent of the values they average;
        // the output is the mean of the two. The final weight is
        // min(colour weight, feature weight) (Rousselle et al. 2013), one
        // exponential of the larger distance.
        const int f = options.patchRadius, radius = options.searchRadius;
        // The patch distance is the colour's alone; alpha is averaged with
        // the colour's weights. In a volume, alpha (1 - transmittance) has
        // strong structure and little noise (the marchers estimate it
        // smoothly), so a distance that held it rejected nearly every
        // neighbour: measured on cloud_sun at 16 s, the denoised RMSE was
        // 0.041 with alpha in the distance and 0.026 without.
        Guide halves;
        for (int c = 0; c < 3; ++c) {
            halves.values.push_back(&a[size_t(c)]);
            halves.secondValues.push_back(&b[size_t(c)]);
            halves.variances.push_back(&variance[size_t(c)]);
        }
        halves.norm = 1.f / float(3 * (2 * f + 1) * (2 * f + 1));

        // Candidate filters (Rousselle, Manzi and Zwicker 2013): the same
        // distances at colour strengths k_j = k_c 2^j. The colour distance
        // scales as 1/k^2, so a candidate's colour weight is the fourth power
        // of the next stronger one's: one exponential (of the strongest)
        // serves them all. `inverse[j]` gets 1/2 (1/sum wA + 1/sum wB), the
        // derivative of the output with respect to the pixel's own value
        // (its centre weight is 1), for SURE below.
        const size_t candidates = size_t(options.candidates);
        halves.k2 = options.colorStrength * options.colorStrength;
        const float strongestScale = std::ldexp(1.f, -2 * (options.candidates - 1));
        const bool withFeatures = !features.empty();
        // The alpha-regression candidate, when there is alpha, comes after
        // the weighted means and takes the weights of the strongest.
        const bool regression = options.alphaRegression && hasAlpha;
        const size_t regressionAt = candidates - 1;
        const size_t filters = candidates + (regression ? 1 : 0);
        std::vector<std::vector<Plane>> filtered(filters, std::vector<Plane>(planes, Plane(w, h, 0)));
        std::vector<Plane> inverse(filters, Plane(w, h, 0));
        forEachTile(w, h, [&](const Rect& tile) {
            const int tw = tile.width(), n = tw * tile.height();
            const size_t tilePixels = static_cast<size_t>(n), tileRow = static_cast<size_t>(tw);
            BoxScratch scratch(TileSize, f);
            std::vector<float> distanceA(tilePixels), distanceB(tilePixels), featureScratch(tileRow),
                weightA(tileRow), weightB(tileRow), colourA(tileRow), colourB(tileRow), featureWeight(tileRow);
            // Per candidate: sums of w * value per channel (A filtered with
            // B's weights, and B with A's), then the sums of the weights.
            const size_t sumSize = size_t(channels) * size_t(n);
            std::vector<float> sumA(candidates * sumSize, 0.f), sumB(candidates * sumSize, 0.f),
                weightsA(candidates * tilePixels, 0.f), weightsB(candidates * tilePixels, 0.f);
            std::vector<float> momentsA, momentsB, targetsA, targetsB, regressionScratch(tileRow);
            if (regression) {
                momentsA.assign(2 * tilePixels, 0.f);
                momentsB.assign(2 * tilePixels, 0.f);
                targetsA.assign(3 * tilePixels, 0.f);
                targetsB.assign(3 * tilePixels, 0.f);
            }
            for (int dy = -radius; dy <= radius; ++dy)
                for (int dx = -radius; dx <= radius; ++dx) {
                    const Rect r = partnersInside(tile, dx, dy, w, h);
                    if (r.empty()) continue;
                    patchDistances(halves, r, dx, dy, f, scratch, distanceA.data(), distanceB.data());
                    const int rw = r.width();
                    for (int y = r.y0; y < r.y1; ++y) {
                        const float* __restrict dB = &distanceB[size_t(y - r.y0) * size_t(rw)];
                        const float* __restrict dA = &distanceA[size_t(y - r.y0) * size_t(rw)];
                        const size_t base = size_t(y - tile.y0) * size_t(tw) + size_t(r.x0 - tile.x0);
                        // Colour weights of the strongest candidate and the
                        // feature weight, then per candidate from the strongest
                        // down: the colour weight squared twice; the weight is
                        // the smaller of colour and feature weight.
                        float* __restrict eA = colourA.data();
                        float* __restrict eB = colourB.data();
                        float* __restrict ef = featureWeight.data();
                        const float norm = halves.norm * strongestScale;
                        for (int x = 0; x < rw; ++x) {
                            eA[x] = clampDistance(dB[x] * norm);
                            eB[x] = clampDistance(dA[x] * norm);
                        }
                        for (int x = 0; x < rw; ++x) eA[x] = expMinus(eA[x]), eB[x] = expMinus(eB[x]);
                        if (withFeatures) {
                            featureRowDistance(features, y, dx, dy, r.x0, r.x1, ef, featureScratch.data());
                            for (int x = 0; x < rw; ++x) ef[x] = clampDistance(ef[x]);
                            for (int x = 0; x < rw; ++x) ef[x] = expMinus(ef[x]);
                        }
                        for (size_t j = candidates; j-- > 0;) {
                            if (j + 1 < candidates) {
                                toNextWeakerCandidate(eA, rw);
                                toNextWeakerCandidate(eB, rw);
                            }
                            const float* __restrict wA = eA;
                            const float* __restrict wB = eB;
                            if (withFeatures) {
                                for (int x = 0; x < rw; ++x) {
                                    weightA[size_t(x)] = eA[x] < ef[x] ? eA[x] : ef[x];
                                    weightB[size_t(x)] = eB[x] < ef[x] ? eB[x] : ef[x];
                                }
                                wA = weightA.data();
                                wB = weightB.data();
                            }
                            float* __restrict sa = &weightsA[j * tilePixels + base];
                            float* __restrict sb = &weightsB[j * tilePixels + base];
                            for (int x = 0; x < rw; ++x) sa[x] += wA[x], sb[x] += wB[x];
                            if (regression && j == regressionAt) {
                                // A is fitted on B's alpha and B on A's.
                                const float* qa[3];
                                const float* qb[3];
                                for (int c = 0; c < 3; ++c) {
                                    qa[c] = a[size_t(c)].row(y + dy) + r.x0 + dx;
                                    qb[c] = b[size_t(c)].row(y + dy) + r.x0 + dx;
                                }
                                accumulateAlphaRegression(wA, b[3].row(y) + r.x0, b[3].row(y + dy) + r.x0 + dx, qa,
                                                          rw, &momentsA[base], &targetsA[base], tilePixels,
                                                          regressionScratch.data());
                                accumulateAlphaRegression(wB, a[3].row(y) + r.x0, a[3].row(y + dy) + r.x0 + dx, qb,
                                                          rw, &momentsB[base], &targetsB[base], tilePixels,
                                                          regressionScratch.data());
                            }
                            for (int c = 0; c < channels; ++c) {
                                const float* __restrict qa = a[size_t(c)].row(y + dy) + r.x0 + dx;
                                const float* __restrict qb = b[size_t(c)].row(y + dy) + r.x0 + dx;
                                const size_t offset = j * sumSize + size_t(c) * size_t(n) + base;
                                float* __restrict accA = &sumA[offset];
                                float* __restrict accB = &sumB[offset];
                                for (int x = 0; x < rw; ++x) accA[x] += wA[x] * qa[x], accB[x] += wB[x] * qb[x];
                            }
                        }
                    }
                }

            // The centre weight is 1 (its distances are <= 0; to the rounding
            // of the running sums), so the sums of the weights are about >= 1.
            for (size_t j = 0; j < candidates; ++j)
                for (int y = tile.y0; y < tile.y1; ++y)
                    for (int x = tile.x0; x < tile.x1; ++x) {
                        const size_t i = size_t(y - tile.y0) * size_t(tw) + size_t(x - tile.x0);
                        const float sa = weightsA[j * tilePixels + i], sb = weightsB[j * tilePixels + i];
                        for (int c = 0; c < channels; ++c) {
                            const size_t k = j * sumSize + size_t(c) * size_t(n) + i;
                            float v = 0.5f * (sumA[k] / sa + sumB[k] / sb);
                            if (!finite(v)) v = 0.5f * (a[size_t(c)].at(x, y) + b[size_t(c)].at(x, y));
                            filtered[j][size_t(c)].at(x, y) = v;
                        }
                        inverse[j].at(x, y) = 0.5f * (1.f / std::max(sa, 1.f) + 1.f / std::max(sb, 1.f));
                    }
            // The regression's intercepts; where a solution is not finite,
            // the weighted mean of its weights. Alpha itself is the mean's.
            if (regression)
                for (int y = tile.y0; y < tile.y1; ++y)
                    for (int x = tile.x0; x < tile.x1; ++x) {
                        const size_t i = size_t(y - tile.y0) * size_t(tw) + size_t(x - tile.x0);
                        // The slope's ridge: a constant, and the expected
                        // square of the feature's own noise (a difference of
                        // two pixels' alpha), scaled.
                        const double ridge = double(options.regressionRidge) +
                                             double(options.regressionNoiseRidge) * 2.0 * double(variance[3].at(x, y));
                        auto solve = [&](const std::vector<float>& weights, const std::vector<float>& sums,
                                         const std::vector<float>& moments, const std::vector<float>& targets,
                                         float* value, float* hat) {
                            double t0[3], t1[3];
                            for (size_t c = 0; c < 3; ++c) {
                                t0[c] = sums[regressionAt * sumSize + c * size_t(n) + i];
                                t1[c] = targets[c * tilePixels + i];
                            }
                            return solveAlphaRegression(weights[regressionAt * tilePixels + i], moments[i],
                                                        moments[tilePixels + i], t0, t1, ridge, value, hat);
                        };
                        float va[3], vb[3], ha = 0, hb = 0;
                        const bool ok = solve(weightsA, sumA, momentsA, targetsA, va, &ha) &&
                                        solve(weightsB, sumB, momentsB, targetsB, vb, &hb);
                        for (int c = 0; c < channels; ++c)
                            filtered[candidates][size_t(c)].at(x, y) =
                                ok && c < 3 ? 0.5f * (va[c] + vb[c]) : filtered[regressionAt][size_t(c)].at(x, y);
                        inverse[candidates].at(x, y) = ok ? 0.5f * (ha + hb) : inverse[regressionAt].at(x, y);
                    }
        });
        // The variance estimate alone takes the selection's path, with one candidate too.
        Plane ownWeight;
        std::vector<Plane> selected =
            filters == 1 && !variances
                ? std::move(filtered[0])
                : selectCandidates(filtered, inverse, clamped, variance, options.selectionRadius,
                                   variances ? &ownWeight : nullptr);
        // The output's noise variance: the noisy mean's (half a half's, step
        // 2) times the pixel's own weight in its output, the variance of a
        // mean of equally noisy values with weights 0 and 1; plus that of the
        // restored local means, a Gaussian average of the noise (1 / (4 pi
        // sigma^2) of it), whose noise at scales beyond the Gaussian is the
        // noisy image's own. Both average the same noise over similar areas,
        // so the sum counts their overlap twice: on the synthetic frame of the
        // tests it is 1.4-1.6x the noise left away from edges, and in renders
        // it keeps adaptive sampling from starving smooth regions, whose
        // low-frequency noise the restored means keep (cloud_sun, 16 s: the
        // own weight alone raised the denoised low-frequency error by a
        // tenth; BENCHMARKS.md). The filter's bias is not in it. (The
        // blend's SURE was tried as this estimate: over an 8x8 block its
        // noise, and its bias from the weights' dependence on the values,
        // left it negative in flat regions.)
        if (variances) {
            const float restored = options.restoreSigma > 0
                                       ? 1.f / (4.f * 3.14159265f * options.restoreSigma * options.restoreSigma)
                                       : 0.f;
            variances->assign(pixels, 0.f);
            forEachRow(h, [&](int y) {
                for (int x = 0; x < w; ++x) {
                    float noise = 0;
                    for (size_t c = 0; c < 3; ++c) noise += 0.5f * variance[c].at(x, y);
                    (*variances)[size_t(y) * size_t(w) + size_t(x)] = noise * (ownWeight.at(x, y) + restored);
                }
            });
        }

        // The noisy image's local means, restored: NL-means averages each
        // pixel with similar ones wherever they are in the search window,
        // which moves light between bright and dim structure (on cloud_sun a
        // darkening of 0.4 % and errors at scales of 8 to 32 pixels twice the
        // noisy image's). The Gaussian average of (clamped - filtered) is
        // added back: only detail finer than the Gaussian is the filter's.
        // The light the firefly clamp took is added back too, spread by a
        // wide Gaussian (a faint haze; over 8 pixels the glass sample's
        // fireflies became blobs): the image keeps its energy.
        for (int c = 0; c < 3; ++c) {
            const size_t k = size_t(c);
            if (options.restoreSigma > 0) {
                Plane change(w, h, 0);
                forEachRow(h, [&](int y) {
                    for (int x = 0; x < w; ++x) change.at(x, y) = clamped[k].at(x, y) - selected[k].at(x, y);
                });
                const Plane restored = gaussian(change, options.restoreSigma, GaussianMode::Average);
                forEachRow(h, [&](int y) {
                    for (int x = 0; x < w; ++x) selected[k].at(x, y) += restored.at(x, y);
                });
            }
            if (options.suppressFireflies && options.fireflySigma > 0) {
                const Plane spread = gaussian(clampedLight[k], options.fireflySigma, GaussianMode::Spread);
                forEachRow(h, [&](int y) {
                    for (int x = 0; x < w; ++x) selected[k].at(x, y) += spread.at(x, y);
                });
            }
        }
        forEachRow(h, [&](int y) {
            for (int x = 0; x < w; ++x) {
                float value[4] = {0, 0, 0, 1};
                for (int c = 0; c < channels; ++c) value[c] = selected[size_t(c)].at(x, y);
                out.set(x, y, Color(value[0], value[1], value[2]), value[3]);
            }
        });
    });
    return out;
}

}  // namespace

Image denoise(const DenoiseInput& in, const DenoiseOptions& options, std::vector<float>* variances) {
    checkInput(in, options);
    const size_t pixels = size_t(in.width) * size_t(in.height);
    // Nothing emitted anywhere (or no emitted part): the whole image as one,
    // bit for bit what no emitted part gives.
    auto zero = [](const Color& c) { return c.x == 0 && c.y == 0 && c.z == 0; };
    if (std::all_of(in.emittedA.begin(), in.emittedA.end(), zero) &&
        std::all_of(in.emittedB.begin(), in.emittedB.end(), zero))
        return denoiseWhole(in, options, variances);
    // The scattered light (each half minus its emitted part) and the emitted
    // part, each denoised on its own with the same alpha and features; the
    // image is their sum, its alpha the scattered part's.
    DenoiseInput scattered = in, emitted = in;
    for (size_t p = 0; p < pixels; ++p) {
        scattered.halfA[p] = in.halfA[p] - in.emittedA[p];
        scattered.halfB[p] = in.halfB[p] - in.emittedB[p];
    }
    emitted.halfA = in.emittedA;
    emitted.halfB = in.emittedB;
    // The scattered part alone is a smooth glow, over which NL-means moves
    // light at scales the restoring Gaussian of step 9 leaves: restored at
    // half its sigma (the sample plume at 139 spp: low-frequency error 1.17x
    // the noisy image's with 4 pixels, 1.07x with 2, and 4 % less MSE).
    DenoiseOptions scatteredOptions = options;
    scatteredOptions.restoreSigma = 0.5f * options.restoreSigma;
    Image out = denoiseWhole(scattered, scatteredOptions, variances);
    // The emitted part is filtered only where its noise counts: the
    // marchers integrate emission along the camera ray nearly noise-free
    // (the sample plume: 2 % of the image's half-difference variance), and
    // NL-means leaves such a part as it is (measured: the same MSE to four
    // digits) at the cost of a second denoise (0.9 s at 480x640). Then its
    // halves' mean is added as it is. Non-finite values always go through
    // the filter, which cleans them.
    double emittedNoise = 0, imageNoise = 0;
    for (size_t p = 0; p < pixels; ++p) {
        emittedNoise += double(lengthSquared(in.emittedA[p] - in.emittedB[p]));
        imageNoise += double(lengthSquared(in.halfA[p] - in.halfB[p]));
    }
    if (std::isfinite(emittedNoise) && std::isfinite(imageNoise) && emittedNoise <= EmittedNoiseShare * imageNoise) {
        for (size_t p = 0; p < pixels; ++p) {
            const Color e = 0.5f * (in.emittedA[p] + in.emittedB[p]);
            for (int c = 0; c < 3; ++c) out.rgba[4 * p + size_t(c)] += e[c];
            // The emitted mean's own variance, (A - B)^2 / 4 per channel.
            if (variances) (*variances)[p] += 0.25f * lengthSquared(in.emittedA[p] - in.emittedB[p]);
        }
        return out;
    }
    std::vector<float> emittedVariances;
    const Image e = denoiseWhole(emitted, options, variances ? &emittedVariances : nullptr);
    for (size_t p = 0; p < out.pixelCount(); ++p) {
        for (int c = 0; c < 3; ++c) out.rgba[4 * p + size_t(c)] += e.rgba[4 * p + size_t(c)];
        if (variances) (*variances)[p] += emittedVariances[p];
    }
    return out;
}

}  // namespace vdbmarch
