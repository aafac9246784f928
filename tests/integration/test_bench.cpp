// vdbmarch bench: CSV rows for every method and budget, the markdown table
// naming the reference, and a cached reference reused by the next run.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "bench.h"
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
