#include "volume/padded_blocks.h"

#include <algorithm>
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <openvdb/tools/Morphology.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace vdbmarch {

namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;
using openvdb::Coord;

// Origins of the 8^3 blocks of the grid's active topology dilated by one voxel
// in all 26 directions (a point is non-empty iff its floor voxel is active
// there), sorted x-major; `bounds` gets the dilated active voxels' box.
std::vector<Coord> dilatedBlockOrigins(const openvdb::FloatTree& tree, openvdb::CoordBBox& bounds) {
    openvdb::BoolTree topology(tree, false, openvdb::TopologyCopy());
    openvdb::tools::dilateActiveValues(topology, 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    topology.evalActiveVoxelBoundingBox(bounds);
    std::vector<Coord> origins;
    for (auto leaf = topology.cbeginLeaf(); leaf; ++leaf) origins.push_back(leaf->origin());
    // Active tiles of the topology (coarse constant regions) hold blocks too.
    for (auto it = topology.cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) continue;
        const openvdb::CoordBBox b = it.getBoundingBox();
        for (int x = b.min().x(); x <= b.max().x(); x += 8)
            for (int y = b.min().y(); y <= b.max().y(); y += 8)
                for (int z = b.min().z(); z <= b.max().z(); z += 8) origins.emplace_back(x, y, z);
    }
    std::sort(origins.begin(), origins.end());
    origins.erase(std::unique(origins.begin(), origins.end()), origins.end());
    return origins;
}

// The grid's values at o + [0, 8]^3 into dst (x-major, z fastest), read from
// the eight leaves the padded block overlaps, or from the tile that covers a
// leaf-sized region where there is no leaf (inactive: 0 after sanitising).
void readPadded(openvdb::FloatGrid::ConstAccessor& acc, const Coord& o, float* dst) {
    constexpr int N = PaddedBlocks::N;
    const float* leaf[8];
    float tile[8];
    for (int i = 0; i < 8; ++i) {
        const Coord c = o.offsetBy(i & 4 ? 8 : 0, i & 2 ? 8 : 0, i & 1 ? 8 : 0);
        const LeafT* l = acc.probeConstLeaf(c);
        leaf[i] = l ? l->buffer().data() : nullptr;
        tile[i] = l ? 0.f : acc.getValue(c);
    }
    for (int x = 0; x < N; ++x)
        for (int y = 0; y < N; ++y)
            for (int z = 0; z < N; ++z) {
                const int i = (x >> 3) * 4 + (y >> 3) * 2 + (z >> 3);
                const int offset = ((x & 7) << 6) | ((y & 7) << 3) | (z & 7);
                dst[(x * N + y) * N + z] = leaf[i] ? leaf[i][offset] : tile[i];
            }
}

uint32_t computeTightBox(const float* v) {
    constexpr int N = PaddedBlocks::N;
    int lo[3] = {8, 8, 8}, hi[3] = {0, 0, 0};
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y)
            for (int z = 0; z < 8; ++z) {
                bool nonZero = false;
                for (int c = 0; c < 8 && !nonZero; ++c)
                    nonZero = v[((x + (c >> 2)) * N + y + ((c >> 1) & 1)) * N + z + (c & 1)] != 0;
                if (!nonZero) continue;
                const int p[3] = {x, y, z};
                for (int a = 0; a < 3; ++a) {
                    lo[a] = std::min(lo[a], p[a]);
                    hi[a] = std::max(hi[a], p[a] + 1);
                }
            }
    uint32_t packed = 0;
    for (int a = 0; a < 3; ++a) packed |= uint32_t(lo[a]) << (4 * a) | uint32_t(hi[a]) << (12 + 4 * a);
    return packed;
}

// Gives freed heap pages back to the system (glibc keeps them otherwise, and
// the grid's leaves are small allocations spread over the heap).
void releaseFreedMemory() {
#if defined(__GLIBC__)
    malloc_trim(0);
#endif
}

}  // namespace

void PaddedBlocks::build(openvdb::FloatGrid& grid) {
    std::vector<Coord> origins = dilatedBlockOrigins(grid.tree(), activeBounds);
    // The grid's leaves in x order: a block at x reads x .. x + 8, so once the
    // blocks of slab X are built, no later block reads a leaf at x <= X.
    std::vector<Coord> leaves;
    leaves.reserve(grid.tree().leafCount());
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) leaves.push_back(leaf->origin());
    std::sort(leaves.begin(), leaves.end());
    size_t nextLeaf = 0;
    uint64_t freedSinceTrim = 0;

    std::vector<float> scratch;
    std::vector<char> nonEmpty;
    std::vector<uint32_t> boxes;
    std::vector<float> maxima, minima;
    for (size_t s = 0; s < origins.size();) {
        const int slabX = origins[s].x();
        size_t e = s;
        while (e < origins.size() && origins[e].x() == slabX) ++e;
        const size_t n = e - s;
        scratch.resize(n * Size);
        nonEmpty.assign(n, 0);
        boxes.assign(n, 0);
        maxima.assign(n, 0.f);
        minima.assign(n, 0.f);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& r) {
            auto acc = grid.getConstAccessor();
            for (size_t b = r.begin(); b != r.end(); ++b) {
                float* dst = &scratch[b * Size];
                readPadded(acc, origins[s + b], dst);
                const bool any = std::any_of(dst, dst + Size, [](float v) { return v != 0; });
                nonEmpty[b] = any;
                if (any) boxes[b] = computeTightBox(dst);
                const auto range = std::minmax_element(dst, dst + Size);
                minima[b] = std::max(0.f, *range.first);
                maxima[b] = *range.second;
            }
        });
        const size_t kept = size_t(std::count(nonEmpty.begin(), nonEmpty.end(), char(1)));
        std::unique_ptr<float[]> slab(kept ? new float[kept * Size] : nullptr);
        size_t k = 0;
        for (size_t b = 0; b < n; ++b) {
            int32_t id = 0;
            if (nonEmpty[b]) {
                float* dst = slab.get() + k * Size;
                std::memcpy(dst, &scratch[b * Size], Size * sizeof(float));
                blockValues.push_back(dst);
                tightBox.push_back(boxes[b]);
                blockMax.push_back(maxima[b]);
                blockMin.push_back(minima[b]);
                id = int32_t(blockValues.size());
                ++k;
            }
            index.addTile(1, origins[s + b], id, true);
        }
        if (slab) mSlabs.push_back(std::move(slab));
        mValueBytes += uint64_t(kept) * Size * sizeof(float);
        // Free the leaves no block still to build reads.
        for (; nextLeaf < leaves.size() && leaves[nextLeaf].x() <= slabX; ++nextLeaf) {
            if (LeafT* leaf = grid.tree().stealNode<LeafT>(leaves[nextLeaf], 0.f, false)) {
                freedSinceTrim += leaf->memUsage();
                delete leaf;
            }
        }
        if (freedSinceTrim > (uint64_t(64) << 20)) {
            releaseFreedMemory();
            freedSinceTrim = 0;
        }
        s = e;
    }
    scratch = std::vector<float>();
    blockValues.shrink_to_fit();
    tightBox.shrink_to_fit();
    blockMax.shrink_to_fit();
    blockMin.shrink_to_fit();
    releaseFreedMemory();
}

uint64_t PaddedBlocks::memoryBytes() const {
    return mValueBytes + blockValues.capacity() * sizeof(const float*) + tightBox.capacity() * sizeof(uint32_t) +
           (blockMax.capacity() + blockMin.capacity()) * sizeof(float) + uint64_t(index.memUsage());
}

}  // namespace vdbmarch
