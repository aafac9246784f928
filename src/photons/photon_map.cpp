#include "photons/photon_map.h"

#include <algorithm>

#include <nanoflann.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace vdbmarch {

namespace {

// Interleaves the low 21 bits of x, y and z.
uint64_t spreadBits(uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

}  // namespace

struct PhotonMap::Tree {
    // A contiguous range of the map's photons.
    struct PhotonCloud {
        const Photon* photons;
        size_t count;
        size_t kdtree_get_point_count() const { return count; }
        float kdtree_get_pt(size_t i, size_t dim) const { return photons[i].position[int(dim)]; }
        template <class Box>
        bool kdtree_get_bbox(Box&) const { return false; }
    };

    using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PhotonCloud>, PhotonCloud, 3,
                                                       uint32_t>;

    PhotonCloud cloud;
    uint32_t first;  // index of cloud.photons[0] in the map
    KdTree index;
    Tree(const std::vector<Photon>& p, size_t begin, size_t end)
        : cloud{p.data() + begin, end - begin},
          first(uint32_t(begin)),
          index(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
};

PhotonMap::PhotonMap(std::vector<Photon> photons, Search search) : mSearch(search) {
    // Sort along a Morton curve (by region first, for Search::ByRegion):
    // queries then touch few cache lines. Keys are unique (the index breaks
    // ties), so the order is deterministic.
    BBox b;
    for (const Photon& p : photons) b.expand(p.position);
    using Key = std::pair<std::pair<int, uint64_t>, uint32_t>;
    std::vector<Key> keys(photons.size());
    const bool byRegion = search == Search::ByRegion;
    Vec3 extent = b.hi - b.lo;
    float scale = float((1 << 21) - 1) / std::max(maxComponent(extent), 1e-30f);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, photons.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            Vec3 q = (photons[i].position - b.lo) * scale;
            uint64_t code = spreadBits(uint64_t(q.x)) | spreadBits(uint64_t(q.y)) << 1 | spreadBits(uint64_t(q.z)) << 2;
            keys[i] = {{byRegion ? photons[i].region() : 0, code}, uint32_t(i)};
        }
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    mPhotons.resize(photons.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, keys.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) mPhotons[i] = photons[keys[i].second];
    });
    if (!byRegion) {
        mTrees.push_back(std::make_unique<Tree>(mPhotons, 0, mPhotons.size()));
        return;
    }
    for (size_t begin = 0; begin < mPhotons.size();) {
        const int r = mPhotons[begin].region();
        size_t end = begin;
        while (end < mPhotons.size() && mPhotons[end].region() == r) ++end;
        if (mTrees.size() <= size_t(r)) mTrees.resize(size_t(r) + 1);
        mTrees[size_t(r)] = std::make_unique<Tree>(mPhotons, begin, end);
        begin = end;
    }
}

PhotonMap::~PhotonMap() = default;

size_t PhotonMap::nearest(const Vec3& x, size_t k, uint32_t* indices, float* dist2, int region) const {
    if (mPhotons.empty() || k == 0) return 0;
    const size_t t = mSearch == Search::ByRegion ? size_t(Photon::storedRegion(region)) : 0;
    if (t >= mTrees.size() || !mTrees[t]) return 0;
    const Tree& tree = *mTrees[t];
    const float q[3] = {x.x, x.y, x.z};
    const size_t n = size_t(tree.index.knnSearch(q, k, indices, dist2));
    for (size_t i = 0; i < n; ++i) indices[i] += tree.first;
    return n;
}

size_t PhotonMap::memoryBytes() const {
    // Photons, plus nanoflann's index permutation and about one node per
    // 8 photons (leaves of at most 16).
    return mPhotons.size() * (sizeof(Photon) + sizeof(uint32_t)) + mPhotons.size() / 8 * 64 +
           mTrees.size() * sizeof(Tree);
}

}  // namespace vdbmarch
