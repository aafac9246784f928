#include "cache/cache_build.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <tbb/enumerable_thread_specific.h>

#include "cache/sh.h"
#include "photons/photon_tracer.h"
#include "transport/media_point.h"
#include "transport/phase.h"
#include "transport/surface_event.h"

namespace vdbmarch {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Cell coordinates relative to the cache origin, 21 bits per axis.
constexpr int KeyBits = 21;
constexpr int64_t MaxCoord = (int64_t(1) << KeyBits) - 1;

uint64_t packKey(int64_t i, int64_t j, int64_t k) {
    return uint64_t(i) | uint64_t(j) << KeyBits | uint64_t(k) << (2 * KeyBits);
}
void unpackKey(uint64_t key, int32_t& i, int32_t& j, int32_t& k) {
    i = int32_t(key & uint64_t(MaxCoord));
    j = int32_t((key >> KeyBits) & uint64_t(MaxCoord));
    k = int32_t((key >> (2 * KeyBits)) & uint64_t(MaxCoord));
}

// Boxes covering the scattering media (unbounded fog: the photon target).
std::vector<BBox> scatteringBoxes(const Scene& scene) {
    std::vector<BBox> boxes;
    bool unbounded = false;
    for (const auto& m : scene.media) {
        if (m->isVacuum() || isBlack(m->sigma_s)) continue;
        if (!m->worldBounds().isFinite()) {
            unbounded = true;
            continue;
        }
        m->activeBoxes(boxes);
    }
    if (unbounded) {
        boxes.clear();
        boxes.push_back(photonTarget(scene).bounds);
    }
    return boxes;
}

// Sorted unique keys of the cells of size h (from origin) that overlap any box.
std::vector<uint64_t> rasterize(const std::vector<BBox>& boxes, const Vec3& origin, float h) {
    std::vector<uint64_t> keys;
    for (const BBox& b : boxes) {
        int64_t lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::max<int64_t>(0, int64_t(std::floor((b.lo[a] - origin[a]) / h)));
            hi[a] = std::min<int64_t>(MaxCoord, int64_t(std::floor((b.hi[a] - origin[a]) / h)));
        }
        for (int64_t i = lo[0]; i <= hi[0]; ++i)
            for (int64_t j = lo[1]; j <= hi[1]; ++j)
                for (int64_t k = lo[2]; k <= hi[2]; ++k) keys.push_back(packKey(i, j, k));
    }
    tbb::parallel_sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return keys;
}

// Number of cells of size h that rasterize() would produce, without
// building them when there are too many (the caller grows h then).
double cellCountEstimate(const std::vector<BBox>& boxes, const Vec3& origin, float h) {
    double n = 0;
    for (const BBox& b : boxes) {
        double c = 1;
        for (int a = 0; a < 3; ++a)
            c *= std::floor((b.hi[a] - origin[a]) / h) - std::floor((b.lo[a] - origin[a]) / h) + 1;
        n += c;
    }
    return n;
}

// Photon counts per cell at one level: sorted (key, count).
struct LevelCounts {
    std::vector<uint64_t> keys;
    std::vector<uint32_t> counts;
    uint32_t count(uint64_t key) const {
        auto it = std::lower_bound(keys.begin(), keys.end(), key);
        return it != keys.end() && *it == key ? counts[size_t(it - keys.begin())] : 0u;
    }
};

LevelCounts countPhotons(const PhotonMap& map, const Vec3& origin, float h) {
    std::vector<uint64_t> keys;
    keys.reserve(map.size());
    for (const Photon& p : map.photons()) {
        Vec3 q = (p.position - origin) / h;
        if (!(q.x >= 0 && q.y >= 0 && q.z >= 0 && q.x <= float(MaxCoord) && q.y <= float(MaxCoord) &&
              q.z <= float(MaxCoord)))
            continue;
        keys.push_back(packKey(int64_t(q.x), int64_t(q.y), int64_t(q.z)));
    }
    tbb::parallel_sort(keys.begin(), keys.end());
    LevelCounts lc;
    for (size_t i = 0; i < keys.size();) {
        size_t j = i;
        while (j < keys.size() && keys[j] == keys[i]) ++j;
        lc.keys.push_back(keys[i]);
        lc.counts.push_back(uint32_t(j - i));
        i = j;
    }
    return lc;
}

}  // namespace

namespace {
// Eq. 27 at every cell of `cache` (its topology) from `map`.
std::vector<float> estimateCoefficients(const Scene& scene, const PhotonMap& map, const RadianceCache& cache,
                                        int kNearest) {
    // Eq. 27 at every cell centre from its k nearest photons, with the
    // Legendre weights of the phase mixture at the centre (eq. 26: sum_i
    // w_i g_i^l where media overlap), as eq. 4 takes the phase at the point
    // it estimates. A centre where nothing scatters (a cell across a
    // medium's edge) takes each photon's own mean g^l.
    const int order = cache.info.shOrder, count = cache.coefficientCount();
    const size_t kk = size_t(std::min(kNearest, 1024));
    std::vector<float> coefficients(cache.cells.size() * size_t(count), 0.f);
    tbb::enumerable_thread_specific<ThreadContext> contexts([&] { return ThreadContext(scene); });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cache.cells.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
        ThreadContext& ctx = contexts.local();
        std::vector<uint32_t> idx(kk);
        std::vector<float> d2(kk);
        float Y[shCount(MaxShOrder)], w[MaxShOrder + 1];
        MediumPoint mp;
        for (size_t c = r.begin(); c < r.end(); ++c) {
            const Vec3 x = cache.cellCenter(cache.cells[c]);
            size_t n = map.nearest(x, kk, idx.data(), d2.data());
            if (n == 0 || !(d2[n - 1] > 0)) continue;
            float* f = &coefficients[c * size_t(count)];
            bool centreScatters = false;
            if (order > 0) {
                evalMedia(ctx, regionAtRayStart(scene, Ray{x, Vec3(0, 0, 1)}), x, mp);
                centreScatters = mp.scatters();
                if (centreScatters) mp.phase.legendreWeights(order, w);
            }
            for (size_t i = 0; i + 1 < n; ++i) {  // the farthest only sets the radius
                const Photon& p = map[idx[i]];
                float weight = average(p.weight);
                if (order == 0) {
                    f[0] += weight;
                    continue;
                }
                evalSh(order, p.travelDirection(), Y);
                if (!centreScatters) hgLegendreWeights(order, p.g(), w);
                for (int l = 0; l <= order; ++l)
                    for (int m = -l; m <= l; ++m) f[shIndex(l, m)] += weight * w[l] * Y[shIndex(l, m)];
            }
            float r2 = d2[n - 1];
            float invVolume = 1 / (4.f / 3.f * Pi * r2 * std::sqrt(r2));
            // Order 0: Y_00 = 1 / sqrt(4 pi) and w'_0 = 1.
            if (order == 0) f[0] *= 0.28209479f;
            for (int i = 0; i < count; ++i) f[i] *= invVolume;
        }
    });
    return coefficients;
}
}  // namespace

int effectiveShOrder(const Scene& scene, int requested) {
    for (const auto& m : scene.media)
        if (!m->isVacuum() && !isBlack(m->sigma_s) && m->g != 0) return requested;
    return 0;
}

RadianceCache buildRadianceCache(const Scene& scene, const PhotonMap& map, size_t paths,
                                 const CacheSettings& settings, int kNearest, CacheBuildStats* stats) {
    auto start = Clock::now();
    RadianceCache cache;
    cache.info.requestedOrder = settings.shOrder;
    cache.info.shOrder = effectiveShOrder(scene, settings.shOrder);
    cache.info.quality = settings.quality;
    cache.info.k = kNearest;
    cache.info.adaptive = settings.adaptive;
    cache.info.photons = map.size();
    cache.info.paths = paths;
    cache.info.sceneHash = sceneHash(scene.desc);
    cache.info.version = VDBMARCH_VERSION;
    float gSum = 0, wSum = 0;
    for (const auto& m : scene.media)
        if (!m->isVacuum() && !isBlack(m->sigma_s)) {
            gSum += m->g * average(m->sigma_s);
            wSum += average(m->sigma_s);
        }
    cache.info.meanG = wSum > 0 ? gSum / wSum : 0.f;

    std::vector<BBox> boxes = scatteringBoxes(scene);
    BBox domain;
    for (const BBox& b : boxes) domain.expand(b);
    if (boxes.empty() || domain.empty() || map.size() == 0) {
        cache.finalize();
        return cache;
    }
    cache.origin = domain.lo;
    const Vec3 extent = domain.hi - domain.lo;
    const double N = double(map.size()), k = double(std::max(1, kNearest)), a = double(settings.quality);
    // The paper's rule on the bounding box, then on the volume of the cells
    // that hold media (sparse media fill a small part of their box).
    const float maxExtent = std::max(maxComponent(extent), 1e-6f);
    auto clampCell = [&](double h) {
        // At most 2^20 cells per axis and about 64M cells.
        h = std::max(h, double(maxExtent) / double(1 << 20));
        while (cellCountEstimate(boxes, cache.origin, float(h)) > 64e6) h *= 1.25;
        return float(h);
    };
    double boxVolume = std::max(double(extent.x) * extent.y * extent.z, 1e-30);
    float h = clampCell(std::cbrt(k * boxVolume / (a * N)));
    for (int iter = 0; iter < 3; ++iter) {
        double active = double(rasterize(boxes, cache.origin, h).size()) * double(h) * h * h;
        h = clampCell(std::cbrt(k * std::min(active, boxVolume) / (a * N)));
    }

    if (!settings.adaptive) {
        cache.levels = 1;
        cache.baseCell = h;
        for (uint64_t key : rasterize(boxes, cache.origin, h)) {
            CacheCell c{0, 0, 0, 0};
            unpackKey(key, c.i, c.j, c.k);
            cache.cells.push_back(c);
        }
    } else {
        // Octree-like: start two levels coarser than the uniform grid and
        // split any cell holding more photons than a uniform cell holds on
        // average (k / a), down to min_cell (default: a quarter of the
        // uniform cell).
        float top = 4 * h;
        float minCell = settings.minCell > 0 ? settings.minCell : h / 4;
        int levels = 1;
        while (levels < 12 && top / float(1 << levels) >= minCell * 0.999f &&
               maxExtent / (top / float(1 << levels)) < float(1 << 20))
            ++levels;
        cache.levels = levels;
        cache.baseCell = top;
        cache.info.minCell = top / float(1 << (levels - 1));
        std::vector<LevelCounts> counts;
        for (int l = 0; l < levels; ++l) counts.push_back(countPhotons(map, cache.origin, cache.cellSize(l)));
        const double threshold = k / a;
        std::vector<CacheCell> stack;
        for (uint64_t key : rasterize(boxes, cache.origin, top)) {
            CacheCell c{0, 0, 0, 0};
            unpackKey(key, c.i, c.j, c.k);
            stack.push_back(c);
            while (!stack.empty()) {
                CacheCell cell = stack.back();
                stack.pop_back();
                bool split = cell.level + 1 < levels &&
                             double(counts[size_t(cell.level)].count(packKey(cell.i, cell.j, cell.k))) > threshold;
                if (!split) {
                    cache.cells.push_back(cell);
                    continue;
                }
                for (int child = 7; child >= 0; --child)
                    stack.push_back({cell.level + 1, 2 * cell.i + (child & 1), 2 * cell.j + ((child >> 1) & 1),
                                     2 * cell.k + ((child >> 2) & 1)});
            }
        }
    }
    double topologySeconds = secondsSince(start);

    auto estimateStart = Clock::now();
    cache.coefficients = estimateCoefficients(scene, map, cache, kNearest);
    cache.finalize();
    cache.info.buildSeconds = secondsSince(start);
    if (stats) {
        stats->topologySeconds = topologySeconds;
        stats->estimateSeconds = secondsSince(estimateStart);
        stats->cells = cache.cells.size();
    }
    return cache;
}

void refineRadianceCache(const Scene& scene, const PhotonMap& photons, size_t paths, int k, RadianceCache& cache) {
    if (cache.cells.empty() || photons.size() == 0) return;
    const std::vector<float> fresh = estimateCoefficients(scene, photons, cache, k);
    // The running mean over equally weighted, independent batches.
    const double n = double(std::max<uint32_t>(1, cache.info.batches));
    const float keep = float(n / (n + 1)), add = float(1 / (n + 1));
    for (size_t i = 0; i < fresh.size(); ++i) cache.coefficients[i] = keep * cache.coefficients[i] + add * fresh[i];
    cache.info.batches = uint32_t(n) + 1;
    cache.info.photons += photons.size();
    cache.info.paths += paths;
}

}  // namespace vdbmarch
