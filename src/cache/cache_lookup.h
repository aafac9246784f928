// Cached L_i along one ray, per thread: Y_lm of the ray's direction is
// evaluated once per ray (section 3.2), and the last cell found is reused
// while the points stay inside it, so walking a ray through the cache costs
// one tree lookup per cell crossed (the histogram of section 3.3).
#pragma once

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
    float at(const Vec3& x) {
        if (mCell >= 0 && x.x >= mLo.x && x.x < mHi.x && x.y >= mLo.y && x.y < mHi.y && x.z >= mLo.z && x.z < mHi.z)
            return mValue;
        int64_t c = mQuery.find(x);
        mCell = c;
        if (c < 0) return 0.f;
        const CacheCell& cell = mCache.cells[size_t(c)];
        const float h = mCache.cellSize(cell.level);
        mLo = mCache.origin + Vec3(float(cell.i) * h, float(cell.j) * h, float(cell.k) * h);
        mHi = mLo + Vec3(h, h, h);
        mValue = evalShNonNegative(mCache.coefficientCount(), mCache.cellCoefficients(size_t(c)), mY);
        ++mCellsVisited;
        return mValue;
    }

    size_t cellsVisited() const { return mCellsVisited; }

private:
    const RadianceCache& mCache;
    RadianceCache::Query mQuery;
    float mY[shCount(MaxShOrder)];
    Vec3 mWo;
    bool mHaveDirection = false;
    int64_t mCell = -1;
    Vec3 mLo, mHi;
    float mValue = 0;
    size_t mCellsVisited = 0;
};

}  // namespace vdbmarch
