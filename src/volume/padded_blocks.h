// Internal to src/volume: a density grid copied into padded 9x9x9 blocks, one
// per 8x8x8 leaf-aligned block where trilinear samples can land. Every lookup
// reads its eight corners from one contiguous block, with no tree traversal
// while a ray stays inside it (a step of one voxel stays ~8 samples in a
// block). Blocks whose values are all equal share one copy. The blocks
// answer every lookup, so the grid they are built from is
// not kept: build() frees its leaves as it goes, and the peak memory of a load
// is about the larger of the grid and the blocks, not their sum.
// Includes OpenVDB; never include it outside volume/.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <map>
#include <memory>
#include <vector>

#include <openvdb/openvdb.h>

namespace vdbmarch {

struct PaddedBlocks {
    static constexpr int N = 9, Size = N * N * N;
    // Values live in chunks of 32 MiB (16 huge pages) holding ChunkBlocks
    // blocks each (20 bytes to spare), so an id finds its values by a division
    // by a constant, with no pointer per block.
    static constexpr size_t ChunkBytes = size_t(32) << 20;
    static constexpr size_t ChunkBlocks = ChunkBytes / (Size * sizeof(float));


    // One level-1 tile (an 8^3 block) per block of the grid's topology dilated
    // by one voxel (trilinear lookups reach the +1 neighbours): the id + 1 of
    // the block's values where they are not all zero, 0 where they are. Blocks
    // of one constant value share one id. Every tile is active; the media's
    // block walk (vdb_medium.cpp) visits these tiles; tiles cost no leaf (an
    // Int32 leaf per block weighed as much as the grid).
    openvdb::Int32Tree index{0};
    // Per id (a block's values, shared by every block of a constant value):
    // the cells (0..7 per axis) whose trilinear stencil touches a non-zero
    // value (lo in bits 0-11, hi exclusive in bits 12-23), and the largest and
    // smallest value of the padded block: every trilinear value inside the
    // cells lies between them, so they are a local majorant and a
    // residual-tracking control. Tables per id, not per block: the constant
    // blocks add no entry.
    std::vector<uint32_t> tightBox;
    std::vector<float> blockMax, blockMin;
    // Bounding box of the dilated topology's active voxels (index space).
    openvdb::CoordBBox activeBounds;

    // Builds the blocks from `grid` (sanitised: inactive values are 0) and
    // frees the grid's leaves on the way (the grid keeps its tiles and
    // interior nodes; drop it afterwards). Values are bit-identical to
    // reading the grid with an accessor; the result is the same for any
    // thread count.
    void build(openvdb::FloatGrid& grid);

    // Memory of a load, predicted from a float grid's metadata before reading:
    // its in-memory size (OpenVDB's file_mem_bytes), active voxels and their
    // bounding box. docs/memory.md has the formula and its measured accuracy.
    struct Footprint {
        uint64_t loadPeak = 0;  // above what the process held before the read
        uint64_t resident = 0;  // the blocks and their index, once loaded
    };
    static Footprint predict(uint64_t gridBytes, uint64_t activeVoxels, const openvdb::CoordBBox& bounds);

    // The Size values of index value `id` (> 0).
    const float* block(int32_t id) const { return values(id); }
    size_t blockCount() const { return tightBox.size(); }
    // Memory held: block values, per-id tables and the index tree.
    uint64_t memoryBytes() const;

private:
    // Reads n blocks of the grid at `origins` into `scratch`, keeps their
    // values and tables and adds them to the index.
    void buildPiece(const openvdb::FloatGrid& grid, const openvdb::Coord* origins, size_t n,
                    std::vector<float>& scratch, openvdb::tree::ValueAccessor<openvdb::Int32Tree>& indexAccessor);
    // The id of the one block of `value` everywhere, shared by every block
    // whose padded values all equal it (the inside of a constant region, an
    // active tile), made on first use.
    int32_t constantBlock(float value, uint32_t tightBox, float maximum, float minimum);
    // A new id with its table entries; its values' storage is block(id).
    int32_t allocateBlock(uint32_t tightBox, float maximum, float minimum);

    // The storage of id's values (the build writes them; lookups read them).
    float* values(int32_t id) const {
        const size_t slot = size_t(id - 1);
        return mChunks[slot / ChunkBlocks].get() + (slot % ChunkBlocks) * Size;
    }
    static float* mapChunk();
    struct UnmapChunk {
        void operator()(float* p) const;
    };
    // Block values, carved in id order from the chunks, and the ids of the
    // shared constant blocks by their value's bits.
    std::vector<std::unique_ptr<float, UnmapChunk>> mChunks;
    std::map<uint32_t, int32_t> mConstantBlocks;
};

}  // namespace vdbmarch
