// VDB media against OpenVDB itself: at every voxel centre the trilinear
// density equals the voxel's value, through the grid's own transform (affine,
// rotated, non-uniformly scaled) and the scene's; active tiles count; and the
// empty-space intervals of any ray through a non-zero point contain it.
#include <gtest/gtest.h>

#include <filesystem>

#include <openvdb/openvdb.h>

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

}  // namespace
}  // namespace vdbmarch
