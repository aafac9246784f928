// Baked caches in the VDB ecosystem (docs/scene-format.md, "The cache file"):
// `vdbmarch bake` writes one fog-volume float grid per SH coefficient named
// Li_sh_<l>_<m> (Li_sh_1_m1 for m = -1), the mean radiance Li, per-grid
// sh_l / sh_m and file metadata that spells out the basis; OpenVDB's
// vdb_print and Blender's reader open it (those tests skip when the tool is
// absent); and a cache of another format version is refused by the command
// naming the file and both versions, with nothing written.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>

#include <openvdb/openvdb.h>

#include "cache/radiance_cache.h"
#include "cache/sh.h"
#include "core/hash.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;
namespace fs = std::filesystem;

// A spot light in an anisotropic fog (g != 0, so all 16 coefficients of order
// 3 are stored); few photons, so a bake takes well under a second.
const char* const kCacheScene = R"({
  "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "resolution": [8, 8]},
  "lights": [{"type": "point", "position": [0, 1.5, 0], "intensity": [5, 5, 5]}],
  "media": [{"name": "fog", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 1, "g": 0.6,
             "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
  "photons": {"count": 8000, "k": 20},
  "cache": {"sh_order": 3},
  "render": {"spp": 1, "max_depth": 2, "seed": 3}
}
)";

class CacheFiles : public BadInput {
protected:
    // Bakes kCacheScene into the work folder; returns the cache's path.
    std::string bakeCache(const std::string& name, bool adaptive = false) {
        scene("cache_scene.json", kCacheScene);
        std::vector<std::string> args{"bake", "cache_scene.json", "-o", name, "--threads", "2"};
        if (adaptive) args.push_back("--adaptive");
        CliResult r = cli(args);
        EXPECT_EQ(r.exitCode, 0) << r.err;
        return work(name);
    }
};

std::map<std::string, openvdb::GridBase::Ptr> readGrids(const std::string& path, openvdb::MetaMap::Ptr* fileMeta) {
    openvdb::initialize();
    openvdb::io::File file(path);
    file.open();
    std::map<std::string, openvdb::GridBase::Ptr> grids;
    openvdb::GridPtrVecPtr all = file.getGrids();  // held: a range-for over *getGrids() would dangle
    for (auto& g : *all) grids[g->getName()] = g;
    if (fileMeta) *fileMeta = file.getMetadata();
    file.close();
    return grids;
}

// The names the documentation promises, built independently of cacheGridName.
std::string expectedName(int l, int m) {
    return "Li_sh_" + std::to_string(l) + "_" + (m < 0 ? "m" + std::to_string(-m) : std::to_string(m));
}

TEST_F(CacheFiles, GridsAreNamedByDegreeAndOrderWithBasisMetadata) {
    const std::string path = bakeCache("cache.vdb");
    openvdb::MetaMap::Ptr meta;
    auto grids = readGrids(path, &meta);
    ASSERT_TRUE(meta);
    const int order = meta->metaValue<int32_t>("sh_order");
    ASSERT_EQ(order, 3) << "g != 0 keeps the requested order";
    // Exactly the coefficient grids and the mean: nothing else, nothing missing.
    EXPECT_EQ(grids.size(), size_t(shCount(order)) + 1);
    for (int l = 0; l <= order; ++l) {
        for (int m = -l; m <= l; ++m) {
            const std::string name = expectedName(l, m);
            SCOPED_TRACE(name);
            ASSERT_TRUE(grids.count(name));
            const openvdb::GridBase& g = *grids[name];
            EXPECT_EQ(g.getGridClass(), openvdb::GRID_FOG_VOLUME);
            EXPECT_TRUE(g.isType<openvdb::FloatGrid>());
            EXPECT_EQ(g.metaValue<int32_t>("sh_l"), l);
            EXPECT_EQ(g.metaValue<int32_t>("sh_m"), m);
            EXPECT_EQ(g.metaValue<int32_t>("sh_coefficient"), l * (l + 1) + m);
            EXPECT_EQ(g.metaValue<int32_t>("vdbmarch_cache_version"), RadianceCache::FormatVersion);
            EXPECT_GT(g.activeVoxelCount(), 0u);
        }
    }
    // The file spells out the basis and the bake.
    for (const char* key : {"sh_basis", "sh_normalisation", "sh_coefficient_order", "sh_grid_names", "Li_quantity",
                            "Li_unit", "Li_reconstruction", "scene_hash", "vdbmarch_version", "description"})
        EXPECT_TRUE(meta->getMetadata<openvdb::StringMetadata>(key)) << key;
    EXPECT_TRUE(meta->metaValue<bool>("sh_condon_shortley_phase"));
    EXPECT_EQ(meta->metaValue<int32_t>("vdbmarch_cache_version"), RadianceCache::FormatVersion);
    EXPECT_EQ(meta->metaValue<int64_t>("photon_paths"), 8000);
    EXPECT_GT(meta->metaValue<int64_t>("photons"), 0);
    EXPECT_EQ(meta->metaValue<int32_t>("k"), 20);
    EXPECT_FLOAT_EQ(meta->metaValue<float>("quality"), 1.f);
    EXPECT_FLOAT_EQ(meta->metaValue<float>("phase_g"), 0.6f);
    EXPECT_CONTAINS(meta->metaValue<std::string>("sh_basis"), "Condon-Shortley");
    EXPECT_CONTAINS(meta->metaValue<std::string>("sh_coefficient_order"), "c = l(l+1) + m");

    // Li is L_i averaged over directions: the integral of sum f_lm Y_lm over
    // the sphere keeps only f_00 Y_00 4 pi, so mean = f_00 Y_00, Y_00 = 1 / (2 sqrt(pi)).
    auto li = openvdb::gridPtrCast<openvdb::FloatGrid>(grids["Li"]);
    auto f00 = openvdb::gridPtrCast<openvdb::FloatGrid>(grids["Li_sh_0_0"]);
    ASSERT_TRUE(li && f00);
    EXPECT_EQ(li->getGridClass(), openvdb::GRID_FOG_VOLUME);
    EXPECT_EQ(li->activeVoxelCount(), f00->activeVoxelCount());
    EXPECT_EQ(li->transform(), f00->transform());
    auto acc = f00->getConstAccessor();
    double y00 = 1 / (2 * std::sqrt(PiD)), maxLi = 0;
    for (auto it = li->cbeginValueOn(); it; ++it) {
        float f;
        ASSERT_TRUE(acc.probeValue(it.getCoord(), f));
        EXPECT_NEAR(*it, f * y00, 1e-6 * std::fabs(f));
        maxLi = std::max(maxLi, double(*it));
    }
    EXPECT_GT(maxLi, 0) << "the light reaches the fog";
}

TEST_F(CacheFiles, AdaptiveCachesNameTheirLevels) {
    const std::string path = bakeCache("adaptive.vdb", /*adaptive=*/true);
    openvdb::MetaMap::Ptr meta;
    auto grids = readGrids(path, &meta);
    const int levels = meta->metaValue<int32_t>("levels"), order = meta->metaValue<int32_t>("sh_order");
    ASSERT_GT(levels, 1);
    EXPECT_EQ(grids.size(), size_t(levels) * size_t(shCount(order) + 1));
    for (int level = 0; level < levels; ++level) {
        const std::string suffix = "_level" + std::to_string(level);
        ASSERT_TRUE(grids.count("Li" + suffix)) << level;
        for (int l = 0; l <= order; ++l)
            for (int m = -l; m <= l; ++m) {
                const std::string name = expectedName(l, m) + suffix;
                ASSERT_TRUE(grids.count(name)) << name;
                EXPECT_EQ(grids[name]->metaValue<int32_t>("level"), level);
                EXPECT_EQ(grids[name]->metaValue<int32_t>("sh_m"), m);
            }
    }
    // And it loads back.
    CliResult r = cli({"inspect", "adaptive.vdb"});
    EXPECT_EQ(r.exitCode, 0) << r.err;
}

TEST_F(CacheFiles, VdbPrintListsTheGridsAndMetadata) {
    if (!onPath("vdb_print")) GTEST_SKIP() << "vdb_print (OpenVDB tools) is not on PATH";
    const std::string path = bakeCache("cache.vdb");
    CliResult r = runShell("vdb_print -l -m " + shellQuote(path), mWork, mRoot.path());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (int l = 0; l <= 3; ++l)
        for (int m = -l; m <= l; ++m) EXPECT_CONTAINS(r.out, "Name: " + expectedName(l, m) + "\n");
    EXPECT_CONTAINS(r.out, "Name: Li\n");
    for (const char* text : {"class: fog volume", "sh_l: 1", "sh_m: -1", "sh_basis: real spherical harmonics",
                             "sh_condon_shortley_phase: true", "sh_coefficient_order: ", "scene_hash: ",
                             "vdbmarch_cache_version: 2", "Li_quantity: in-scattered radiance"})
        EXPECT_CONTAINS(r.out, text);
}

TEST_F(CacheFiles, OpensInBlender) {
    if (!onPath("blender")) GTEST_SKIP() << "blender is not on PATH";
    const std::string path = bakeCache("cache.vdb");
    const std::string script = std::string(VDBMARCH_SOURCE_DIR) + "/tools/blender_open_cache.py";
    // --factory-startup: no user preferences or add-ons, so the test sees Blender itself.
    CliResult r = runShell("blender -b --factory-startup --python " + shellQuote(script) + " -- " + shellQuote(path) +
                               " --expect Li --expect Li_sh_1_m1 --expect Li_sh_3_3",
                           mWork, mRoot.path(), 120);
    ASSERT_EQ(r.exitCode, 0) << r.out << r.err;
    for (int l = 0; l <= 3; ++l)
        for (int m = -l; m <= l; ++m)
            EXPECT_CONTAINS(r.out, "grid " + expectedName(l, m) + " FLOAT channels=1 loaded=True\n");
    EXPECT_CONTAINS(r.out, "grid Li FLOAT channels=1 loaded=True\n");
    EXPECT_CONTAINS(r.out, "blender_open_cache: ok, 17 grids");
}

// Writes `grids` (and file metadata `meta`) with the checksum trailer
// vdbmarch appends, so a load gets past the checksum to the version check.
void writeWithChecksum(const std::string& path, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta) {
    openvdb::io::File(path).write(grids, meta);
    std::string bytes = readBytes(path);
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a64(bytes.data(), bytes.size())));
    writeText(path, bytes + "\nvdbmarch-fnv1a64:" + hex);
}

// A cache as format version 1 wrote it: grids Li_sh00 ... with the cache keys
// on every grid, no mean grid, no file metadata, and the checksum trailer.
void rewriteAsVersion1(const std::string& from, const std::string& to) {
    openvdb::MetaMap::Ptr meta;
    auto grids = readGrids(from, &meta);
    openvdb::GridPtrVec old;
    for (auto& [name, g] : grids) {
        if (!(*g)["sh_coefficient"]) continue;  // the mean grid is new in version 2
        const int c = g->metaValue<int32_t>("sh_coefficient");
        char buf[16];
        std::snprintf(buf, sizeof buf, "Li_sh%02d", c);
        g->setName(buf);
        g->insertMeta("vdbmarch_cache_version", openvdb::Int32Metadata(1));
        old.push_back(g);
    }
    writeWithChecksum(to, old, openvdb::MetaMap());
}

TEST_F(CacheFiles, CacheOfAnotherVersionIsRefusedNamingBothVersionsCli) {
    bakeCache("cache.vdb");
    rewriteAsVersion1(work("cache.vdb"), work("old.vdb"));
    const std::string expected = "reads cache format version " + std::to_string(RadianceCache::FormatVersion);
    CliResult r = cli({"render", "cache_scene.json", "--method", "guided", "--li", "cache", "--cache", "old.vdb", "-o", "out.exr"});
    expectCliError(r, {"old.vdb", "cache format version 1", expected, "bake the cache again"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
    EXPECT_TRUE(tempLeftovers(mWork).empty());
    r = cli({"inspect", "old.vdb", "--direction", "0,0,1", "-o", "li.vdb"});
    expectCliError(r, {"old.vdb", "cache format version 1", expected});
    EXPECT_FALSE(fs::exists(work("li.vdb")));

    // A newer format, as its file metadata would say.
    openvdb::MetaMap::Ptr meta;
    auto grids = readGrids(work("cache.vdb"), &meta);
    meta->insertMeta("vdbmarch_cache_version", openvdb::Int32Metadata(RadianceCache::FormatVersion + 1));
    openvdb::GridPtrVec all;
    for (auto& [name, g] : grids) all.push_back(g);
    writeWithChecksum(work("future.vdb"), all, *meta);
    r = cli({"render", "cache_scene.json", "--method", "guided", "--li", "cache", "--cache", "future.vdb", "-o", "out.exr"});
    expectCliError(r, {"future.vdb", "cache format version " + std::to_string(RadianceCache::FormatVersion + 1),
                       expected});
    EXPECT_FALSE(fs::exists(work("out.exr")));

    // The cache itself renders.
    r = cli({"render", "cache_scene.json", "--method", "guided", "--li", "cache", "--cache", "cache.vdb", "-o", "out.exr"});
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(work("out.exr")));
}

// A cache baked for product sampling (removed) holds direction-lobe grids
// lobe<j>_W, _S (vector) and _N and metadata direction_lobes = true: it
// still loads, says the lobes are ignored, and renders the pixels of the
// same cache without them.
TEST_F(CacheFiles, ACacheWithDirectionLobesStillLoads) {
    bakeCache("cache.vdb");
    openvdb::MetaMap::Ptr meta;
    auto grids = readGrids(work("cache.vdb"), &meta);
    meta->insertMeta("direction_lobes", openvdb::BoolMetadata(true));
    openvdb::GridPtrVec all;
    for (auto& [name, g] : grids) all.push_back(g);
    const auto& mean = grids.at("Li");
    for (int j = 0; j < 4; ++j) {
        const std::string n = "lobe" + std::to_string(j);
        auto w = openvdb::FloatGrid::create(0.f), c = openvdb::FloatGrid::create(0.f);
        auto sum = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.f));
        w->setName(n + "_W");
        c->setName(n + "_N");
        sum->setName(n + "_S");
        for (auto g : {openvdb::GridBase::Ptr(w), openvdb::GridBase::Ptr(c), openvdb::GridBase::Ptr(sum)}) {
            g->setTransform(mean->transform().copy());
            all.push_back(g);
        }
        w->tree().setValueOn(openvdb::Coord(0, 0, 0), 1.f);
    }
    writeWithChecksum(work("lobes.vdb"), all, *meta);
    const std::vector<std::string> guided = {"--method", "guided", "--spp", "4", "--res", "16x16", "--threads", "2",
                                             "--no-denoise"};
    auto render = [&](const std::string& out, const std::string& cache) {
        std::vector<std::string> args{"render", "cache_scene.json", "-o", out, "--cache", cache};
        args.insert(args.end(), guided.begin(), guided.end());
        return cli(args);
    };
    CliResult plain = render("plain.exr", "cache.vdb");
    ASSERT_EQ(plain.exitCode, 0) << plain.err;
    CliResult lobes = render("lobes.exr", "lobes.vdb");
    ASSERT_EQ(lobes.exitCode, 0) << lobes.err;
    EXPECT_CONTAINS(lobes.err, "lobes.vdb");
    EXPECT_CONTAINS(lobes.err, "direction lobes");
    EXPECT_CONTAINS(lobes.err, "ignored");
    CliResult same = cli({"compare", "plain.exr", "lobes.exr", "--identical"});
    EXPECT_EQ(same.exitCode, 0) << same.out << same.err;
}

}  // namespace
}  // namespace vdbmarch
