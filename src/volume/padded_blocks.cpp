#include "volume/padded_blocks.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <limits>
#include <stdexcept>
#include <new>

#include <sys/mman.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace vdbmarch {

namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;
using Level1 = openvdb::FloatTree::RootNodeType::ChildNodeType::ChildNodeType;
using openvdb::Coord;
// Blocks read into the scratch at a time (12 MB).
constexpr size_t PieceBlocks = 4096;

// For each of the 26 neighbouring leaves, the voxels of a leaf whose
// 26-neighbourhood reaches into it (x = 7 towards +x, x = 0 towards -x,
// any x where the step in x is 0; the same in y and z).
struct NeighbourReach {
    Coord step;
    LeafT::NodeMaskType voxels;
};

std::vector<NeighbourReach> neighbourReaches() {
    std::vector<NeighbourReach> out;
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
                if (dx == 0 && dy == 0 && dz == 0) continue;
                NeighbourReach n{Coord(dx, dy, dz), LeafT::NodeMaskType()};
                auto reaches = [](int d, int v) { return d == 0 || (d > 0 ? v == 7 : v == 0); };
                for (openvdb::Index i = 0; i < LeafT::SIZE; ++i) {
                    const Coord v = LeafT::offsetToLocalCoord(i);
                    if (reaches(dx, v.x()) && reaches(dy, v.y()) && reaches(dz, v.z())) n.voxels.setOn(i);
                }
                out.push_back(n);
            }
    return out;
}

// Origins of the 8^3 blocks of the grid's active topology dilated by one voxel
// in all 26 directions (a point is non-empty iff its floor voxel is active
// there), sorted x-major; `bounds` gets the dilated active voxels' box. As
// OpenVDB's dilateActiveValues by one voxel on a topology copy: every
// leaf, the neighbours its active voxels reach, and the blocks of active
// tiles with the layer of blocks below their low faces (where their trilinear
// support reaches); done on the leaves' masks, in a tree with one voxel per
// block, without building the dilated tree.
std::deque<Coord> dilatedBlockOrigins(const openvdb::FloatTree& tree, openvdb::CoordBBox& bounds) {
    static const std::vector<NeighbourReach> reaches = neighbourReaches();
    // The leaves in parallel, each range into its own block set; the union of
    // sets (and of boxes) does not depend on how the leaves were split.
    struct MarkBlocks {
        openvdb::BoolTree blocks{false};
        openvdb::CoordBBox bounds;
        MarkBlocks() = default;
        MarkBlocks(MarkBlocks&, tbb::split) {}
        void operator()(const openvdb::tree::LeafManager<const openvdb::FloatTree>::LeafRange& range) {
            openvdb::tree::ValueAccessor<openvdb::BoolTree> acc(blocks);
            for (auto leaf = range.begin(); leaf; ++leaf) {
                const Coord b = leaf->origin() >> 3;
                acc.setValueOn(b);
                const auto& on = leaf->getValueMask();
                if (on.isOff()) continue;
                openvdb::CoordBBox box;
                leaf->evalActiveBoundingBox(box, /*visitVoxels=*/true);
                box.expand(1);
                bounds.expand(box);
                for (const NeighbourReach& n : reaches) {
                    LeafT::NodeMaskType hit = on;
                    hit &= n.voxels;
                    if (!hit.isOff()) acc.setValueOn(b + n.step);
                }
            }
        }
        void join(MarkBlocks& other) {
            blocks.topologyUnion(other.blocks);
            bounds.expand(other.bounds);
        }
    } marked;
    openvdb::tree::LeafManager<const openvdb::FloatTree> leaves(tree);
    tbb::parallel_reduce(leaves.leafRange(64), marked);
    openvdb::BoolTree& blocks = marked.blocks;
    bounds = marked.bounds;
    openvdb::tree::ValueAccessor<openvdb::BoolTree> acc(blocks);
    // Active tiles: the interior nodes' values only (the leaves' voxels are
    // done). A tile's trilinear support reaches one voxel past each face: on
    // the high side that lies in the tile's own last blocks (a block holds
    // o + [0, 8]), on the low side in the blocks below it, which are added.
    auto tile = tree.cbeginValueOn();
    tile.setMaxDepth(openvdb::FloatTree::DEPTH - 2);
    for (; tile; ++tile) {
        openvdb::CoordBBox box = tile.getBoundingBox();
        box.expand(1);
        bounds.expand(box);
        const Coord lo = box.min() >> 3, hi = tile.getBoundingBox().max() >> 3;
        for (int x = lo.x(); x <= hi.x(); ++x)
            for (int y = lo.y(); y <= hi.y(); ++y)
                for (int z = lo.z(); z <= hi.z(); ++z) acc.setValueOn(Coord(x, y, z));
    }
    std::deque<Coord> origins;
    for (auto it = blocks.cbeginValueOn(); it; ++it) {
        const Coord b = it.getCoord();
        origins.emplace_back(b.x() * 8, b.y() * 8, b.z() * 8);
    }
    std::sort(origins.begin(), origins.end());
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
    // Rows along z: eight values from one leaf, the ninth from the next.
    for (int x = 0; x < N; ++x)
        for (int y = 0; y < N; ++y) {
            const int i = (x >> 3) * 4 + (y >> 3) * 2, offset = ((x & 7) << 6) | ((y & 7) << 3);
            float* row = dst + (x * N + y) * N;
            if (leaf[i]) std::memcpy(row, leaf[i] + offset, 8 * sizeof(float));
            else std::fill_n(row, 8, tile[i]);
            row[8] = leaf[i + 1] ? leaf[i + 1][offset] : tile[i + 1];
        }
}

// What the build keeps of a block besides its values.
struct BlockSummary {
    bool any = false, constant = false;
    uint32_t tightBox = 0;
    float minimum = 0, maximum = 0;
};

// One pass over the padded values. A cell touches the vertices c + {0,1}^3,
// so the cells whose stencil holds a non-zero vertex v span, per axis,
// [max(0, v - 1), min(7, v)]: the tight box follows from the smallest and
// largest coordinates of the non-zero vertices.
BlockSummary summarize(const float* v) {
    constexpr int N = PaddedBlocks::N;
    BlockSummary b;
    int lo[3] = {N, N, N}, hi[3] = {-1, -1, -1};
    float mn = v[0], mx = v[0];
    bool constant = true;
    for (int x = 0; x < N; ++x)
        for (int y = 0; y < N; ++y) {
            // Per row: its extremes and the first and last non-zero z; the
            // row's x and y join the box once, if any value is non-zero.
            const float* row = v + (x * N + y) * N;
            int zLo = N, zHi = -1;
            for (int z = 0; z < N; ++z) {
                const float value = row[z];
                mn = std::min(mn, value);
                mx = std::max(mx, value);
                constant = constant && value == v[0];
                if (value != 0) {
                    zLo = std::min(zLo, z);
                    zHi = z;
                }
            }
            if (zHi < 0) continue;
            lo[0] = std::min(lo[0], x);
            hi[0] = std::max(hi[0], x);
            lo[1] = std::min(lo[1], y);
            hi[1] = std::max(hi[1], y);
            lo[2] = std::min(lo[2], zLo);
            hi[2] = std::max(hi[2], zHi);
        }
    b.any = hi[0] >= 0;
    b.constant = b.any && constant;
    b.minimum = std::max(0.f, mn);
    b.maximum = mx;
    if (b.any)
        for (int a = 0; a < 3; ++a)
            b.tightBox |= uint32_t(std::max(0, lo[a] - 1)) << (4 * a) | uint32_t(std::min(8, hi[a] + 1)) << (12 + 4 * a);
    return b;
}

// Gives freed heap pages back to the system (glibc keeps them otherwise, and
// the grid's leaves are small allocations spread over the heap).
void releaseFreedMemory() {
#if defined(__GLIBC__)
    malloc_trim(0);
#endif
}

}  // namespace

void PaddedBlocks::buildPiece(const openvdb::FloatGrid& grid, const Coord* origins, size_t n,
                              std::vector<float>& scratch,
                              openvdb::tree::ValueAccessor<openvdb::Int32Tree>& indexAccessor) {
    scratch.resize(n * Size);
    std::vector<BlockSummary> summaries(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& r) {
        auto acc = grid.getConstAccessor();
        for (size_t b = r.begin(); b != r.end(); ++b) {
            float* dst = &scratch[b * Size];
            readPadded(acc, origins[b], dst);
            summaries[b] = summarize(dst);
        }
    });
    // Each block's id (constant blocks share one), in block order so that
    // ids do not depend on the thread count, then the copies.
    std::vector<int32_t> ids(n, 0);
    for (size_t b = 0; b < n; ++b) {
        const BlockSummary& s = summaries[b];
        if (s.any)
            ids[b] = s.constant ? constantBlock(scratch[b * Size], s.tightBox, s.maximum, s.minimum)
                                : allocateBlock(s.tightBox, s.maximum, s.minimum);
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t b = r.begin(); b != r.end(); ++b)
            if (summaries[b].any && !summaries[b].constant)
                std::memcpy(values(ids[b]), &scratch[b * Size], Size * sizeof(float));
    });
    for (size_t b = 0; b < n; ++b) indexAccessor.addTile(1, origins[b], ids[b], true);
}

void PaddedBlocks::build(openvdb::FloatGrid& grid) {
    // Consumed from the front as the build goes: a deque gives its memory
    // back chunk by chunk (at the end of a large build, the peak).
    std::deque<Coord> origins = dilatedBlockOrigins(grid.tree(), activeBounds);
    // The grid's leaves in x order: a block at x reads x .. x + 8, so once the
    // blocks of slab X are built, no later block reads a leaf at x <= X.
    std::deque<Coord> leaves;
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) leaves.push_back(leaf->origin());
    std::sort(leaves.begin(), leaves.end());
    uint64_t freedSinceTrim = 0;
    // The interior nodes just above the leaves, in x order.
    std::vector<Coord> nodes;
    for (auto top = grid.tree().root().cbeginChildOn(); top; ++top)
        for (auto node = top->cbeginChildOn(); node; ++node) nodes.push_back(node->origin());
    std::sort(nodes.begin(), nodes.end());
    size_t nextNode = 0;

    std::vector<float> scratch;
    std::vector<Coord> piece;
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> indexAccessor(index);
    // The tables hold at most one entry per block: reserved once, so no
    // growth copies them at the end of a large build (the peak). Pages of
    // the reserve that no id reaches are never touched, so never resident.
    const size_t blockCount = origins.size();
    tightBox.reserve(blockCount);
    blockMax.reserve(blockCount);
    blockMin.reserve(blockCount);
    while (!origins.empty()) {
        const int slabX = origins.front().x();
        // Pieces of a slab at a time: the scratch stays small.
        while (!origins.empty() && origins.front().x() == slabX) {
            piece.clear();
            while (!origins.empty() && origins.front().x() == slabX && piece.size() < PieceBlocks) {
                piece.push_back(origins.front());
                origins.pop_front();
            }
            buildPiece(grid, piece.data(), piece.size(), scratch, indexAccessor);
        }
        // Free the leaves, then the interior nodes, that no block still to
        // build reads (a 16^3-leaf node once its last column is done).
        for (; !leaves.empty() && leaves.front().x() <= slabX; leaves.pop_front()) {
            if (LeafT* leaf = grid.tree().stealNode<LeafT>(leaves.front(), 0.f, false)) {
                freedSinceTrim += leaf->memUsage();
                delete leaf;
            }
        }
        for (; nextNode < nodes.size() && nodes[nextNode].x() + int(Level1::DIM) - 8 <= slabX; ++nextNode) {
            if (Level1* node = grid.tree().stealNode<Level1>(nodes[nextNode], 0.f, false)) {
                freedSinceTrim += node->memUsage();
                delete node;
            }
        }
        if (freedSinceTrim > (uint64_t(16) << 20)) {
            releaseFreedMemory();
            freedSinceTrim = 0;
        }
    }
    scratch = std::vector<float>();
    releaseFreedMemory();
}

PaddedBlocks::Footprint PaddedBlocks::predict(uint64_t gridBytes, uint64_t activeVoxels,
                                              const openvdb::CoordBBox& bounds) {
    using Level2 = openvdb::FloatTree::RootNodeType::ChildNodeType;
    // Interior nodes: one per node-sized cell the active box overlaps (an
    // upper bound: a sparse grid leaves some out). The Int32 index has
    // the same 8-byte table entries as the float grid.
    auto cells = [&](int log2Size) {
        uint64_t n = 1;
        for (int a = 0; a < 3; ++a) n *= uint64_t((bounds.max()[a] >> log2Size) - (bounds.min()[a] >> log2Size) + 1);
        return n;
    };
    const uint64_t level2Bytes = Level2::NUM_VALUES * sizeof(void*) + 2 * (Level2::NUM_VALUES / 8);
    const uint64_t level1Bytes = Level1::NUM_VALUES * sizeof(void*) + 2 * (Level1::NUM_VALUES / 8);
    const uint64_t interior = bounds.empty() ? 0
                                             : cells(Level2::TOTAL) * level2Bytes + cells(Level1::TOTAL) * level1Bytes;
    const uint64_t leafBytes = sizeof(LeafT) + LeafT::SIZE * sizeof(float);
    // Leaves from the grid's size; its active voxels only where the size
    // says nothing (active tiles hold voxels without leaves, and become
    // shared constant blocks).
    uint64_t leaves = gridBytes > interior ? (gridBytes - interior) / leafBytes : 0;
    if (leaves == 0) leaves = (activeVoxels + LeafT::SIZE - 1) / LeafT::SIZE;
    // Blocks with their own values per leaf, and blocks in all: ratios
    // measured on the sample assets and the upsampled clouds (docs/memory.md).
    const uint64_t kept = leaves * 110 / 100, all = leaves * 125 / 100;
    const uint64_t perBlock = Size * sizeof(float) + sizeof(uint32_t) + 2 * sizeof(float);
    const uint64_t lists = sizeof(openvdb::Coord) * (all + leaves);  // block origins, leaves in x order
    const uint64_t slabs = bounds.empty() ? 1 : uint64_t(bounds.dim().x()) / 8 + 1;
    const uint64_t scratch = 2 * all / slabs * Size * sizeof(float);  // the largest slab, taken as twice the mean
    Footprint f;
    f.resident = kept * perBlock + interior;
    // At the start the grid; at the end the blocks, their index and what is
    // left of the grid (its interior nodes).
    const uint64_t start = gridBytes + lists;
    const uint64_t end = f.resident + interior + lists + scratch;
    f.loadPeak = std::max(start, end);
    return f;
}

// A chunk is mapped from the system directly, 2 MB aligned, with transparent
// huge pages asked for: the kernel then maps 2 MB per page fault, not 4 kB
// (in 4 kB pages, faulting in a large build took seconds). Not from malloc,
// whose heap would place chunks by its own thresholds among the freed
// leaves; pages of the last chunk that no block reaches are never resident.
constexpr size_t HugePage = size_t(2) << 20;
static_assert(PaddedBlocks::ChunkBytes % HugePage == 0, "chunks are whole huge pages");

float* PaddedBlocks::mapChunk() {
    void* p = ::mmap(nullptr, ChunkBytes + HugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    const uintptr_t start = reinterpret_cast<uintptr_t>(p);
    const uintptr_t aligned = (start + HugePage - 1) & ~uintptr_t(HugePage - 1);
    // Trim the mapping to [aligned, aligned + ChunkBytes): the head (empty when
    // start is aligned) and the tail (never empty: aligned < start + HugePage).
    if (aligned > start) ::munmap(p, aligned - start);
    ::munmap(reinterpret_cast<void*>(aligned + ChunkBytes), start + HugePage - aligned);
#if defined(MADV_HUGEPAGE)
    ::madvise(reinterpret_cast<void*>(aligned), ChunkBytes, MADV_HUGEPAGE);
#endif
    return reinterpret_cast<float*>(aligned);
}

void PaddedBlocks::UnmapChunk::operator()(float* p) const { ::munmap(p, ChunkBytes); }

int32_t PaddedBlocks::allocateBlock(uint32_t box, float maximum, float minimum) {
    const size_t slot = tightBox.size();
    if (slot >= size_t(std::numeric_limits<int32_t>::max()))
        throw std::length_error("PaddedBlocks: more blocks than an Int32 index holds");
    if (slot % ChunkBlocks == 0) mChunks.emplace_back(mapChunk());
    tightBox.push_back(box);
    blockMax.push_back(maximum);
    blockMin.push_back(minimum);
    return int32_t(slot + 1);
}

int32_t PaddedBlocks::constantBlock(float value, uint32_t box, float maximum, float minimum) {
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    int32_t& id = mConstantBlocks[bits];
    if (id == 0) {
        id = allocateBlock(box, maximum, minimum);
        std::fill_n(values(id), Size, value);
    }
    return id;
}

uint64_t PaddedBlocks::memoryBytes() const {
    return uint64_t(blockCount()) * (Size * sizeof(float) + sizeof(uint32_t) + 2 * sizeof(float)) +
           uint64_t(index.memUsage());
}

}  // namespace vdbmarch
