// vdbmarch bench: CSV rows for every method and budget, the markdown table
// naming the reference, and a cached reference reused by the next run.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "bench.h"
#include "image/exr_io.h"
#include "test_helpers.h"

namespace vdbmarch::testing {
namespace {

std::string readAll(const std::string& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

TEST(Bench, WritesCsvAndTableAndReusesItsReference) {
    SceneDesc d = loadSceneFile(std::string(VDBMARCH_SOURCE_DIR) + "/vdb_samples/cloud.json",
                                {"camera.resolution=[16,12]"});
    BenchOptions o;
    o.methods = {"uniform", "reference"};
    o.budgets = {1, 2};
    o.outDir = tempDir() + "/bench";
    o.referenceSpp = 16;
    BenchResult a = runBench(d, o);
    ASSERT_EQ(a.rows.size(), 4u);
    for (const auto& r : a.rows) {
        EXPECT_GT(r.rmse, 0);
        EXPECT_EQ(r.spp, int(r.budget));
    }
    EXPECT_GT(a.referenceNoiseRmse, 0);
    std::string csv = readAll(a.csvPath);
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5);  // header + 4 rows
    EXPECT_NE(readAll(a.tablePath).find(a.referenceImage), std::string::npos);
    // Second run: the same cached reference, hence the same errors.
    BenchResult b = runBench(d, o);
    EXPECT_EQ(b.referenceImage, a.referenceImage);
    EXPECT_DOUBLE_EQ(b.referenceNoiseRmse, a.referenceNoiseRmse);
    EXPECT_DOUBLE_EQ(b.rows[0].rmse, a.rows[0].rmse);
}

}  // namespace
}  // namespace vdbmarch::testing

namespace vdbmarch::testing {
namespace {

// vdb_render as a benchmarked method: runs with the scene translated to its
// options, and refuses scenes it cannot express, naming why.
TEST(Bench, VdbRenderIsAMethodForScenesItCanExpress) {
    std::string vdb = tempDir() + "/bench_box.vdb";
    writeBoxGrid(vdb, openvdb::Coord(0), openvdb::Coord(19), 0.5f, 0.05);
    std::string json = R"({"camera": {"position": [0.6, 0.7, 2.5], "look_at": [0.475, 0.475, 0.475], "fov_deg": 30,
        "resolution": [16, 12]},
        "lights": [{"type": "directional", "direction": [-0.3, -1, -0.2], "irradiance": 6}],
        "media": [{"type": "vdb", "file": ")" + vdb + R"(", "sigma_s": 8, "sigma_a": 0.5}],
        "render": {"pixel_jitter": false}})";
    SceneDesc d = parseSceneText(json, tempDir() + "/bench_box.json");
    BenchOptions o;
    o.methods = {"vdb_render"};
    o.budgets = {1};
    o.vdbRenderSteps = {1, 0.5};
    o.outDir = tempDir() + "/bench_vdbr";
    o.referenceSpp = 64;
    if (std::system("command -v vdb_render >/dev/null 2>&1") != 0) GTEST_SKIP() << "vdb_render not installed";
    BenchResult r = runBench(d, o);
    ASSERT_EQ(r.rows.size(), 2u);
    // Same physics: vdb_render's error against our reference is small next to the image.
    Image ref = readExr(r.referenceImage);
    double mean = 0;
    for (size_t i = 0; i < ref.rgba.size(); i += 4) mean += ref.rgba[i];
    mean /= double(ref.rgba.size() / 4);
    EXPECT_GT(mean, 0.01);
    EXPECT_LT(r.rows[1].rmse, 0.5 * mean);

    SceneDesc withGlass = parseSceneText(json.substr(0, json.size() - 1) +
                                             R"(, "surfaces": [{"shape": "sphere"}]})",
                                         tempDir() + "/bench_glass.json");
    try {
        runBench(withGlass, o);
        FAIL() << "vdb_render accepted a scene with surfaces";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("surfaces"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace vdbmarch::testing
