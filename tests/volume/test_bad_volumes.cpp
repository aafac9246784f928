// Bad input gets a clear error and nothing is lost (the bad-input suite, by
// layer: parse/test_scene_errors.cpp, volume/test_bad_volumes.cpp,
// app/test_bad_input_cli.cpp).
//
// Every test feeds the library or the vdbmarch command one specific defect and
// checks (a) the error type (InputError for bad content, IoError for the file
// system), (b) that the message names the file / key path / grid AND the bad
// value, and, for the command, (c) exit status 1, the "vdbmarch: error:" line,
// and that no output file is created, clobbered or left half-written.
//
// VDB fixtures are generated with OpenVDB in a temporary directory per test
// (test::BadInput).
//
// This file: VDB volumes that are missing, not VDBs, lack the grid asked for,
// hold vectors, non-finite or negative densities, or nothing at all.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "parse/scene_desc.h"
#include "render/render.h"
#include "scene/auto_scene.h"
#include "scene/scene.h"
#include "support/support.h"
#include "volume/medium.h"

using namespace vdbmarch;
using namespace vdbmarch::test;

namespace {

// ===========================================================================
// 1. Missing files

TEST_F(BadInput, MissingVdbFileReferencedBySceneNamesThePath) {
    const std::string sceneFile = work("scene.json");
    SceneDesc desc = parseSceneText(vdbScene("density", "missing/nowhere.vdb"), sceneFile);
    const std::string resolved = work("missing/nowhere.vdb");
    EXPECT_EQ(desc.media.at(0).file, resolved) << "relative VDB paths resolve against the scene's folder";
    std::string msg = errorOf<IoError>([&] { buildScene(desc); });
    EXPECT_CONTAINS(msg, resolved);
    EXPECT_CONTAINS(msg, "No such file");
}

TEST_F(BadInput, MissingBareVdbIsIoErrorNamingThePath) {
    const std::string path = work("nowhere.vdb");
    std::string msg = errorOf<IoError>([&] { loadAutoScene(path); });
    EXPECT_CONTAINS(msg, path);
    msg = errorOf<IoError>([&] { summarizeVdb(path, ""); });
    EXPECT_CONTAINS(msg, path);
}

// ===========================================================================
// 2. A file that is not a VDB

TEST_F(BadInput, TextFileNamedVdbIsInputErrorNamingTheFile) {
    const std::string path = work("not_a_vdb.vdb");
    std::string msg = errorOf<InputError>([&] { summarizeVdb(path, ""); });
    EXPECT_CONTAINS(msg, path);
    msg = errorOf<InputError>([&] { loadAutoScene(path); });
    EXPECT_CONTAINS(msg, path);
    SceneDesc desc = parseSceneText(vdbScene("density", "not_a_vdb.vdb"), work("scene.json"));
    msg = errorOf<InputError>([&] { buildScene(desc); });
    EXPECT_CONTAINS(msg, path);
}

// ===========================================================================
// 3. A grid name that does not exist

TEST_F(BadInput, UnknownGridNameListsTheGridsThatExist) {
    SceneDesc desc = parseSceneText(vdbScene("densty"), work("scene.json"));
    std::string msg = errorOf<InputError>([&] { buildScene(desc); });
    EXPECT_CONTAINS(msg, work("grids.vdb"));
    EXPECT_CONTAINS(msg, "'densty'");
    for (const char* name : {"'density'", "'vel'", "'bad'", "'empty'"}) EXPECT_CONTAINS(msg, name);

    msg = errorOf<InputError>([&] { summarizeVdb(work("grids.vdb"), "temperature"); });
    EXPECT_CONTAINS(msg, "'temperature'");
    for (const char* name : {"'density'", "'vel'", "'bad'", "'empty'"}) EXPECT_CONTAINS(msg, name);
}

TEST_F(BadInput, UnknownEmissionGridListsTheGridsThatExist) {
    std::string text = vdbScene("density");
    size_t p = text.find("\"sigma_s\": 2");
    ASSERT_NE(p, std::string::npos);
    text.insert(p, "\"emission\": {\"grid\": \"temprature\"}, ");
    SceneDesc desc = parseSceneText(text, work("scene.json"));
    std::string msg = errorOf<InputError>([&] { buildScene(desc); });
    EXPECT_CONTAINS(msg, work("grids.vdb"));
    EXPECT_CONTAINS(msg, "'temprature'");
    EXPECT_CONTAINS(msg, "'density'");
}

// Blackbody emission: a missing temperature grid and temperatures below 0 K
// (in the file, or after temperature_scale / temperature_offset) are refused
// naming the file, the grid and the value; the command writes nothing.
std::string withEmission(const std::string& emission) {
    std::string text = vdbScene("density");
    size_t p = text.find("\"sigma_s\": 2");
    EXPECT_NE(p, std::string::npos);
    text.insert(p, "\"emission\": " + emission + ", ");
    return text;
}

// The InputError message of building the fixture scene with `emission`.
std::string buildError(const std::string& workScene, const std::string& emission) {
    SceneDesc desc = parseSceneText(withEmission(emission), workScene);
    return errorOf<InputError>([&] { buildScene(desc); });
}

TEST_F(BadInput, MissingBlackbodyTemperatureGridNamesFileAndGrid) {
    const std::string msg = buildError(work("scene.json"), R"({"grid": "temprature", "blackbody": true})");
    EXPECT_CONTAINS(msg, work("grids.vdb"));
    EXPECT_CONTAINS(msg, "'temprature'");
    EXPECT_CONTAINS(msg, "'density'");
}

TEST_F(BadInput, NegativeBlackbodyTemperatureNamesFileGridAndValue) {
    // Grid "bad" holds -0.5 and -3 among its good values (and NaN / Inf,
    // which are zeroed with a warning as for density).
    std::string msg = buildError(work("scene.json"), R"({"grid": "bad", "blackbody": true})");
    EXPECT_CONTAINS(msg, work("grids.vdb"));
    EXPECT_CONTAINS(msg, "emission grid 'bad'");
    EXPECT_CONTAINS(msg, "cannot be negative");
    EXPECT_TRUE(hasNumberToken(msg, "-0.5") || hasNumberToken(msg, "-3")) << msg;

    // Values of 1 mapped by the offset to -1 K: the message gives the mapping.
    const std::string offset = R"({"grid": "density", "blackbody": true, "temperature_offset": -2})";
    writeText(work("scene.json"), withEmission(offset));
    msg = buildError(work("scene.json"), offset);
    EXPECT_CONTAINS(msg, "emission grid 'density'");
    EXPECT_CONTAINS(msg, "temperature_offset -2");
    EXPECT_TRUE(hasNumberToken(msg, "-1")) << msg;

    CliResult r = cli({"render", "scene.json", "-o", "out.exr"});
    expectCliError(r, {"grids.vdb", "'density'", "cannot be negative"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// A grid in Kelvin renders; the same values scaled into Kelvin render the same.
TEST_F(BadInput, BlackbodyTemperatureScaleMapsGridToKelvin) {
    auto render = [&](const std::string& emission) {
        SceneDesc desc = parseSceneText(withEmission(emission), work("scene.json"));
        return renderImage(*buildScene(desc)).image;
    };
    const Image a = render(R"({"grid": "density", "blackbody": true, "temperature_scale": 2000})");
    const Image b = render(R"({"grid": "density", "blackbody": true, "temperature_scale": 1000, "temperature_offset": 1000})");
    EXPECT_EQ(a.rgba, b.rgba);
    const Image off = render(R"({"grid": "density", "blackbody": true, "temperature_scale": 0})");
    bool brighter = false;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) brighter = brighter || a.rgb(x, y).x > off.rgb(x, y).x;
    EXPECT_TRUE(brighter) << "2000 K emission adds light";
}

// ===========================================================================
// 4. A vector grid where a float grid is needed

TEST_F(BadInput, VectorGridWhereFloatNeededNamesTheType) {
    SceneDesc desc = parseSceneText(vdbScene("vel"), work("scene.json"));
    std::string msg = errorOf<InputError>([&] { buildScene(desc); });
    EXPECT_CONTAINS(msg, work("grids.vdb"));
    EXPECT_CONTAINS(msg, "'vel'");
    EXPECT_CONTAINS(msg, "vec3");

    msg = errorOf<InputError>([&] { summarizeVdb(work("grids.vdb"), "vel"); });
    EXPECT_CONTAINS(msg, "'vel'");
    EXPECT_CONTAINS(msg, "vec3");
}

TEST_F(BadInput, BareVdbWithOnlyAVectorGridNamesItsGrids) {
    const std::string path = work("vel_only.vdb");
    std::string msg = errorOf<InputError>([&] { loadAutoScene(path); });
    EXPECT_CONTAINS(msg, path);
    EXPECT_CONTAINS(msg, "'vel'");
    EXPECT_CONTAINS(msg, "vec3");
    CliResult r = cli({"render", "vel_only.vdb", "-o", "out.exr", "--res", "8x8", "--spp", "1"});
    expectCliError(r, {"vel_only.vdb", "'vel'", "vec3"});
}

// ===========================================================================
// 5. NaN, Inf and negative densities

TEST_F(BadInput, NonFiniteAndNegativeDensitiesSanitisedWithOneCountingWarning) {
    SceneDesc desc = parseSceneText(vdbScene("bad"), work("scene.json"));
    const int before = warningCount();
    std::unique_ptr<Scene> s = buildScene(desc);
    EXPECT_EQ(warningCount() - before, 1) << "last warning: " << lastWarning();
    const std::string w = lastWarning();
    EXPECT_CONTAINS(w, work("grids.vdb"));
    EXPECT_CONTAINS(w, "'bad'");
    EXPECT_TRUE(hasNumberToken(w, std::to_string(kBadValues))) << "the warning should count the " << kBadValues
                                                                << " bad values: " << w;
    ASSERT_EQ(s->media.size(), 1u);
    EXPECT_TRUE(std::isfinite(s->media[0]->maxDensity()));
    EXPECT_FLOAT_EQ(s->media[0]->maxDensity(), 1.f);

    // Render: no NaN/Inf pixel, and the medium is actually in view.
    RenderResult r = renderImage(*s);
    EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
    EXPECT_TRUE(allFinite(r.image));
    EXPECT_GT(maxAlpha(r.image), 0.05f) << "the medium should be visible, or this test proves nothing";
}

TEST_F(BadInput, SummaryOfBadGridIsSanitised) {
    const int before = warningCount();
    VdbGridSummary s = summarizeVdb(work("grids.vdb"), "bad");
    EXPECT_EQ(warningCount() - before, 1) << lastWarning();
    EXPECT_TRUE(hasNumberToken(lastWarning(), std::to_string(kBadValues))) << lastWarning();
    EXPECT_EQ(s.gridName, "bad");
    EXPECT_EQ(s.activeVoxels, size_t(kBlockVoxels));
    EXPECT_EQ(s.minValue, 0.f);
    EXPECT_EQ(s.maxValue, 1.f);
    EXPECT_TRUE(std::isfinite(s.meanValue));
    EXPECT_NEAR(s.meanValue, float(kBlockVoxels - kBadValues) / kBlockVoxels, 1e-6);
}

// ===========================================================================
// 9. An empty grid renders the background, with a warning

TEST_F(BadInput, EmptyGridRendersBackgroundWithOneWarning) {
    SceneDesc desc = parseSceneText(vdbScene("empty"), work("scene.json"));
    const int before = warningCount();
    std::unique_ptr<Scene> s = buildScene(desc);
    EXPECT_EQ(warningCount() - before, 1) << lastWarning();
    EXPECT_CONTAINS(lastWarning(), work("grids.vdb"));
    EXPECT_CONTAINS(lastWarning(), "'empty'");
    RenderResult r = renderImage(*s);
    expectBackgroundEverywhere(r.image, Color(0.25f, 0.5f, 0.75f));
}

}  // namespace
