#include "denoise/denoise_nlmeans.h"

namespace vdbmarch::denoising {

namespace {

// Keeps the distance finite where both variances are 0 (noise-free input):
// there only (nearly) identical values are averaged.
constexpr float DistanceEpsilon = 1e-10f;
// A pixel distance this large already makes the weight of any patch that
// holds it negligible (1e4 / 49 > 87 for a 7x7 patch of one channel); the
// clamp keeps the running sums of the box filter precise.
constexpr float DistanceClamp = 1e4f;

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

}  // namespace

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

}  // namespace vdbmarch::denoising
