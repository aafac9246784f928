// Storage, lookup and VDB input/output of the radiance cache. The only cache
// file that includes OpenVDB.
#include "cache/radiance_cache.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

#include <openvdb/openvdb.h>

#include "cache/sh.h"
#include "core/hash.h"
#include "core/error.h"
#include "core/atomic_file.h"
#include "volume/medium.h"

namespace vdbmarch {

namespace {

// VDB voxel (i, j, k) of level `level` has its centre at the cell centre.
openvdb::math::Transform::Ptr levelTransform(const Vec3& origin, float h) {
    auto t = openvdb::math::Transform::createLinearTransform(double(h));
    t->postTranslate(openvdb::Vec3d(origin.x + 0.5 * h, origin.y + 0.5 * h, origin.z + 0.5 * h));
    return t;
}

template <typename T>
T metaValue(const openvdb::GridBase& g, const std::string& key, const std::string& file) {
    auto m = g.getMetadata<openvdb::TypedMetadata<T>>(key);
    if (!m) throw InputError(str(file, ": grid '", g.getName(), "' has no metadata '", key, "': not a vdbmarch cache"));
    return m->value();
}

// A trailer after the VDB data (OpenVDB readers ignore trailing bytes): a tag
// and the FNV-1a hash of everything before it, so a damaged file is refused
// before OpenVDB parses it (random damage can make that parse very slow).
const std::string ChecksumTag = "\nvdbmarch-fnv1a64:";
constexpr size_t ChecksumDigits = 16;

std::string hex64(uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

void appendChecksum(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.eof() && in.fail()) throw IoError(str(path, ": cannot read back the cache to checksum it"));
    std::ofstream out(path, std::ios::binary | std::ios::app);
    out << ChecksumTag << hex64(fnv1a64(bytes.data(), bytes.size()));
    if (!out.flush()) throw IoError(str(path, ": cannot write the cache checksum: ", std::strerror(errno)));
}

// True when the file ends with a matching trailer; false when it has none
// (re-saved by another VDB tool); throws when the trailer does not match.
bool verifyChecksum(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t trailer = ChecksumTag.size() + ChecksumDigits;
    if (bytes.size() < trailer || bytes.compare(bytes.size() - trailer, ChecksumTag.size(), ChecksumTag) != 0)
        return false;
    std::string stored = bytes.substr(bytes.size() - ChecksumDigits);
    if (stored != hex64(fnv1a64(bytes.data(), bytes.size() - trailer)))
        throw InputError(str(path, ": checksum mismatch: the cache file is damaged; bake it again"));
    return true;
}

}  // namespace

struct RadianceCache::Index {
    std::vector<openvdb::Int32Tree::Ptr> levels;  // value: cell index + 1
};

struct RadianceCache::Query::Accessors {
    std::vector<openvdb::tree::ValueAccessor<const openvdb::Int32Tree>> levels;
};

RadianceCache::RadianceCache() = default;
RadianceCache::~RadianceCache() = default;
RadianceCache::RadianceCache(RadianceCache&&) noexcept = default;
RadianceCache& RadianceCache::operator=(RadianceCache&&) noexcept = default;

std::string cacheGridName(int coefficient, int level, int levels) {
    std::string name = str("Li_sh", coefficient < 10 ? "0" : "", coefficient);
    if (levels > 1) name += str("_level", level);
    return name;
}

void RadianceCache::finalize() {
    mIndex = std::make_unique<Index>();
    for (int l = 0; l < levels; ++l) mIndex->levels.push_back(std::make_shared<openvdb::Int32Tree>(0));
    std::vector<openvdb::tree::ValueAccessor<openvdb::Int32Tree>> acc;
    for (auto& t : mIndex->levels) acc.emplace_back(*t);
    for (size_t c = 0; c < cells.size(); ++c) {
        const CacheCell& cell = cells[c];
        acc[size_t(cell.level)].setValue(openvdb::Coord(cell.i, cell.j, cell.k), int32_t(c + 1));
    }
}

size_t RadianceCache::cellsAtLevel(int level) const {
    size_t n = 0;
    for (const auto& c : cells) n += c.level == level;
    return n;
}

size_t RadianceCache::memoryBytes() const {
    size_t bytes = (coefficients.size() + incident.size()) * sizeof(float) + cells.size() * sizeof(CacheCell);
    if (mIndex)
        for (const auto& t : mIndex->levels) bytes += t->memUsage();
    return bytes;
}

RadianceCache::Query::Query(const RadianceCache& c) : mCache(c), mAcc(std::make_unique<Accessors>()) {
    if (!c.mIndex) throw std::logic_error("RadianceCache::finalize() was not called");
    for (const auto& t : c.mIndex->levels) mAcc->levels.emplace_back(*t);
}

RadianceCache::Query::~Query() = default;

int64_t RadianceCache::Query::find(const Vec3& x) {
    const Vec3 q = (x - mCache.origin) / mCache.baseCell;
    for (int l = mCache.levels - 1; l >= 0; --l) {
        float s = float(1 << l);
        float fx = std::floor(q.x * s), fy = std::floor(q.y * s), fz = std::floor(q.z * s);
        if (!(std::fabs(fx) < 2e9f && std::fabs(fy) < 2e9f && std::fabs(fz) < 2e9f)) return -1;
        int32_t v = mAcc->levels[size_t(l)].getValue(openvdb::Coord(int(fx), int(fy), int(fz)));
        if (v > 0) return int64_t(v) - 1;
    }
    return -1;
}

void RadianceCache::save(const std::string& path) const {
    initOpenVdb();
    const int count = coefficientCount();
    openvdb::GridPtrVec grids;
    std::vector<std::vector<openvdb::FloatGrid::Ptr>> perLevel{size_t(levels)};
    for (int l = 0; l < levels; ++l) {
        auto xform = levelTransform(origin, cellSize(l));
        for (int c = 0; c < count; ++c) {
            auto g = openvdb::FloatGrid::create(0.f);
            g->setName(cacheGridName(c, l, levels));
            g->setTransform(xform);
            g->setGridClass(openvdb::GRID_FOG_VOLUME);
            g->insertMeta("vdbmarch_cache_version", openvdb::Int32Metadata(FormatVersion));
            g->insertMeta("vdbmarch_version", openvdb::StringMetadata(info.version));
            g->insertMeta("sh_order", openvdb::Int32Metadata(info.shOrder));
            g->insertMeta("sh_order_requested", openvdb::Int32Metadata(info.requestedOrder));
            g->insertMeta("sh_coefficient", openvdb::Int32Metadata(c));
            int band = int(std::sqrt(float(c)));
            g->insertMeta("sh_l", openvdb::Int32Metadata(band));
            g->insertMeta("sh_m", openvdb::Int32Metadata(c - band * (band + 1)));
            g->insertMeta("level", openvdb::Int32Metadata(l));
            g->insertMeta("levels", openvdb::Int32Metadata(levels));
            g->insertMeta("cell_size", openvdb::FloatMetadata(cellSize(l)));
            g->insertMeta("origin", openvdb::Vec3SMetadata(openvdb::Vec3s(origin.x, origin.y, origin.z)));
            g->insertMeta("phase_g", openvdb::FloatMetadata(info.meanG));
            g->insertMeta("photons", openvdb::Int64Metadata(int64_t(info.photons)));
            g->insertMeta("photon_paths", openvdb::Int64Metadata(int64_t(info.paths)));
            g->insertMeta("photon_batches", openvdb::Int32Metadata(int32_t(info.batches)));
            g->insertMeta("seed", openvdb::Int64Metadata(int64_t(info.seed)));
            g->insertMeta("k", openvdb::Int32Metadata(info.k));
            g->insertMeta("quality", openvdb::FloatMetadata(info.quality));
            g->insertMeta("adaptive", openvdb::BoolMetadata(info.adaptive));
            g->insertMeta("min_cell", openvdb::FloatMetadata(info.minCell));
            g->insertMeta("scene_hash", openvdb::StringMetadata(info.sceneHash));
            g->insertMeta("description", openvdb::StringMetadata(
                "vdbmarch in-scattered radiance cache: real SH coefficient f_lm of L_i (W/m^2/sr) at cell centres"));
            perLevel[size_t(l)].push_back(g);
            grids.push_back(g);
        }
    }
    std::vector<std::vector<openvdb::FloatGrid::Accessor>> acc{size_t(levels)};
    for (int l = 0; l < levels; ++l)
        for (auto& g : perLevel[size_t(l)]) acc[size_t(l)].push_back(g->getAccessor());
    for (size_t i = 0; i < cells.size(); ++i) {
        const CacheCell& cell = cells[i];
        const float* f = cellCoefficients(i);
        for (int c = 0; c < count; ++c)
            acc[size_t(cell.level)][size_t(c)].setValueOn(openvdb::Coord(cell.i, cell.j, cell.k), f[c]);
    }
    AtomicFile out(path);
    try {
        openvdb::io::File file(out.tempPath());
        file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
        file.write(grids);
        file.close();
    } catch (const openvdb::Exception& e) {
        throw IoError(str(path, ": cannot write the cache: ", e.what()));
    }
    appendChecksum(out.tempPath());
    out.commit();
}

void RadianceCache::saveDirectional(const std::string& path, const Vec3& wo) const {
    initOpenVdb();
    const int count = coefficientCount();
    std::vector<float> Y(size_t(shCount(info.shOrder)));
    evalSh(info.shOrder, wo, Y.data());
    openvdb::GridPtrVec grids;
    std::vector<openvdb::FloatGrid::Accessor> acc;
    for (int l = 0; l < levels; ++l) {
        auto g = openvdb::FloatGrid::create(0.f);
        g->setName(levels > 1 ? str("Li_level", l) : std::string("Li"));
        g->setTransform(levelTransform(origin, cellSize(l)));
        g->setGridClass(openvdb::GRID_FOG_VOLUME);
        g->insertMeta("direction", openvdb::Vec3SMetadata(openvdb::Vec3s(wo.x, wo.y, wo.z)));
        g->insertMeta("description", openvdb::StringMetadata(
            "vdbmarch cached in-scattered radiance L_i(x, wo) towards `direction` (clamped at 0)"));
        grids.push_back(g);
        acc.push_back(g->getAccessor());
    }
    for (size_t i = 0; i < cells.size(); ++i) {
        const CacheCell& cell = cells[i];
        float v = evalShNonNegative(count, cellCoefficients(i), Y.data());
        acc[size_t(cell.level)].setValueOn(openvdb::Coord(cell.i, cell.j, cell.k), v);
    }
    AtomicFile out(path);
    try {
        openvdb::io::File file(out.tempPath());
        file.write(grids);
        file.close();
    } catch (const openvdb::Exception& e) {
        throw IoError(str(path, ": cannot write: ", e.what()));
    }
    out.commit();
}

RadianceCache RadianceCache::load(const std::string& path) {
    initOpenVdb();
    {
        std::ifstream probe(path, std::ios::binary);
        if (!probe) throw IoError(str(path, ": cannot open cache file: ", std::strerror(errno)));
    }
    if (!verifyChecksum(path))
        warn(str(path, ": no vdbmarch checksum (the file was truncated, or re-saved by another VDB tool): "
                       "loading it unverified"));
    openvdb::GridPtrVecPtr grids;
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        grids = file.getGrids();
        file.close();
    } catch (const std::exception& e) {
        throw InputError(str(path, ": not a readable VDB cache file (", e.what(), ")"));
    }
    // Level 0, coefficient 0 carries the metadata every grid repeats.
    openvdb::FloatGrid::Ptr first;
    for (auto& g : *grids)
        if (g && (g->getName() == "Li_sh00" || g->getName() == "Li_sh00_level0"))
            first = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    if (!first) throw InputError(str(path, ": no grid 'Li_sh00' or 'Li_sh00_level0': not a vdbmarch cache"));
    RadianceCache c;
    int version = metaValue<int32_t>(*first, "vdbmarch_cache_version", path);
    if (version != FormatVersion)
        throw InputError(str(path, ": cache format version ", version, " is not the supported version ", FormatVersion,
                             "; bake it again"));
    c.info.version = metaValue<std::string>(*first, "vdbmarch_version", path);
    c.info.shOrder = metaValue<int32_t>(*first, "sh_order", path);
    c.info.requestedOrder = metaValue<int32_t>(*first, "sh_order_requested", path);
    c.levels = metaValue<int32_t>(*first, "levels", path);
    c.baseCell = metaValue<float>(*first, "cell_size", path);
    openvdb::Vec3s o = metaValue<openvdb::Vec3s>(*first, "origin", path);
    c.origin = Vec3(o.x(), o.y(), o.z());
    c.info.meanG = metaValue<float>(*first, "phase_g", path);
    c.info.photons = uint64_t(metaValue<int64_t>(*first, "photons", path));
    c.info.paths = uint64_t(metaValue<int64_t>(*first, "photon_paths", path));
    c.info.seed = uint64_t(metaValue<int64_t>(*first, "seed", path));
    // Caches baked before progressive refinement hold one batch.
    if ((*first)["photon_batches"])
        c.info.batches = uint32_t(std::max(1, metaValue<int32_t>(*first, "photon_batches", path)));
    c.info.k = metaValue<int32_t>(*first, "k", path);
    c.info.quality = metaValue<float>(*first, "quality", path);
    c.info.adaptive = metaValue<bool>(*first, "adaptive", path);
    c.info.minCell = metaValue<float>(*first, "min_cell", path);
    c.info.sceneHash = metaValue<std::string>(*first, "scene_hash", path);
    if (c.info.shOrder < 0 || c.info.shOrder > MaxShOrder)
        throw InputError(str(path, ": metadata sh_order = ", c.info.shOrder, " is outside [0, ", MaxShOrder, "]"));
    if (c.levels < 1 || c.levels > 16)
        throw InputError(str(path, ": metadata levels = ", c.levels, " is outside [1, 16]"));
    if (!(c.baseCell > 0) || !std::isfinite(c.baseCell))
        throw InputError(str(path, ": metadata cell_size = ", c.baseCell, " is not a positive number"));
    const int count = c.coefficientCount();
    for (int l = 0; l < c.levels; ++l) {
        std::vector<openvdb::FloatGrid::Ptr> coeffGrids;
        for (int k = 0; k < count; ++k) {
            std::string name = cacheGridName(k, l, c.levels);
            openvdb::FloatGrid::Ptr g;
            for (auto& gg : *grids)
                if (gg && gg->getName() == name) g = openvdb::gridPtrCast<openvdb::FloatGrid>(gg);
            if (!g) throw InputError(str(path, ": cache grid '", name, "' is missing or not a float grid"));
            coeffGrids.push_back(g);
        }
        std::vector<openvdb::FloatGrid::ConstAccessor> acc;
        for (auto& g : coeffGrids) acc.push_back(g->getConstAccessor());
        for (auto it = coeffGrids[0]->cbeginValueOn(); it; ++it) {
            if (!it.isVoxelValue()) throw InputError(str(path, ": cache grid '", coeffGrids[0]->getName(), "' has tiles"));
            openvdb::Coord xyz = it.getCoord();
            c.cells.push_back({l, xyz.x(), xyz.y(), xyz.z()});
            for (int k = 0; k < count; ++k) {
                float v;
                if (!acc[size_t(k)].probeValue(xyz, v))
                    throw InputError(str(path, ": cache grid '", coeffGrids[size_t(k)]->getName(),
                                         "' lacks the cell ", xyz, " that 'Li_sh00' has"));
                if (!std::isfinite(v))
                    throw InputError(str(path, ": cache grid '", coeffGrids[size_t(k)]->getName(), "' holds ", v,
                                         " at ", xyz));
                c.coefficients.push_back(v);
            }
        }
    }
    c.finalize();
    return c;
}

}  // namespace vdbmarch
