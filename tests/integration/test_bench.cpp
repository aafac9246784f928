// vdbmarch bench: CSV rows for every method and budget, the markdown table
// naming the reference, a cached reference reused by the next run, the image
// strip and the spread of the per-pixel relative error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "app/bench.h"
#include "image/exr_io.h"
#include "image/metrics.h"
#include "image/png_io.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

// The sample cloud at 16x12.
SceneDesc smallCloud() { return loadSceneFile(samplePath("cloud.json"), {"camera.resolution=[16,12]"}); }

// uniform and reference at budgets 1 and 2 spp, against a 16 spp reference.
BenchOptions uniformAndReference(const std::string& outDir) {
    BenchOptions o;
    o.methods = {"uniform", "reference"};
    o.budgets = {1, 2};
    o.outDir = outDir;
    o.referenceSpp = 16;
    return o;
}

TEST(Bench, WritesCsvAndTableAndReusesItsReference) {
    TempDir dir;
    SceneDesc d = smallCloud();
    BenchOptions o = uniformAndReference(dir / "bench");
    BenchResult a = runBench(d, o);
    ASSERT_EQ(a.rows.size(), 4u);
    for (const auto& r : a.rows) {
        EXPECT_GT(r.rmse, 0);
        EXPECT_EQ(r.spp, int(r.budget));
    }
    EXPECT_GT(a.referenceNoiseRmse, 0);
    std::string csv = readBytes(a.csvPath);
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5);  // header + 4 rows
    EXPECT_NE(readBytes(a.tablePath).find(a.referenceImage), std::string::npos);
    // Second run: the same cached reference, hence the same errors.
    BenchResult b = runBench(d, o);
    EXPECT_EQ(b.referenceImage, a.referenceImage);
    EXPECT_DOUBLE_EQ(b.referenceNoiseRmse, a.referenceNoiseRmse);
    EXPECT_DOUBLE_EQ(b.rows[0].rmse, a.rows[0].rmse);
}

// A method name the bench does not know is refused before anything renders
// or is written (it used to fail only after the reference was rendered).
TEST(Bench, UnknownMethodIsRefusedBeforeAnyRender) {
    TempDir dir;
    BenchOptions o = uniformAndReference(dir / "bench");
    o.methods = {"uniform", "guidd"};
    expectErrorContaining<InputError>([&] { runBench(smallCloud(), o); },
                                      {"unknown method \"guidd\"", "reference", "auto", "vdb_render"});
    EXPECT_TRUE(listDir(dir.path()).empty());
}

// auto as a benchmarked method renders as `vdbmarch render` does: at a
// sample budget the rule's pick (the sample cloud's is the path tracer: the
// same pixels, so the same error), in a timed run the pick of pilots, whose
// time counts in its run's seconds.
TEST(Bench, AutoIsTheRulesPickAtSampleBudgetsAndPilotsInTimedRuns) {
    TempDir dir;
    BenchOptions o = uniformAndReference(dir / "bench");
    o.methods = {"auto", "reference"};
    BenchResult spp = runBench(smallCloud(), o);
    ASSERT_EQ(spp.rows.size(), 4u);
    EXPECT_DOUBLE_EQ(spp.rows[0].rmse, spp.rows[2].rmse);
    EXPECT_DOUBLE_EQ(spp.rows[1].rmse, spp.rows[3].rmse);

    o.methods = {"auto"};
    o.budgetSeconds = true;
    o.budgets = {0.6};
    BenchResult timed = runBench(smallCloud(), o);
    ASSERT_EQ(timed.rows.size(), 1u);
    EXPECT_GE(timed.rows[0].spp, 2);
    EXPECT_GT(timed.rows[0].rmse, 0);
    EXPECT_GT(timed.rows[0].seconds, 0.1);  // the pilots' time is in it
}

// vdb_render as a benchmarked method: runs with the scene translated to its
// options, and refuses scenes it cannot express, naming why.
TEST(Bench, VdbRenderIsAMethodForScenesItCanExpress) {
    TempDir dir;
    std::string vdb = writeBoxGrid(dir / "bench_box.vdb", 0, 19, 0.5f, 0.05);
    std::string json = R"({"camera": {"position": [0.6, 0.7, 2.5], "look_at": [0.475, 0.475, 0.475], "fov_deg": 30,
        "resolution": [16, 12]},
        "lights": [{"type": "directional", "direction": [-0.3, -1, -0.2], "irradiance": 6}],
        "media": [{"type": "vdb", "file": ")" + vdb + R"(", "sigma_s": 8, "sigma_a": 0.5}],
        "render": {"pixel_jitter": false}})";
    SceneDesc d = parseSceneText(json, dir / "bench_box.json");
    BenchOptions o;
    o.methods = {"vdb_render"};
    o.budgets = {1};
    o.vdbRenderSteps = {1, 0.5};
    o.outDir = dir / "bench_vdbr";
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
                                         dir / "bench_glass.json");
    // vdb_render cannot render a scene with surfaces.
    EXPECT_CONTAINS(errorOf<InputError>([&] { runBench(withGlass, o); }), "surfaces");
}

// The strip: rows = methods, columns = the reference then the budgets, thin
// separators; tiles are the images as the PNG preview shows them, and shrink
// to the width limit.
TEST(Bench, WritesAnImageStripOfMethodsByBudgets) {
    TempDir dir;
    SceneDesc d = smallCloud();
    BenchOptions o = uniformAndReference(dir / "bench_strip");
    o.stripPath = o.outDir + "/strip.png";
    BenchResult r = runBench(d, o);
    EXPECT_EQ(r.stripPath, o.stripPath);
    EXPECT_EQ(r.stripRows, 2);
    EXPECT_EQ(r.stripColumns, 3);
    ASSERT_EQ(r.tileWidth, 16);
    ASSERT_EQ(r.tileHeight, 12);
    Image strip = readPng(o.stripPath);
    EXPECT_EQ(strip.width, 3 * 16 + 2 * StripSeparator + (StripReferenceGap - StripSeparator));
    EXPECT_EQ(strip.height, 2 * 12 + StripSeparator);

    // Both rows start with the reference, tone mapped exactly as writePng does.
    Image ref = readExr(r.referenceImage);
    std::vector<uint8_t> bytes = toSrgb8(ref, d.render.exposure);
    for (int row = 0; row < 2; ++row)
        for (int y = 0; y < 12; ++y)
            for (int x = 0; x < 16; ++x)
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(strip.rgb(x, row * (12 + StripSeparator) + y)[c],
                              srgbToLinear(bytes[(size_t(y) * 16 + size_t(x)) * 3 + size_t(c)] / 255.f))
                        << "row " << row << " pixel " << x << "," << y;
    // Separators: after the reference column, between budgets, between rows.
    EXPECT_EQ(strip.rgb(16, 0).x, 1.f);
    EXPECT_EQ(strip.rgb(16 + StripReferenceGap - 1, 5).y, 1.f);
    EXPECT_EQ(strip.rgb(16 + StripReferenceGap + 16, 3).z, 1.f);
    EXPECT_EQ(strip.rgb(3, 12).x, 1.f);
    // Different methods at the same budget give different tiles.
    bool differ = false;
    const int x1 = 16 + StripReferenceGap;
    for (int y = 0; y < 12 && !differ; ++y)
        for (int x = 0; x < 16 && !differ; ++x)
            differ = strip.rgb(x1 + x, y).x != strip.rgb(x1 + x, 12 + StripSeparator + y).x;
    EXPECT_TRUE(differ);

    // The spread and low-frequency columns follow the existing ones.
    std::string csv = readBytes(r.csvPath);
    EXPECT_EQ(csv.substr(0, csv.find('\n')),
              "method,budget,spp,seconds,rmse,relmse,rel_p50,rel_p95,rel_p95_over_p50,low_freq");
    std::string md = readBytes(r.tablePath);
    EXPECT_NE(md.find("| RMSE | relMSE | LF error | rel. error p50 | rel. error p95 | p95/p50 |"), std::string::npos);
    EXPECT_NE(md.find("| method | b (RMSE) | b (LF) | RMSE ratio | LF ratio |"), std::string::npos);
    EXPECT_NE(md.find("strip.png"), std::string::npos);
    EXPECT_GT(r.spreadPixels, 0u);
    EXPECT_LT(r.spreadPixels, size_t(16 * 12));  // the sky around the cloud is left out
    for (const auto& row : r.rows) {
        EXPECT_GT(row.relP50, 0) << row.method;
        EXPECT_GE(row.relP95, row.relP50) << row.method;
        EXPECT_DOUBLE_EQ(row.relSpread, row.relP95 / row.relP50) << row.method;
        EXPECT_GT(row.lowFreq, 0) << row.method;
    }

    // Narrower than the images: tiles are box-downscaled to fit; no reference column.
    o.stripReference = false;
    o.stripMaxWidth = 30;
    BenchResult s = runBench(d, o);
    EXPECT_EQ(s.stripColumns, 2);
    EXPECT_EQ(s.tileWidth, (30 - StripSeparator) / 2);
    EXPECT_EQ(s.tileHeight, 11);  // 12 * 14 / 16 = 10.5, rounded
    Image small = readPng(o.stripPath);
    EXPECT_EQ(small.width, 2 * s.tileWidth + StripSeparator);
    EXPECT_LE(small.width, 30);
    EXPECT_EQ(small.height, 2 * s.tileHeight + StripSeparator);

    o.stripMaxWidth = 3;
    EXPECT_THROW(runBench(d, o), InputError);
}

TEST(Bench, DownscaleBoxAveragesTheCoveredArea) {
    Image a(3, 1);
    a.set(0, 0, Color(1.f), 1.f);
    a.set(1, 0, Color(2.f), 1.f);
    a.set(2, 0, Color(3.f), 1.f);
    Image b = downscaleBox(a, 2, 1);
    EXPECT_NEAR(b.rgb(0, 0).x, 4.f / 3.f, 1e-6);  // (1 + 2/2) / 1.5
    EXPECT_NEAR(b.rgb(1, 0).y, 8.f / 3.f, 1e-6);  // (2/2 + 3) / 1.5
    EXPECT_NEAR(b.alpha(1, 0), 1.f, 1e-6);

    Image c(4, 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) c.set(x, y, Color(float(x + 4 * y)), 0.f);
    c.rgba[0] = std::numeric_limits<float>::quiet_NaN();  // counts as black, as in the PNG preview
    Image e = downscaleBox(c, 2, 2);
    EXPECT_NEAR(e.rgb(0, 0).x, (0 + 1 + 4 + 5) / 4.f, 1e-6);
    EXPECT_NEAR(e.rgb(1, 1).x, (10 + 11 + 14 + 15) / 4.f, 1e-6);
    EXPECT_THROW(downscaleBox(c, 0, 2), InputError);
}

// relativeErrorSpread against values known in closed form: reference 2 in all
// channels (eps = 0.01 * 2), pixel k (in shuffled order) off by
// (k + 1) * 0.01 * (2 + eps), so its relative error is (k + 1) / 100.
TEST(Bench, RelativeErrorSpreadPercentilesOnAKnownPair) {
    Image ref(10, 11), test(10, 11);
    std::vector<int> order(100);
    for (int i = 0; i < 100; ++i) order[size_t(i)] = i;
    std::shuffle(order.begin(), order.end(), std::mt19937(7));
    for (int i = 0; i < 100; ++i) {
        int k = order[size_t(i)];
        double off = (k + 1) * 0.01 * (2 + 0.02) * (k % 2 ? -1 : 1);
        ref.set(i % 10, i / 10, Color(2.f), 1.f);
        test.set(i % 10, i / 10, Color(float(2 + off)), 1.f);
    }
    // The last row: the reference's background (alpha 0), with large errors.
    for (int x = 0; x < 10; ++x) {
        ref.set(x, 10, Color(2.f), 0.f);
        test.set(x, 10, Color(50.f), 1.f);
    }
    RelErrorSpread s = relativeErrorSpread(test, ref, BenchSpreadMinAlpha);
    EXPECT_EQ(s.pixels, 100u);
    EXPECT_NEAR(s.eps, 0.02, 1e-9);
    EXPECT_NEAR(s.p50, 0.50, 1e-5);  // nearest rank: the 50th of 100 sorted values
    EXPECT_NEAR(s.p95, 0.95, 1e-5);
    EXPECT_NEAR(s.ratio, 1.9, 1e-4);

    // Without the alpha mask the background row counts: 10 pixels at 24 / 1.01.
    RelErrorSpread all = relativeErrorSpread(test, ref);
    EXPECT_EQ(all.pixels, 110u);
    EXPECT_NEAR(all.p95, 48.0 / 2.02, 1e-4);  // rank ceil(104.5) = 105 > 100 ordinary pixels
    // A non-finite pixel is left out.
    test.rgba[0] = std::numeric_limits<float>::infinity();
    EXPECT_EQ(relativeErrorSpread(test, ref, BenchSpreadMinAlpha).pixels, 99u);
}

// The same figures computed the plain way (full sort) on a random pair, and 0
// for an image against itself.
TEST(Bench, RelativeErrorSpreadMatchesABruteForceComputation) {
    std::mt19937 gen(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    Image ref(37, 23), test(37, 23);
    for (size_t i = 0; i < ref.rgba.size(); ++i) {
        ref.rgba[i] = (i % 4 == 3) ? (u(gen) < 0.3f ? 0.f : u(gen)) : u(gen) * u(gen);
        test.rgba[i] = ref.rgba[i] + 0.2f * (u(gen) - 0.5f) * ref.rgba[i] + 0.01f * u(gen);
    }
    std::vector<size_t> used;
    double mean = 0;
    for (size_t p = 0; p < ref.pixelCount(); ++p)
        if (ref.rgba[p * 4 + 3] >= BenchSpreadMinAlpha) {
            used.push_back(p);
            mean += (double(ref.rgba[p * 4]) + ref.rgba[p * 4 + 1] + ref.rgba[p * 4 + 2]) / 3;
        }
    mean /= double(used.size());
    const double eps = 0.01 * mean;
    std::vector<double> e;
    for (size_t p : used) {
        double sum = 0;
        for (int c = 0; c < 3; ++c)
            sum += std::abs(double(test.rgba[p * 4 + c]) - ref.rgba[p * 4 + c]) / (ref.rgba[p * 4 + c] + eps);
        e.push_back(sum / 3);
    }
    std::sort(e.begin(), e.end());
    const size_t n = e.size();
    const double p50 = e[(n + 1) / 2 - 1], p95 = e[size_t(std::ceil(0.95 * double(n))) - 1];

    RelErrorSpread s = relativeErrorSpread(test, ref, BenchSpreadMinAlpha);
    EXPECT_EQ(s.pixels, n);
    EXPECT_NEAR(s.eps, eps, 1e-12);
    // Not bit-equal: the mean (hence eps) is summed in another order.
    EXPECT_NEAR(s.p50, p50, 1e-12 * p50);
    EXPECT_NEAR(s.p95, p95, 1e-12 * p95);
    EXPECT_NEAR(s.ratio, p95 / p50, 1e-11 * p95 / p50);

    RelErrorSpread self = relativeErrorSpread(ref, ref, BenchSpreadMinAlpha);
    EXPECT_EQ(self.p50, 0);
    EXPECT_EQ(self.p95, 0);
    EXPECT_EQ(self.ratio, 0);
    EXPECT_THROW(relativeErrorSpread(test, Image(3, 3)), InputError);
}

}  // namespace
}  // namespace vdbmarch
