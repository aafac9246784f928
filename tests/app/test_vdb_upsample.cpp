// vdb_upsample (tools/vdb_upsample.cpp, issue 24) on the 1/16 Disney cloud at
// factor 2: every stored value is OpenVDB's BoxSampler of the source at the
// mapped point, the active voxels are exactly those where it is above 0, the
// world bounds agree, --detail writes the same file for 1 and 2 threads, and
// bad input fails naming the file and grid, leaving no OUT behind.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/tools/Interpolation.h>

#include "support/support.h"
#include "volume/medium.h"

namespace vdbmarch {
namespace {

namespace fs = std::filesystem;
using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::Vec3d;
using test::assetPath;
using test::CliResult;
using test::shellQuote;
using test::TempDir;

constexpr int kFactor = 2;

// Runs vdb_upsample with `args` in `dir`.
CliResult upsample(const TempDir& dir, const std::vector<std::string>& args) {
    std::string cmd = shellQuote(VDBMARCH_UPSAMPLE_BINARY);
    for (const auto& a : args) cmd += " " + shellQuote(a);
    fs::create_directories(dir / "capture");
    return test::runShell(cmd, dir.path(), dir / "capture", 120);
}

FloatGrid::Ptr readDensity(const std::string& file) {
    initOpenVdb();
    openvdb::io::File f(file);
    f.open();
    auto grid = openvdb::gridPtrCast<FloatGrid>(f.readGrid("density"));
    f.close();
    return grid;
}

// The source index point that output index point q samples.
Vec3d sourcePoint(const Coord& q, int n) {
    return Vec3d((q.x() + 0.5) / n - 0.5, (q.y() + 0.5) / n - 0.5, (q.z() + 0.5) / n - 0.5);
}

class VdbUpsample : public ::testing::Test {
protected:
    void SetUp() override {
        if (!fs::exists(source())) GTEST_SKIP() << "asset not present: " << source();
    }
    static std::string source() { return assetPath("wdas_cloud_sixteenth.vdb"); }

    // The source and its factor-2 upsampling without detail, made once.
    struct Pair {
        FloatGrid::Ptr src, out;
    };
    static const Pair& plain() {
        static TempDir dir("upsample");
        static const Pair pair = [] {
            const CliResult r = upsample(dir, {source(), "x2.vdb", "--factor", std::to_string(kFactor)});
            EXPECT_EQ(r.exitCode, 0) << r.out << r.err;
            EXPECT_NE(r.out.find("active voxels"), std::string::npos) << r.out;
            EXPECT_NE(r.out.find("memUsage"), std::string::npos) << r.out;
            return Pair{readDensity(source()), r.exitCode == 0 ? readDensity(dir / "x2.vdb") : nullptr};
        }();
        return pair;
    }
};

// Every active output voxel (tiles voxel by voxel) holds exactly
// BoxSampler::sample of the source at (q + 0.5) / 2 - 0.5, above 0.
TEST_F(VdbUpsample, ValuesAreTheSourcesBoxSamplerAtTheMappedPoint) {
    const auto& [src, out] = plain();
    ASSERT_TRUE(out);
    auto acc = src->getConstAccessor();
    size_t checked = 0, wrong = 0;
    for (auto it = out->cbeginValueOn(); it; ++it) {
        const openvdb::CoordBBox box = it.getBoundingBox();
        for (auto q = box.begin(); q; ++q) {
            const float expected = openvdb::tools::BoxSampler::sample(acc, sourcePoint(*q, kFactor));
            ++checked;
            if (*it == expected && *it > 0.f) continue;
            if (++wrong <= 5) ADD_FAILURE() << "at " << *q << ": " << *it << ", BoxSampler " << expected;
        }
    }
    EXPECT_EQ(wrong, 0u);
    EXPECT_EQ(checked, out->activeVoxelCount());
    // The output index point of the source's voxel (0,0,0) lands on its world point.
    const Vec3d a = out->indexToWorld(Vec3d(0.5 * (kFactor - 1))), b = src->indexToWorld(Vec3d(0.0));
    EXPECT_LT((a - b).length(), 1e-9);
}

// Output voxel q lies in source cell floor(p(q)), and each cell holds N^3 of
// them. BoxSampler is above 0 only in cells with a corner above 0 (the
// values are >= 0), and at even N everywhere inside such a cell (no sample
// point is on the lattice, so all eight weights are > 0). So the active count
// is exactly N^3 x (cells with a positive corner): between N^3 and 8 N^3
// times the positive source voxels, near N^3 times for a large cloud.
TEST_F(VdbUpsample, ActiveVoxelsAreTheCellsWithAPositiveCorner) {
    const auto& [src, out] = plain();
    ASSERT_TRUE(out);
    openvdb::MaskTree cells;
    openvdb::Index64 positive = 0;
    for (auto it = src->tree().cbeginValueAll(); it; ++it) {
        if (!(*it > 0.f)) continue;
        const openvdb::CoordBBox box = it.getBoundingBox();
        positive += box.volume();
        for (auto c = box.begin(); c; ++c)
            for (int d = 0; d < 8; ++d) cells.setValueOn((*c).offsetBy(-(d & 1), -((d >> 1) & 1), -(d >> 2)));
    }
    const openvdb::Index64 n3 = kFactor * kFactor * kFactor;
    ASSERT_GT(positive, 100000u);
    EXPECT_EQ(out->activeVoxelCount(), n3 * cells.activeVoxelCount());
    EXPECT_GE(out->activeVoxelCount(), n3 * positive);
    // Measured 1.124 (363,037 positive voxels, 408,100 cells): the shell around the cloud is thin.
    EXPECT_LT(double(out->activeVoxelCount()), 1.25 * double(n3 * positive));
}

// The world box of the active output voxels and that of the source's positive
// voxels: the output reaches half a source voxel further on every side.
TEST_F(VdbUpsample, WorldBoundsAgreeWithinOneSourceVoxel) {
    const auto& [src, out] = plain();
    ASSERT_TRUE(out);
    openvdb::CoordBBox positive;
    for (auto it = src->tree().cbeginValueAll(); it; ++it)
        if (*it > 0.f) positive.expand(it.getBoundingBox());
    const openvdb::CoordBBox active = out->evalActiveVoxelBoundingBox();
    const Vec3d srcLo = src->indexToWorld(positive.min().asVec3d() - Vec3d(0.5));
    const Vec3d srcHi = src->indexToWorld(positive.max().asVec3d() + Vec3d(0.5));
    const Vec3d outLo = out->indexToWorld(active.min().asVec3d() - Vec3d(0.5));
    const Vec3d outHi = out->indexToWorld(active.max().asVec3d() + Vec3d(0.5));
    const double h = src->voxelSize().x();
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(outLo[a], srcLo[a] - 0.5 * h, 1e-6) << a;
        EXPECT_NEAR(outHi[a], srcHi[a] + 0.5 * h, 1e-6) << a;
        EXPECT_LE(std::abs(outLo[a] - srcLo[a]), h) << a;
        EXPECT_LE(std::abs(outHi[a] - srcHi[a]), h) << a;
    }
    EXPECT_NEAR(out->voxelSize().x(), h / kFactor, 1e-12);
}

// With --detail the files of 1 and 2 threads are the same but for the random
// UUID io::File stamps at bytes [21, 57) of the header; another seed differs.
TEST_F(VdbUpsample, DetailIsTheSameForOneAndTwoThreads) {
    TempDir dir("upsample");
    auto run = [&](const std::string& file, const std::string& threads, const std::string& seed) {
        const CliResult r = upsample(dir, {source(), file, "--factor", "2", "--detail", "0.6", "--seed", seed,
                                           "--threads", threads});
        EXPECT_EQ(r.exitCode, 0) << r.out << r.err;
        return test::readBytes(dir / file);
    };
    const std::string one = run("t1.vdb", "1", "7"), two = run("t2.vdb", "2", "7"), other = run("s8.vdb", "2", "8");
    ASSERT_GT(one.size(), 1000000u);
    ASSERT_EQ(one.size(), two.size());
    constexpr size_t kUuid = 21, kUuidEnd = kUuid + 36;
    EXPECT_EQ(one[kUuid + 8], '-');  // the UUID's first dash: its place is right
    EXPECT_NE(one.substr(kUuid, 36), two.substr(kUuid, 36));
    EXPECT_EQ(one.substr(0, kUuid), two.substr(0, kUuid));
    EXPECT_TRUE(one.compare(kUuidEnd, std::string::npos, two, kUuidEnd, std::string::npos) == 0);
    EXPECT_FALSE(one.size() == other.size() &&
                 one.compare(kUuidEnd, std::string::npos, other, kUuidEnd, std::string::npos) == 0);
    // Detail changes values but not which voxels are active (AMP < 1).
    auto detailed = readDensity(dir / "t1.vdb");
    const auto& plainOut = plain().out;
    ASSERT_TRUE(plainOut);
    EXPECT_EQ(detailed->activeVoxelCount(), plainOut->activeVoxelCount());
}

// Failures exit 1 (usage 2) with a message naming the file or grid, and never
// leave OUT or a temporary behind.
TEST_F(VdbUpsample, BadInputIsRefusedByName) {
    TempDir dir("upsample");
    test::writeVdbFixtures(dir.path());
    struct Case {
        std::vector<std::string> args;
        int exitCode;
        std::vector<std::string> needles;
    };
    const std::string missing = dir / "missing.vdb";
    const std::vector<Case> cases = {
        {{missing, "out.vdb", "--factor", "2"}, 1, {missing, "no such file"}},
        {{source(), "out.vdb", "--factor", "2", "--grid", "smoke"}, 1, {source(), "'smoke'", "density"}},
        {{"grids.vdb", "out.vdb", "--factor", "2", "--grid", "vel"}, 1, {"grids.vdb", "'vel'", "vec3s", "float"}},
        {{"not_a_vdb.vdb", "out.vdb", "--factor", "2"}, 1, {"not_a_vdb.vdb"}},
        {{source(), "out.vdb", "--factor", "2", "--threshold", "-1"}, 1, {source(), "'density'", "--threshold"}},
        {{source(), "out.vdb", "--factor", "33"}, 2, {"--factor", "1 to 32", "'33'"}},
        {{source(), "out.vdb", "--factor", "0"}, 2, {"--factor", "'0'"}},
        {{source(), "out.vdb"}, 2, {"--factor"}},
        {{source(), "no_folder/out.vdb", "--factor", "2"}, 1, {"no_folder/out.vdb"}},
    };
    for (const Case& c : cases) {
        const CliResult r = upsample(dir, c.args);
        EXPECT_EQ(r.exitCode, c.exitCode) << c.args[0] << "\n" << r.err;
        EXPECT_CONTAINS(r.err, "vdb_upsample: error:");
        for (const auto& needle : c.needles) EXPECT_CONTAINS(r.err, needle);
    }
    EXPECT_FALSE(fs::exists(dir / "out.vdb"));
    EXPECT_TRUE(test::tempLeftovers(dir.path()).empty());
    for (const auto& name : test::listDir(dir.path())) EXPECT_EQ(name.find(".tmp-"), std::string::npos) << name;
}

}  // namespace
}  // namespace vdbmarch
