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

struct PhotonCloud {
    const std::vector<Photon>* photons;
    size_t kdtree_get_point_count() const { return photons->size(); }
    float kdtree_get_pt(size_t i, size_t dim) const { return (*photons)[i].position[int(dim)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const { return false; }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PhotonCloud>, PhotonCloud, 3,
                                                   uint32_t>;

}  // namespace

struct PhotonMap::Tree {
    PhotonCloud cloud;
    KdTree index;
    explicit Tree(const std::vector<Photon>& p)
        : cloud{&p}, index(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
};

PhotonMap::PhotonMap(std::vector<Photon> photons) {
    // Sort along a Morton curve: queries then touch few cache lines. Keys
    // are unique (the index breaks ties), so the order is deterministic.
    BBox b;
    for (const Photon& p : photons) b.expand(p.position);
    std::vector<std::pair<uint64_t, uint32_t>> keys(photons.size());
    Vec3 extent = b.hi - b.lo;
    float scale = float((1 << 21) - 1) / std::max(maxComponent(extent), 1e-30f);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, photons.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            Vec3 q = (photons[i].position - b.lo) * scale;
            uint64_t code = spreadBits(uint64_t(q.x)) | spreadBits(uint64_t(q.y)) << 1 | spreadBits(uint64_t(q.z)) << 2;
            keys[i] = {code, uint32_t(i)};
        }
    });
    tbb::parallel_sort(keys.begin(), keys.end());
    mPhotons.resize(photons.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, keys.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) mPhotons[i] = photons[keys[i].second];
    });
    mTree = std::make_unique<Tree>(mPhotons);
}

PhotonMap::~PhotonMap() = default;

size_t PhotonMap::nearest(const Vec3& x, size_t k, uint32_t* indices, float* dist2) const {
    if (mPhotons.empty() || k == 0) return 0;
    const float q[3] = {x.x, x.y, x.z};
    return size_t(mTree->index.knnSearch(q, k, indices, dist2));
}

size_t PhotonMap::memoryBytes() const {
    // Photons, plus nanoflann's index permutation and about one node per
    // 8 photons (leaves of at most 16).
    return mPhotons.size() * (sizeof(Photon) + sizeof(uint32_t)) + mPhotons.size() / 8 * 64;
}

}  // namespace vdbmarch
