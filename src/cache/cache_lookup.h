// Cached L_i along one ray, per thread: Y_lm of the ray's direction is
// evaluated once per ray (section 3.2), and the last cell found is reused
// while the points stay inside it, so walking a ray through the cache costs
// one tree lookup per cell crossed (the histogram of section 3.3).
#pragma once

#include <cmath>

#include "cache/radiance_cache.h"
#include "cache/sh.h"

namespace vdbmarch {

class CacheLookup {
public:
    explicit CacheLookup(const RadianceCache& cache) : mCache(cache), mQuery(cache) {}

    // wo: the direction the light leaves in, towards the viewer (-ray.d).
    void setDirection(const Vec3& wo) {
        if (mHaveDirection && wo.x == mWo.x && wo.y == mWo.y && wo.z == mWo.z) return;
        evalSh(mCache.info.shOrder, wo, mY);
        mWo = wo;
        mHaveDirection = true;
        mCell = -1;  // cell values depend on the direction
    }

    // max(0, cached L_i(x, wo)) (eq. 14, clamped); 0 outside every cell.
    // The last cell is reused when x maps to it by the same arithmetic as
    // RadianceCache::Query::find, so the value never depends on which points
    // were looked up before (leaves do not overlap, so that cell is x's).
    float at(const Vec3& x) {
        if (mCell >= 0) {
            const Vec3 q = (x - mCache.origin) / mCache.baseCell;
            const float s = float(1 << mLevel);
            if (std::floor(q.x * s) == mI && std::floor(q.y * s) == mJ && std::floor(q.z * s) == mK) return mValue;
        }
        int64_t c = mQuery.find(x);
        mCell = c;
        if (c < 0) return 0.f;
        const CacheCell& cell = mCache.cells[size_t(c)];
        mLevel = cell.level;
        mI = float(cell.i);
        mJ = float(cell.j);
        mK = float(cell.k);
        mValue = evalShNonNegative(mCache.coefficientCount(), mCache.cellCoefficients(size_t(c)), mY);
        return mValue;
    }

private:
    const RadianceCache& mCache;
    RadianceCache::Query mQuery;
    float mY[shCount(MaxShOrder)];
    Vec3 mWo;
    bool mHaveDirection = false;
    int64_t mCell = -1;
    int mLevel = 0;
    float mI = 0, mJ = 0, mK = 0;  // the cell's coordinates (exact in float below 2^24)
    float mValue = 0;
};

}  // namespace vdbmarch
