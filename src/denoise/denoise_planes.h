// The denoiser's working image: float planes with replicated borders, the
// row and tile loops its steps run in parallel, and the box and Gaussian
// averages several steps share. Internal to src/denoise.
#pragma once

#include "core/math.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

namespace vdbmarch::denoising {

// Output tiles of the NL-means passes. Fixed (not derived from the thread
// count) so that the running sums start at the same pixels and the result is
// bit-identical for any number of threads.
constexpr int TileSize = 64;

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

// The rectangle [x0, x1) x [y0, y1) of a tile whose partners (x + dx, y + dy)
// lie inside the image: the search window is clamped to the image.
struct Rect {
    int x0, y0, x1, y1;
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    bool empty() const { return x1 <= x0 || y1 <= y0; }
};

inline Rect partnersInside(const Rect& tile, int dx, int dy, int width, int height) {
    return {std::max(tile.x0, -dx), std::max(tile.y0, -dy), std::min(tile.x1, width - dx),
            std::min(tile.y1, height - dy)};
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

inline bool finite(float v) { return std::isfinite(v); }
inline float clampMagnitude(float v, float limit) { return v < -limit ? -limit : (v > limit ? limit : v); }

// Channel c of a vector of colours.
std::vector<float> channelOf(const std::vector<Color>& v, int c);

// A box of `radius` around each pixel, averaged over the pixels inside the
// image (separable, direct sums: cheap next to the NL-means passes).
Plane boxAverage(const Plane& in, int radius);

// A separable Gaussian of standard deviation `sigma` pixels, cut at 3 sigma.
// Per axis, W(i) is the kernel's weight inside the image around pixel i (the
// same for a pixel gathering and a pixel giving, the kernel being
// symmetric). Average: each pixel becomes its neighbours' weighted sum
// divided by its own W (a constant stays that constant). Spread:
// each pixel gives its value to its neighbours, divided by its W first (the
// sum over the image stays that sum).
enum class GaussianMode { Average, Spread };
Plane gaussian(const Plane& in, float sigma, GaussianMode mode);

}  // namespace vdbmarch::denoising
