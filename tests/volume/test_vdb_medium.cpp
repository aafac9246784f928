// VDB media against OpenVDB itself: at every voxel centre the trilinear
// density equals the voxel's value, through the grid's own transform (affine,
// rotated, non-uniformly scaled) and the scene's; active tiles count; and the
// empty-space intervals of any ray through a non-zero point contain it.
// The asset files (shared/assets) are not always there, so each of their
// properties is also checked on a grid the test writes itself: an affine
// transform with rotation and non-uniform scale, active tiles beside
// voxels, and half-float storage; and there the density at any point is
// OpenVDB's own trilinear sample (tools::BoxSampler) of the grid as read.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include "core/rng.h"
#include "core/sampling.h"
#include "core/transform.h"
#include "support/support.h"
#include "volume/medium.h"

namespace vdbmarch {
namespace {

namespace fs = std::filesystem;
using test::assetPath;
using test::samplePath;
using test::TempDir;

struct VoxelProbe {
    openvdb::Vec3d world;
    float value;
};

// Every `stride`-th active voxel or tile centre, with its world position.
std::vector<VoxelProbe> probes(const std::string& file, size_t stride, bool tilesOnly = false) {
    initOpenVdb();
    openvdb::io::File f(file);
    f.open();
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("density"));
    std::vector<VoxelProbe> out;
    size_t i = 0;
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        if (tilesOnly && it.isVoxelValue()) continue;
        if (i++ % stride != 0) continue;
        if (!std::isfinite(*it) || *it < 0) continue;
        // For a tile, a voxel deep inside it (its trilinear stencil stays in the tile).
        openvdb::Coord c = it.isVoxelValue() ? it.getCoord() : it.getBoundingBox().min().offsetBy(2);
        out.push_back({grid->indexToWorld(c), *it});
    }
    return out;
}

void checkDensityAtVoxelCentres(const std::string& file, const Mat4& sceneTransform, size_t stride, bool tilesOnly) {
    if (!fs::exists(file)) GTEST_SKIP() << "asset not present: " << file;
    MediumDesc d;
    d.type = MediumDesc::Type::Vdb;
    d.file = file;
    d.sigma_s = Vec3(1);
    d.transform = sceneTransform;
    auto medium = loadVdbMedium(d);
    auto q = medium->makeQuery();
    Transform xf(sceneTransform);
    auto ps = probes(file, stride, tilesOnly);
    ASSERT_GT(ps.size(), 10u);
    Rng rng(17);
    std::vector<Interval> iv;
    size_t checked = 0;
    for (const auto& p : ps) {
        Vec3 w = xf.point(Vec3(float(p.world.x()), float(p.world.y()), float(p.world.z())));
        // Float world positions put the sample ~1e-5 voxel off centre.
        ASSERT_NEAR(q->density(w), p.value, 2e-3f * std::max(1.f, p.value)) << "at " << w.x << "," << w.y << "," << w.z;
        if (p.value <= 1e-3f) continue;
        // A random ray through w: its active intervals contain w's parameter.
        Vec3 dir = sampleUniformSphere(rng.uniform(), rng.uniform());
        float back = 10 * medium->minVoxelSize() * 50;
        Ray r{w - dir * back, dir};
        iv.clear();
        q->activeIntervals(r, 0, Infinity, iv);
        bool inside = false;
        for (const auto& i : iv) inside = inside || (i.t0 <= back && back <= i.t1);
        ASSERT_TRUE(inside) << "the point with density " << p.value << " lies in skipped space";
        ++checked;
    }
    EXPECT_GT(checked, 5u);
}

TEST(VdbMedium, SampleCloudDensityAtVoxelCentres) {
    checkDensityAtVoxelCentres(samplePath("cloud.vdb"), Mat4::identity(), 97, false);
}

TEST(VdbMedium, SceneTransformIsAppliedAfterTheGrids) {
    Mat4 m = Mat4::translate(Vec3(3, -1, 2)) * Mat4::rotate(Vec3(1, 2, 0.5f), 37) * Mat4::scale(Vec3(2, 0.5f, 1.5f));
    checkDensityAtVoxelCentres(samplePath("cloud.vdb"), m, 131, false);
}

TEST(VdbMedium, AffineDragonHonoursItsRotatedNonUniformTransform) {
    checkDensityAtVoxelCentres(assetPath("dragon_fog_affine.vdb"), Mat4::identity(), 53, false);
}

TEST(VdbMedium, DisneyCloudVoxelsAndActiveTiles) {
    checkDensityAtVoxelCentres(assetPath("wdas_cloud_sixteenth.vdb"), Mat4::identity(), 211, false);
    checkDensityAtVoxelCentres(assetPath("wdas_cloud_sixteenth.vdb"), Mat4::identity(), 1, true);
}

TEST(VdbMedium, SmokePlumeStoredAsHalf) {
    checkDensityAtVoxelCentres(assetPath("smoke1.vdb"), Mat4::identity(), 499, false);
}


// ---------------------------------------------------------------------------
// The same properties on a grid written by the test.

struct SelfBuilt {
    bool tiles = false, half = false;
};

// Random values, none of them a half-float: storing as half changes each.
float randomValue(Rng& rng) { return 0.05f + 2.f * rng.uniform() + 1e-4f; }

// A "density" grid whose index -> world map is a non-uniform scale, three
// rotations and a translation (an AffineMap): 20x12x10 voxels of random
// values; with `tiles`, 17 active 8^3 tiles of two values beside them (one
// block of them touching the voxels' leaf); with `half`, written as half floats.
openvdb::FloatGrid::Ptr selfBuiltGrid(const SelfBuilt& o) {
    initOpenVdb();
    auto g = openvdb::FloatGrid::create(0.f);
    g->setName("density");
    g->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto xf = openvdb::math::Transform::createLinearTransform(1.0);
    xf->preScale(openvdb::Vec3d(0.03, 0.05, 0.02));
    xf->postRotate(0.6, openvdb::math::X_AXIS);
    xf->postRotate(-0.9, openvdb::math::Y_AXIS);
    xf->postRotate(0.3, openvdb::math::Z_AXIS);
    xf->postTranslate(openvdb::Vec3d(0.4, -0.3, 0.2));
    g->setTransform(xf);
    Rng rng(41, 7);
    auto acc = g->getAccessor();
    for (int x = 0; x < 20; ++x)
        for (int y = 0; y < 12; ++y)
            for (int z = 0; z < 10; ++z) acc.setValueOn(openvdb::Coord(x, y, z), randomValue(rng));
    if (o.tiles) {
        g->tree().fill(openvdb::CoordBBox(openvdb::Coord(24, 0, 0), openvdb::Coord(55, 15, 15)), 1.7f, true);
        g->tree().fill(openvdb::CoordBBox(openvdb::Coord(-16, 0, 0), openvdb::Coord(-9, 7, 7)), 0.3f, true);
    }
    g->setSaveFloatAsHalf(o.half);
    return g;
}

std::string writeSelfBuilt(const TempDir& dir, const SelfBuilt& o) {
    const std::string path = dir / (std::string("self") + (o.tiles ? "_tiles" : "") + (o.half ? "_half" : "") + ".vdb");
    auto g = selfBuiltGrid(o);
    openvdb::io::File f(path);
    f.write({g});
    f.close();
    return path;
}

openvdb::FloatGrid::Ptr readBack(const std::string& path) {
    openvdb::io::File f(path);
    f.open();
    auto g = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("density"));
    f.close();
    return g;
}

TEST(VdbMedium, SelfBuiltAffineGridHonoursItsRotatedNonUniformTransform) {
    TempDir dir("vdbmedium");
    const std::string file = writeSelfBuilt(dir, {});
    // What the file holds: a general affine map, scale different per axis.
    auto g = readBack(file);
    EXPECT_EQ(g->transform().mapType(), openvdb::math::AffineMap::mapType());
    const openvdb::Vec3d vs = g->transform().voxelSize();
    EXPECT_NEAR(vs.x(), 0.03, 1e-9);
    EXPECT_NEAR(vs.z(), 0.02, 1e-9);
    checkDensityAtVoxelCentres(file, Mat4::identity(), 3, false);
    // And with a scene transform on top of the grid's.
    Mat4 m = Mat4::translate(Vec3(3, -1, 2)) * Mat4::rotate(Vec3(1, 2, 0.5f), 37) * Mat4::scale(Vec3(2, 0.5f, 1.5f));
    checkDensityAtVoxelCentres(file, m, 5, false);
}

TEST(VdbMedium, SelfBuiltGridVoxelsAndActiveTiles) {
    TempDir dir("vdbmedium");
    const std::string file = writeSelfBuilt(dir, {true, false});
    auto g = readBack(file);
    ASSERT_EQ(g->tree().activeTileCount(), 17u);
    checkDensityAtVoxelCentres(file, Mat4::identity(), 7, false);
    checkDensityAtVoxelCentres(file, Mat4::identity(), 1, true);
}

TEST(VdbMedium, SelfBuiltGridStoredAsHalf) {
    TempDir dir("vdbmedium");
    const std::string file = writeSelfBuilt(dir, {true, true});
    // The file does hold halves: every voxel read back is its value rounded
    // to half precision (relative error <= 2^-11), and not the float itself.
    auto stored = readBack(file);
    auto original = selfBuiltGrid({true, true});
    auto acc = stored->getConstAccessor();
    size_t voxels = 0, changed = 0;
    for (auto it = original->cbeginValueOn(); it; ++it) {
        if (!it.isVoxelValue()) continue;
        const float v = *it, h = acc.getValue(it.getCoord());
        ASSERT_TRUE(acc.isValueOn(it.getCoord()));
        EXPECT_NEAR(h, v, v * 0x1p-11f);
        changed += h != v;
        ++voxels;
    }
    EXPECT_EQ(voxels, 20u * 12u * 10u);
    EXPECT_GT(changed, voxels / 2);
    checkDensityAtVoxelCentres(file, Mat4::identity(), 7, false);
    checkDensityAtVoxelCentres(file, Mat4::identity(), 1, true);
}

// This test found the one-voxel shell below a tile's low faces at density 0
// (fixed in padded_blocks.cpp, 2026-12-03; e.g. index point
// (52.50, -0.41, 9.67) in front of the tile block at y = 0: BoxSampler 1.51).
//
// At random points in and around the grid (voxels, tiles and the half-voxel
// shells at their faces, where the trilinear stencil reaches inactive space),
// the medium's density is OpenVDB's BoxSampler on the grid read from the
// file, times density_scale.
TEST(VdbMedium, SelfBuiltGridDensityIsOpenVdbsTrilinearSample) {
    TempDir dir("vdbmedium");
    const std::string file = writeSelfBuilt(dir, {true, true});
    auto g = readBack(file);
    MediumDesc d;
    d.type = MediumDesc::Type::Vdb;
    d.file = file;
    d.sigma_s = Vec3(1);
    d.densityScale = 1.5f;
    auto medium = loadVdbMedium(d);
    auto q = medium->makeQuery();
    Rng rng(43, 1);
    int nonZero = 0, worst = -1, bad = 0;
    double worstErr = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        // Index points over the whole active box and one voxel beyond it.
        const openvdb::Vec3d ip(-18 + 76 * double(rng.uniform()), -2 + 20 * double(rng.uniform()),
                                -2 + 20 * double(rng.uniform()));
        const openvdb::Vec3d w = g->indexToWorld(ip);
        const Vec3 wf(float(w.x()), float(w.y()), float(w.z()));
        // Sample where the float point really is.
        const openvdb::Vec3d at = g->worldToIndex(openvdb::Vec3d(wf.x, wf.y, wf.z));
        const double want = 1.5 * openvdb::tools::BoxSampler::sample(g->tree(), at);
        const double got = q->density(wf);
        nonZero += want > 0;
        if (std::fabs(got - want) > worstErr) {
            worstErr = std::fabs(got - want);
            worst = i;
        }
        if (std::fabs(got - want) > 1e-4 * std::max(1.0, want) && ++bad <= 5)
            ADD_FAILURE() << "index point " << at << ": density " << got << ", OpenVDB's trilinear sample " << want;
    }
    std::printf("worst |density - BoxSampler| %.3g at sample %d\n", worstErr, worst);
    EXPECT_EQ(bad, 0) << "of " << n << " points";
    EXPECT_GT(nonZero, n / 4);
}

}  // namespace
}  // namespace vdbmarch
