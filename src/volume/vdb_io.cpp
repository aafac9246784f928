// Reading VDB files: opening them with errors that name the file (and a
// check that every grid lies inside the file), choosing and reading a scalar
// grid as float, what the file's metadata says of a grid's memory before it
// is read, and the summaries and listings of `vdbmarch info`. One of the few
// files that include OpenVDB headers.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>

#include <openvdb/openvdb.h>
#include <openvdb/io/GridDescriptor.h>

#include "core/error.h"
#include "core/memory.h"
#include "core/transform.h"
#include "volume/medium.h"
#include "volume/padded_blocks.h"
#include "volume/vdb_conditioning.h"
#include "volume/vdb_io.h"
#include "volume/vdb_read_guard.h"

namespace vdbmarch {

void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

namespace {

std::string gridTypeName(const openvdb::GridBase& g) {
    std::string t = g.valueType();
    return t;
}

// Reads a VDB file's header and grid descriptors, as io::File::open does,
// to check what OpenVDB's reader takes on trust: every grid's data must lie
// inside the file (a file cut short, by a failed copy, ends before its last
// grid's end position, and OpenVDB would read the front part silently).
class GridExtentCheck : public openvdb::io::Archive {
public:
    void check(const std::string& path) {
        std::ifstream is(path, std::ios::binary);
        if (!is) throw IoError(str(path, ": cannot open VDB file: ", std::strerror(errno)));
        is.seekg(0, std::ios::end);
        const int64_t size = int64_t(is.tellg());
        is.seekg(0, std::ios::beg);
        readHeader(is);
        if (!inputHasGridOffsets()) return;  // files before grid offsets: nothing to check against
        setFormatVersion(is);
        setLibraryVersion(is);
        setDataCompression(is);
        openvdb::MetaMap meta;
        meta.readMeta(is);
        const int32_t count = readGridCount(is);
        if (count < 0) throw InputError(str(path, ": damaged VDB file (grid count ", count, ")"));
        for (int32_t i = 0; i < count; ++i) {
            if (!is.good() || int64_t(is.tellg()) >= size)
                throw InputError(str(path, ": the VDB file is cut short: it ends (", size,
                                     " bytes) before the descriptor of grid ", i + 1, " of ", count,
                                     "; copy it again"));
            openvdb::io::GridDescriptor gd;
            gd.read(is);
            const std::string name = openvdb::io::GridDescriptor::nameAsString(gd.uniqueName());
            if (gd.getGridPos() < 0 || gd.getBlockPos() < gd.getGridPos() || gd.getEndPos() < gd.getBlockPos())
                throw InputError(str(path, ": damaged VDB file: grid '", printableExcerpt(name, 80), "' has inconsistent offsets (",
                                     gd.getGridPos(), ", ", gd.getBlockPos(), ", ", gd.getEndPos(), ")"));
            if (gd.getEndPos() > size)
                throw InputError(str(path, ": the VDB file is cut short: grid '", printableExcerpt(name, 80), "' ends at byte ",
                                     gd.getEndPos(), " but the file has ", size, " bytes; copy it again"));
            gd.seekToEnd(is);
        }
    }
    // Archive's interface, unused: this class only reads descriptors.
    openvdb::io::Archive::Ptr copy() const override { return std::make_shared<GridExtentCheck>(*this); }
};

// Opens a VDB file, turning OpenVDB's exceptions into messages that name it,
// and refuses a file whose grids do not lie inside it (GridExtentCheck).
std::unique_ptr<openvdb::io::File> openVdbFile(const std::string& path) {
    initOpenVdb();
    {
        std::ifstream probe(path, std::ios::binary);
        if (!probe) throw IoError(str(path, ": cannot open VDB file: ", std::strerror(errno)));
    }
    try {
        GridExtentCheck().check(path);
    } catch (const InputError&) {
        throw;
    } catch (const IoError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(str(path, ": not a readable OpenVDB file (", printableExcerpt(e.what()), ")"));
    }
    auto file = std::make_unique<openvdb::io::File>(path);
    try {
        file->open(/*delayLoad=*/false);
    } catch (const std::exception& e) {
        throw InputError(str(path, ": not a readable OpenVDB file (", printableExcerpt(e.what()), ")"));
    }
    return file;
}

std::string gridListing(openvdb::io::File& file) {
    std::string names;
    auto grids = file.readAllGridMetadata();
    for (const auto& g : *grids) names += str(names.empty() ? "" : ", ", "'", printableExcerpt(g->getName(), 80), "' (", printableExcerpt(gridTypeName(*g), 80), ")");
    return names.empty() ? "none" : names;
}


// The grid `wanted` names; with an empty name "density", else the first
// scalar grid. Throws InputError listing the grids when there is none.
std::string chooseGrid(openvdb::io::File& file, const std::string& path, const std::string& wanted) {
    std::string name = wanted;
    if (name.empty()) {
        auto grids = file.readAllGridMetadata();
        for (const auto& g : *grids)
            if (g->getName() == "density") name = "density";
        if (name.empty())
            for (const auto& g : *grids)
                if (g->isType<openvdb::FloatGrid>() || g->isType<openvdb::DoubleGrid>()) {
                    name = g->getName();
                    break;
                }
        if (name.empty()) throw InputError(str(path, ": no float grid in the file; grids: ", gridListing(file)));
    }
    if (!file.hasGrid(name))
        throw InputError(str(path, ": no grid named '", name, "'; grids in the file: ", gridListing(file)));
    return name;
}

// What OpenVDB's writer records of a grid: its in-memory size, active voxels
// and their bounds (known = false for files written without them).
struct GridStats {
    bool known = false, isDouble = false;
    uint64_t bytes = 0, voxels = 0;
    openvdb::CoordBBox bounds;
};

GridStats gridStats(openvdb::io::File& file, const std::string& name) {
    GridStats s;
    try {
        const auto meta = file.readGridMetadata(name);
        const auto bytes = meta->getMetadata<openvdb::Int64Metadata>(openvdb::GridBase::META_FILE_MEM_BYTES);
        const auto voxels = meta->getMetadata<openvdb::Int64Metadata>(openvdb::GridBase::META_FILE_VOXEL_COUNT);
        const auto lo = meta->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MIN);
        const auto hi = meta->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MAX);
        if (!bytes) return s;
        s.known = true;
        s.isDouble = meta->isType<openvdb::DoubleGrid>();
        s.bytes = uint64_t(std::max<int64_t>(0, bytes->value()));
        s.voxels = voxels ? uint64_t(std::max<int64_t>(0, voxels->value())) : 0;
        if (lo && hi) s.bounds = openvdb::CoordBBox(openvdb::Coord(lo->value()), openvdb::Coord(hi->value()));
    } catch (const std::exception&) {  // no metadata: nothing known before reading
    }
    return s;
}

// The grid's load: PaddedBlocks::predict on its float size (a double grid is
// held while its float copy is made).
PaddedBlocks::Footprint gridFootprint(const GridStats& g) {
    const uint64_t floatBytes = g.isDouble ? g.bytes / 2 : g.bytes;
    PaddedBlocks::Footprint f = PaddedBlocks::predict(floatBytes, g.voxels, g.bounds);
    if (g.isDouble) f.loadPeak += g.bytes;
    return f;
}

}  // namespace

MediumMemory predictMediumMemory(const MediumDesc& d) {
    MediumMemory m;
    if (d.type != MediumDesc::Type::Vdb) return m;
    auto file = openVdbFile(d.file);
    const GridStats density = gridStats(*file, chooseGrid(*file, d.file, d.grid));
    if (!density.known) return m;
    const PaddedBlocks::Footprint f = gridFootprint(density);
    m.gridBytes = density.bytes;
    m.loading = f.loadPeak;
    m.resident = f.resident;
    if (d.hasEmission) {
        // The emission grid is kept as read; the emission sampler adds a
        // coordinate, a cdf entry and a weight (24 bytes) per voxel of its
        // topology dilated by one (about 1.3 per active voxel).
        const GridStats e = gridStats(*file, chooseGrid(*file, d.file, d.emissionGrid));
        const uint64_t sampler = e.voxels * 13 / 10 * 24;
        m.loading = std::max(m.loading, m.resident + e.bytes + (e.isDouble ? e.bytes : 0));
        m.resident += (e.isDouble ? e.bytes / 2 : e.bytes) + sampler;
    }
    return m;
}

// Reads the grid `wanted` names (chooseGrid) as a float grid.
openvdb::FloatGrid::Ptr readFloatGrid(const std::string& path, const std::string& wanted, std::string* chosenName) {
    const auto guard = guardVdbRead(path);
    auto file = openVdbFile(path);
    const std::string name = chooseGrid(*file, path, wanted);
    // The read itself, refused before it starts when it cannot fit beside
    // what the process holds (a medium checks its whole load first).
    const GridStats stats = gridStats(*file, name);
    if (stats.known)
        checkMemory(residentMemoryBytes() + stats.bytes + (stats.isDouble ? stats.bytes / 2 : 0),
                    str(path, ": grid '", name, "' (", formatBytes(stats.bytes), " in memory)"));
    openvdb::GridBase::Ptr base;
    try {
        base = file->readGrid(name);
    } catch (const std::exception& e) {
        throw InputError(str(path, ": grid '", name, "' could not be read (", printableExcerpt(e.what()), ")"));
    }
    if (chosenName) *chosenName = name;
    if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(base)) return f;
    if (auto d = openvdb::gridPtrCast<openvdb::DoubleGrid>(base)) {
        auto f = openvdb::FloatGrid::create(float(d->background()));
        f->setTransform(d->transform().copy());
        f->setName(d->getName());
        f->tree().topologyUnion(d->tree());
        auto acc = f->getAccessor();
        for (auto it = d->cbeginValueOn(); it; ++it) {
            if (it.isVoxelValue()) acc.setValue(it.getCoord(), float(*it));
            else f->tree().fill(it.getBoundingBox(), float(*it), true);
        }
        return f;
    }
    throw InputError(str(path, ": grid '", name, "' is a ", gridTypeName(*base),
                         " grid; a scalar float grid is needed (density or emission)"));
}

VdbGridSummary summarizeVdb(const std::string& file, const std::string& grid) {
    VdbGridSummary s;
    auto g = readFloatGrid(file, grid, &s.gridName);
    sanitize(*g, str(file, ": grid '", s.gridName, "'"));
    Mat4 i2w = indexToWorldMatrix(*g, Mat4::identity(), file);
    s.voxelSize = Infinity;
    for (int c = 0; c < 3; ++c)
        s.voxelSize = std::min(s.voxelSize, float(std::sqrt(i2w.m[0][c] * i2w.m[0][c] + i2w.m[1][c] * i2w.m[1][c] +
                                                            i2w.m[2][c] * i2w.m[2][c])));
    s.activeVoxels = g->activeVoxelCount();
    double sum = 0;
    size_t n = 0;
    bool any = false;
    for (auto it = g->cbeginValueOn(); it; ++it) {
        float v = *it;
        if (!any) s.minValue = s.maxValue = v;
        any = true;
        s.minValue = std::min(s.minValue, v);
        s.maxValue = std::max(s.maxValue, v);
        double count = double(it.getVoxelCount());
        sum += double(v) * count;
        n += size_t(count);
    }
    s.meanValue = n ? float(sum / double(n)) : 0.f;
    openvdb::CoordBBox ib = g->evalActiveVoxelBoundingBox();
    if (!ib.empty())
        for (int i = 0; i < 8; ++i) {
            openvdb::Vec3d c(i & 1 ? ib.max().x() + 0.5 : ib.min().x() - 0.5, i & 2 ? ib.max().y() + 0.5 : ib.min().y() - 0.5,
                             i & 4 ? ib.max().z() + 0.5 : ib.min().z() - 0.5);
            openvdb::Vec3d w = g->transform().indexToWorld(c);
            s.worldBounds.expand(Vec3(float(w.x()), float(w.y()), float(w.z())));
        }
    return s;
}

std::vector<std::string> listVdbGrids(const std::string& path) {
    auto file = openVdbFile(path);
    std::vector<std::string> out;
    auto grids = file->readAllGridMetadata();
    for (const auto& g : *grids) out.push_back(str(g->getName(), " (", gridTypeName(*g), ")"));
    return out;
}

size_t readEveryGrid(const std::string& path) {
    const auto guard = guardVdbRead(path);
    auto file = openVdbFile(path);
    size_t voxels = 0;
    for (auto name = file->beginName(); name != file->endName(); ++name) {
        openvdb::GridBase::Ptr g;
        try {
            g = file->readGrid(*name);
        } catch (const std::exception& e) {
            throw InputError(str(path, ": grid '", *name, "' could not be read (", printableExcerpt(e.what()), ")"));
        }
        voxels += size_t(g->activeVoxelCount());
    }
    return voxels;
}

}  // namespace vdbmarch
