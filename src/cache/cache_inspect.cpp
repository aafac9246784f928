#include "cache/cache_inspect.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "cache/sh.h"
#include "core/error.h"
#include "image/metrics.h"
#include "image/png_io.h"

namespace vdbmarch {

std::string cacheSummary(const RadianceCache& c) {
    std::ostringstream o;
    const CacheInfo& i = c.info;
    o << "vdbmarch radiance cache (format " << RadianceCache::FormatVersion << ", written by vdbmarch " << i.version
      << ")\n";
    o << "sh order " << i.shOrder << " (" << c.coefficientCount() << " coefficients per cell";
    if (i.shOrder != i.requestedOrder) o << "; " << i.requestedOrder << " requested, every medium is isotropic";
    o << "), mean phase g " << i.meanG << "\n";
    o << "photons " << i.photons << " from " << i.paths << " paths, k " << i.k << ", quality " << i.quality
      << ", seed " << i.seed << ", scene hash " << i.sceneHash << "\n";
    o << (i.adaptive ? "adaptive" : "uniform") << ", " << c.levels << " level(s), origin [" << c.origin.x << " "
      << c.origin.y << " " << c.origin.z << "]\n";
    for (int l = 0; l < c.levels; ++l)
        o << "  level " << l << ": cell " << c.cellSize(l) << ", " << c.cellsAtLevel(l) << " cells\n";
    o << "cells " << c.cells.size() << ", memory " << c.memoryBytes() << " bytes ("
      << (c.cells.empty() ? 0.0 : double(c.memoryBytes()) / double(c.cells.size())) << " per cell)\n";
    const int n = c.coefficientCount();
    for (int k = 0; k < n; ++k) {
        float lo = Infinity, hi = -Infinity;
        for (size_t cell = 0; cell < c.cells.size(); ++cell) {
            float v = c.cellCoefficients(cell)[k];
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
        int l = shBand(k);
        o << "  f(l=" << l << ", m=" << k - l * (l + 1) << ") [" << (c.cells.empty() ? 0.f : lo) << ", "
          << (c.cells.empty() ? 0.f : hi) << "]\n";
    }
    return o.str();
}

float writeCacheSlice(const RadianceCache& c, int axis, float value, const Vec3& wo, const std::string& path) {
    if (c.cells.empty()) throw InputError(str(path, ": the cache has no cells to slice"));
    BBox bounds;
    for (const CacheCell& cell : c.cells) {
        float h = c.cellSize(cell.level);
        Vec3 lo = c.origin + Vec3(float(cell.i), float(cell.j), float(cell.k)) * h;
        bounds.expand(lo);
        bounds.expand(lo + Vec3(h));
    }
    if (!(value >= bounds.lo[axis] && value <= bounds.hi[axis]))
        throw InputError(str("--slice ", "xyz"[axis], "=", value, ": outside the cache, which spans [",
                             bounds.lo[axis], ", ", bounds.hi[axis], "] on that axis"));
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    float extentU = bounds.hi[u] - bounds.lo[u], extentV = bounds.hi[v] - bounds.lo[v];
    float pixel = std::max(extentU, extentV) / 512;  // cells show as blocks
    int width = std::max(1, int(std::ceil(extentU / pixel))), height = std::max(1, int(std::ceil(extentV / pixel)));
    const bool directional = lengthSquared(wo) > 0;
    std::vector<float> Y(size_t(shCount(c.info.shOrder)), 0.f);
    if (directional) evalSh(c.info.shOrder, normalize(wo), Y.data());
    else Y[0] = 0.28209479f;  // Y_00: the mean over directions
    std::vector<float> L(size_t(width) * size_t(height), -1.f);
    RadianceCache::Query q(c);
    float maxL = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            Vec3 p;
            p[axis] = value;
            p[u] = bounds.lo[u] + (float(x) + 0.5f) * pixel;
            p[v] = bounds.hi[v] - (float(y) + 0.5f) * pixel;  // top row = largest v
            int64_t cell = q.find(p);
            if (cell < 0) continue;
            float l = evalShNonNegative(c.coefficientCount(), c.cellCoefficients(size_t(cell)), Y.data());
            L[size_t(y) * size_t(width) + size_t(x)] = l;
            maxL = std::max(maxL, l);
        }
    std::vector<uint8_t> rgb(size_t(width) * size_t(height) * 3, 0);
    for (size_t i = 0; i < L.size(); ++i) {
        if (L[i] < 0) continue;  // no cell: black
        double t = maxL > 0 && L[i] > 0 ? 1 + std::log10(double(L[i]) / maxL) / 4 : 0;
        viridisColor(t, &rgb[i * 3]);
    }
    writePngRgb8(path, width, height, rgb);
    return maxL;
}

}  // namespace vdbmarch
