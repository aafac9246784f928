// The in-scattered radiance cache (sections 3.1, 3.2 and 3.4): cells of a
// sparse, octree-like hierarchy of world-aligned grids, each holding the
// spherical-harmonics coefficients f_lm of L_i at its centre (eq. 27). Level
// 0 is the coarsest; level j has cells of size baseCell / 2^j; only the
// leaves of the hierarchy are stored, so every point has at most one cell
// per level and the finest one present is its cell. A uniform cache is a
// single level. The index of each level is a sparse OpenVDB tree (hidden
// here, so that only radiance_cache.cpp includes OpenVDB).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cache/sh.h"
#include "core/math.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

// What a cache was made from, recorded in the .vdb metadata.
struct CacheInfo {
    int shOrder = 0;         // stored order (0 when every medium is isotropic)
    int requestedOrder = 3;  // the order asked for
    float quality = 1;
    int k = 50;
    bool adaptive = false;
    float minCell = 0;
    uint64_t photons = 0, paths = 0, seed = 0;
    uint32_t batches = 1;    // independent photon batches averaged (refineRadianceCache)
    float meanG = 0;         // sigma_s-weighted mean g of the scattering media
    std::string sceneHash;
    std::string version;
    double buildSeconds = 0;
};

struct CacheCell {
    int level;
    int32_t i, j, k;  // cell coordinates at its level
};

class RadianceCache {
public:
    // 2: grids Li_sh_<l>_<m> (1: Li_sh<c>), a mean-radiance grid Li, and
    // file metadata spelling out the SH basis.
    static constexpr int FormatVersion = 2;

    RadianceCache();
    ~RadianceCache();
    RadianceCache(RadianceCache&&) noexcept;
    RadianceCache& operator=(RadianceCache&&) noexcept;

    // Builds the per-level indices after cells and coefficients are set.
    void finalize();

    CacheInfo info;
    Vec3 origin;            // world position of cell (0,0,0)'s low corner at every level
    float baseCell = 1;     // cell size at level 0
    int levels = 1;
    std::vector<CacheCell> cells;
    std::vector<float> coefficients;  // coefficientCount() per cell
    int coefficientCount() const { return (info.shOrder + 1) * (info.shOrder + 1); }
    float cellSize(int level) const { return baseCell / float(1 << level); }
    Vec3 cellCenter(const CacheCell& c) const {
        float h = cellSize(c.level);
        return origin + Vec3((float(c.i) + 0.5f) * h, (float(c.j) + 0.5f) * h, (float(c.k) + 0.5f) * h);
    }
    const float* cellCoefficients(size_t cell) const { return &coefficients[cell * size_t(coefficientCount())]; }
    size_t cellsAtLevel(int level) const;
    size_t memoryBytes() const;

    // Per-thread lookups (VDB accessors are not thread-safe).
    class Query {
    public:
        explicit Query(const RadianceCache& c);
        ~Query();
        // Index of the finest cell holding x, or -1 outside the cache.
        int64_t find(const Vec3& x);

    private:
        struct Accessors;
        const RadianceCache& mCache;
        std::unique_ptr<Accessors> mAcc;
    };

    // Writes the cache as VDB float grids (one per coefficient and level,
    // grid class fog volume, plus the mean radiance Li per level) with file and grid
    // metadata (docs/scene-format.md, "The cache file"); atomically.
    void save(const std::string& path) const;
    // Reads a cache written by save(); throws InputError naming the file
    // (and the grid) for missing, truncated or inconsistent files, and for a
    // cache of another format version (naming both versions).
    static RadianceCache load(const std::string& path);

    // Writes L_i(wo) of every cell as one float grid per level (for viewing).
    void saveDirectional(const std::string& path, const Vec3& wo) const;

    struct Index;

private:
    std::unique_ptr<Index> mIndex;
};

// Grid name of coefficient `c` = shIndex(l, m) at `level`: "Li_sh_<l>_<m>"
// for a single-level cache, "Li_sh_<l>_<m>_level<level>" otherwise. A
// negative m is spelt "m<|m|>" (Li_sh_1_m1), so that every name is an
// identifier: Houdini binds volumes as @name in VEX, where '-' cannot appear
// (documented in docs/scene-format.md).
std::string cacheGridName(int coefficient, int level, int levels);
// The grid of mean radiance over directions, f_00 Y_00: "Li" or "Li_level<level>".
std::string cacheMeanGridName(int level, int levels);
}  // namespace vdbmarch
