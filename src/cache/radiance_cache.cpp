// Storage, lookup and VDB input/output of the radiance cache. The only cache
// file that includes OpenVDB.
#include "cache/radiance_cache.h"

#include <array>
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

// `where` names the holder in messages: "the file metadata" or "grid 'x'".
template <typename T>
T metaValue(const openvdb::MetaMap& meta, const std::string& where, const std::string& key, const std::string& file) {
    auto m = meta.getMetadata<openvdb::TypedMetadata<T>>(key);
    if (!m) throw InputError(str(file, ": ", where, " lacks the key '", key, "' (or it has another type): ",
                                 "not a vdbmarch cache"));
    return m->value();
}

constexpr float Y00 = 0.28209479177387814f;  // 1 / (2 sqrt(pi)): Y_00, and f_00 Y_00 = mean of L_i

// The keys load() reads: written on the file and repeated on every
// coefficient grid, so a cache re-saved by a tool that keeps grid metadata
// but not file metadata still loads.
void insertCacheKeys(openvdb::MetaMap& m, const RadianceCache& c) {
    const CacheInfo& info = c.info;
    m.insertMeta("vdbmarch_cache_version", openvdb::Int32Metadata(RadianceCache::FormatVersion));
    m.insertMeta("vdbmarch_version", openvdb::StringMetadata(info.version));
    m.insertMeta("sh_order", openvdb::Int32Metadata(info.shOrder));
    m.insertMeta("sh_order_requested", openvdb::Int32Metadata(info.requestedOrder));
    m.insertMeta("levels", openvdb::Int32Metadata(c.levels));
    m.insertMeta("origin", openvdb::Vec3SMetadata(openvdb::Vec3s(c.origin.x, c.origin.y, c.origin.z)));
    m.insertMeta("phase_g", openvdb::FloatMetadata(info.meanG));
    m.insertMeta("photons", openvdb::Int64Metadata(int64_t(info.photons)));
    m.insertMeta("photon_paths", openvdb::Int64Metadata(int64_t(info.paths)));
    m.insertMeta("photon_batches", openvdb::Int32Metadata(int32_t(info.batches)));
    m.insertMeta("seed", openvdb::Int64Metadata(int64_t(info.seed)));
    m.insertMeta("k", openvdb::Int32Metadata(info.k));
    m.insertMeta("quality", openvdb::FloatMetadata(info.quality));
    m.insertMeta("adaptive", openvdb::BoolMetadata(info.adaptive));
    m.insertMeta("min_cell", openvdb::FloatMetadata(info.minCell));
    m.insertMeta("scene_hash", openvdb::StringMetadata(info.sceneHash));
}

// What the numbers mean, for other tools (file metadata only); the basis
// is the one of cache/sh.h, whose tests check these statements.
void insertBasisKeys(openvdb::MetaMap& m) {
    static const char* const kText[][2] = {
        {"description",
         "vdbmarch radiance cache: spherical-harmonics coefficients of the in-scattered radiance L_i at cell "
         "centres (one float grid per coefficient and level), and L_i averaged over directions (grid Li)"},
        {"Li_quantity",
         "in-scattered radiance L_i(x, wo) = integral over w of p(w . wo) L(x, w) dw (eq. 3): incident radiance "
         "L over the travel direction w of the arriving light, convolved with the phase function p (eq. 27), "
         "so the phase function is already applied; wo is the direction the scattered light travels in "
         "(towards a viewer at e: wo = normalize(e - x)). Estimated from the volume photon map; scalar: the "
         "mean of the RGB channels. The radiance scattered towards wo per unit length is sigma_s(x) L_i(x, wo)"},
        {"Li_unit", "W m^-2 sr^-1 (radiance in the scene's units)"},
        {"Li_reconstruction",
         "L_i(x, wo) = sum over l = 0..sh_order, m = -l..l of Li_sh_<l>_<m>(x) Y_lm(wo); "
         "mean over directions = Li_sh_0_0(x) Y_00 = grid Li"},
        {"sh_basis",
         "real spherical harmonics, orthonormal on the unit sphere, Condon-Shortley phase included, z the polar "
         "axis (theta = acos z, phi = atan2(y, x)): Y_l0 = K_l0 P_l^0(cos theta); "
         "Y_lm = sqrt(2) K_lm P_l^m(cos theta) cos(m phi) for m > 0; "
         "Y_lm = sqrt(2) K_l|m| P_l^|m|(cos theta) sin(|m| phi) for m < 0; "
         "K_lm = sqrt((2l+1)/(4 pi) (l-|m|)!/(l+|m|)!); P_l^m with the (-1)^m phase. "
         "So Y_00 = 0.282095, Y_1,-1 = -0.488603 y, Y_1,0 = 0.488603 z, Y_1,1 = -0.488603 x "
         "(Sloan, Stupid Spherical Harmonics Tricks, 2008)"},
        {"sh_normalisation",
         "orthonormal: integral over the unit sphere of Y_lm Y_l'm' = 1 if (l, m) = (l', m') else 0"},
        {"sh_coefficient_order",
         "band by band, c = l(l+1) + m for l = 0..sh_order, m = -l..l (metadata sh_coefficient of each grid)"},
        {"sh_grid_names",
         "Li_sh_<l>_<m>, a negative m spelt m<|m|> (Li_sh_1_m1 is l = 1, m = -1); adaptive caches add "
         "_level<n> (level 0 the coarsest, each level halves the cell), and Li becomes Li_level<n>"},
    };
    for (const auto& [key, text] : kText) m.insertMeta(key, openvdb::StringMetadata(text));
    m.insertMeta("sh_condon_shortley_phase", openvdb::BoolMetadata(true));
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
    const int l = shBand(coefficient), m = coefficient - l * (l + 1);
    std::string name = str("Li_sh_", l, "_", m < 0 ? "m" : "", std::abs(m));
    if (levels > 1) name += str("_level", level);
    return name;
}

std::string cacheMeanGridName(int level, int levels) {
    return levels > 1 ? str("Li_level", level) : std::string("Li");
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
    size_t bytes = coefficients.size() * sizeof(float) + cells.size() * sizeof(CacheCell);
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
    openvdb::MetaMap fileMeta;
    insertCacheKeys(fileMeta, *this);
    insertBasisKeys(fileMeta);
    fileMeta.insertMeta("cell_size", openvdb::FloatMetadata(baseCell));
    openvdb::GridPtrVec grids;
    std::vector<std::vector<openvdb::FloatGrid::Ptr>> perLevel{size_t(levels)};
    std::vector<openvdb::FloatGrid::Ptr> means;
    for (int l = 0; l < levels; ++l) {
        auto xform = levelTransform(origin, cellSize(l));
        for (int c = 0; c < count; ++c) {
            auto g = openvdb::FloatGrid::create(0.f);
            g->setName(cacheGridName(c, l, levels));
            g->setTransform(xform);
            g->setGridClass(openvdb::GRID_FOG_VOLUME);
            insertCacheKeys(*g, *this);
            g->insertMeta("cell_size", openvdb::FloatMetadata(cellSize(l)));
            g->insertMeta("level", openvdb::Int32Metadata(l));
            g->insertMeta("sh_coefficient", openvdb::Int32Metadata(c));
            const int band = shBand(c);
            g->insertMeta("sh_l", openvdb::Int32Metadata(band));
            g->insertMeta("sh_m", openvdb::Int32Metadata(c - band * (band + 1)));
            g->insertMeta("description", openvdb::StringMetadata(
                str("vdbmarch radiance cache: real SH coefficient f_lm (l = ", band, ", m = ", c - band * (band + 1),
                    ") of the in-scattered radiance L_i (W m^-2 sr^-1); basis in the file metadata sh_*")));
            perLevel[size_t(l)].push_back(g);
            grids.push_back(g);
        }
        // A scalar a viewer can show as is, without the SH basis.
        auto mean = openvdb::FloatGrid::create(0.f);
        mean->setName(cacheMeanGridName(l, levels));
        mean->setTransform(xform);
        mean->setGridClass(openvdb::GRID_FOG_VOLUME);
        mean->insertMeta("level", openvdb::Int32Metadata(l));
        mean->insertMeta("cell_size", openvdb::FloatMetadata(cellSize(l)));
        mean->insertMeta("description", openvdb::StringMetadata(
            "vdbmarch radiance cache: L_i averaged over directions, Li_sh_0_0 * Y_00 (W m^-2 sr^-1); "
            "not read back by vdbmarch"));
        means.push_back(mean);
        grids.push_back(mean);
    }
    std::vector<std::vector<openvdb::FloatGrid::Accessor>> acc{size_t(levels)};
    std::vector<openvdb::FloatGrid::Accessor> meanAcc;
    for (int l = 0; l < levels; ++l) {
        for (auto& g : perLevel[size_t(l)]) acc[size_t(l)].push_back(g->getAccessor());
        meanAcc.push_back(means[size_t(l)]->getAccessor());
    }
    for (size_t i = 0; i < cells.size(); ++i) {
        const CacheCell& cell = cells[i];
        const float* f = cellCoefficients(i);
        const openvdb::Coord xyz(cell.i, cell.j, cell.k);
        for (int c = 0; c < count; ++c) acc[size_t(cell.level)][size_t(c)].setValueOn(xyz, f[c]);
        meanAcc[size_t(cell.level)].setValueOn(xyz, f[0] * Y00);
    }
    AtomicFile out(path);
    try {
        openvdb::io::File file(out.tempPath());
        file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
        file.write(grids, fileMeta);
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
    openvdb::MetaMap::Ptr fileMeta;
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        grids = file.getGrids();
        fileMeta = file.getMetadata();
        file.close();
    } catch (const std::exception& e) {
        throw InputError(str(path, ": not a readable VDB cache file (", printableExcerpt(e.what()), ")"));
    }
    // The cache keys: on the file, or (re-saved by a tool that keeps only
    // grid metadata) on the level-0 grid of coefficient 0, which repeats them.
    const std::string firstName = cacheGridName(0, 0, 1), firstLevelName = cacheGridName(0, 0, 2);
    const openvdb::MetaMap* meta = nullptr;
    std::string where;
    if (fileMeta && (*fileMeta)["vdbmarch_cache_version"]) {
        meta = fileMeta.get();
        where = "the file metadata";
    }
    for (auto& g : *grids)
        if (!meta && g && (g->getName() == firstName || g->getName() == firstLevelName)) {
            meta = g.get();
            where = str("grid '", g->getName(), "'");
        }
    // Another format's layout (version 1 named its grids Li_sh00, ...): any
    // grid's version says which, so the message can name it.
    for (auto& g : *grids)
        if (!meta && g && (*g)["vdbmarch_cache_version"]) {
            meta = g.get();
            where = str("grid '", g->getName(), "'");
        }
    if (!meta)
        throw InputError(str(path, ": no metadata 'vdbmarch_cache_version' and no grid '", firstName,
                             "': not a vdbmarch cache"));
    const int version = metaValue<int32_t>(*meta, where, "vdbmarch_cache_version", path);
    if (version != FormatVersion) {
        auto writer = meta->getMetadata<openvdb::StringMetadata>("vdbmarch_version");
        throw InputError(str(path, ": cache format version ", version,
                             writer ? str(" (written by vdbmarch ", writer->value(), ")") : std::string(),
                             "; this vdbmarch (", VDBMARCH_VERSION, ") reads cache format version ", FormatVersion,
                             " only: bake the cache again (vdbmarch bake SCENE -o ", path, ")"));
    }
    RadianceCache c;
    auto get = [&](auto tag, const char* key) { return metaValue<decltype(tag)>(*meta, where, key, path); };
    c.info.version = get(std::string(), "vdbmarch_version");
    c.info.shOrder = get(int32_t(), "sh_order");
    c.info.requestedOrder = get(int32_t(), "sh_order_requested");
    c.levels = get(int32_t(), "levels");
    c.baseCell = get(float(), "cell_size");
    openvdb::Vec3s o = get(openvdb::Vec3s(), "origin");
    c.origin = Vec3(o.x(), o.y(), o.z());
    c.info.meanG = get(float(), "phase_g");
    c.info.photons = uint64_t(get(int64_t(), "photons"));
    c.info.paths = uint64_t(get(int64_t(), "photon_paths"));
    c.info.seed = uint64_t(get(int64_t(), "seed"));
    c.info.batches = uint32_t(std::max(1, get(int32_t(), "photon_batches")));
    c.info.k = get(int32_t(), "k");
    c.info.quality = get(float(), "quality");
    c.info.adaptive = get(bool(), "adaptive");
    c.info.minCell = get(float(), "min_cell");
    c.info.sceneHash = get(std::string(), "scene_hash");
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
                                         "' lacks the cell ", xyz, " that '", coeffGrids[0]->getName(), "' has"));
                if (!std::isfinite(v))
                    throw InputError(str(path, ": cache grid '", coeffGrids[size_t(k)]->getName(), "' holds ", v,
                                         " at ", xyz));
                c.coefficients.push_back(v);
            }
        }
    }
    // Caches baked for product sampling (removed) also hold direction-lobe
    // grids: nothing reads them now.
    auto lobesKey = meta->getMetadata<openvdb::BoolMetadata>("direction_lobes");
    if (lobesKey && lobesKey->value())
        warn(str(path, ": the cache's direction lobes (grids lobe<j>_W, _S, _N) are ignored: product sampling was "
                       "removed; the SH coefficients load as usual"));
    c.finalize();
    return c;
}

}  // namespace vdbmarch
