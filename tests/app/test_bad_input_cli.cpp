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
// This file: the vdbmarch command's side (exit status, one error line, and
// that no output is created, clobbered or left half-written).
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/memory.h"
#include "image/exr_io.h"
#include "scene/auto_scene.h"
#include "support/support.h"

using namespace vdbmarch;
using namespace vdbmarch::test;

namespace {

namespace fs = std::filesystem;

// ===========================================================================
// 1. Missing files

TEST_F(BadInput, MissingSceneFileCli) {
    CliResult r = cli({"render", "no_such_scene.json", "-o", "out.exr"});
    expectCliError(r, {"no_such_scene.json", "No such file"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

TEST_F(BadInput, MissingVdbFileCli) {
    scene("scene.json", vdbScene("density", "nowhere.vdb"));
    CliResult r = cli({"render", "scene.json", "-o", "out.exr"});
    // Run from the scene's folder, the path is reported relative to it ("./nowhere.vdb").
    expectCliError(r, {"nowhere.vdb", "No such file"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// ===========================================================================
// 2. A file that is not a VDB

TEST_F(BadInput, TextFileNamedVdbCli) {
    CliResult r = cli({"render", "not_a_vdb.vdb", "-o", "out.exr", "--res", "8x8", "--spp", "1"});
    expectCliError(r, {"not_a_vdb.vdb"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
    r = cli({"info", "not_a_vdb.vdb"});
    expectCliError(r, {"not_a_vdb.vdb"});
}

// A real VDB cut short must also be an error naming the file, not a crash
// (run through the command so that a crash cannot take the test binary down).
TEST_F(BadInput, TruncatedVdbCli) {
    std::string bytes = readBytes(work("grids.vdb"));
    ASSERT_GT(bytes.size(), 200u);
    writeText(work("truncated.vdb"), bytes.substr(0, bytes.size() / 2));
    CliResult r = cli({"info", "truncated.vdb"});
    expectCliError(r, {"truncated.vdb"});
    scene("scene.json", vdbScene("density", "truncated.vdb"));
    r = cli({"render", "scene.json", "-o", "out.exr"});
    expectCliError(r, {"truncated.vdb"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// Cut anywhere past its header, a VDB file is refused by the grid extent
// check, never read in part: the message names the file and says it is cut
// short. At any cut, `info` and `check` exit 1 naming it.
TEST_F(BadInput, VdbCutAnywhereIsRefusedNotReadInPartCli) {
    const std::string bytes = readBytes(work("grids.vdb"));
    ASSERT_GT(bytes.size(), 1000u);
    for (double f : {0.05, 0.5, 0.9, 0.97, 0.99, 0.999}) {
        const size_t len = std::max<size_t>(1, size_t(double(bytes.size()) * f));
        for (size_t cut : {len, bytes.size() - 1}) {
            writeText(work("cut.vdb"), bytes.substr(0, cut));
            CliResult r = cli({"info", "cut.vdb"});
            expectCliError(r, {"cut.vdb"});
            if (cut > bytes.size() / 2) {
                EXPECT_NE(r.err.find("cut short"), std::string::npos) << cut << ": " << r.err;
            }
            r = cli({"check", "cut.vdb"});
            expectCliError(r, {"cut.vdb"});
        }
    }
    // The whole file reads cleanly.
    CliResult ok = cli({"check", "grids.vdb"});
    EXPECT_EQ(ok.exitCode, 0) << ok.err;
}

// Regression fixtures from the damaged-file catalogue (tools/
// damage_catalogue.py), made from the project's own sample: one changed byte
// in vdb_samples/cloud.vdb makes OpenVDB's reader corrupt the heap and abort
// ("free(): invalid pointer") when it reads the grid in-process. Every command
// that opens it must instead exit 1 naming the file: the file is read in a
// child process first (app/vdb_check.h).
TEST_F(BadInput, VdbThatCrashesOpenVdbsReaderIsAnErrorCli) {
    std::string bytes = readBytes(samplePath("cloud.vdb"));
    ASSERT_EQ(bytes.size(), 689538u) << "vdb_samples/cloud.vdb changed: find new crashers with tools/damage_catalogue.py";
    for (auto [offset, value] : {std::pair<size_t, int>{111263, 29}, {111444, 221}, {114343, 114}}) {
        std::string damaged = bytes;
        damaged[offset] = char(value);
        writeText(work("damaged.vdb"), damaged);
        CliResult r = cli({"info", "damaged.vdb"});
        expectCliError(r, {"damaged.vdb"});
        r = cli({"check", "damaged.vdb"});
        expectCliError(r, {"damaged.vdb"});
        r = cli({"render", "damaged.vdb", "-o", "out.exr", "--res", "16x12", "--spp", "1"});
        expectCliError(r, {"damaged.vdb"});
        EXPECT_FALSE(fs::exists(work("out.exr")));
        scene("scene.json", vdbScene("density", "damaged.vdb"));
        r = cli({"render", "scene.json", "-o", "out.exr"});
        expectCliError(r, {"damaged.vdb"});
        EXPECT_FALSE(fs::exists(work("out.exr")));
    }
}

// ===========================================================================
// 3. A grid name that does not exist

TEST_F(BadInput, UnknownGridNameCli) {
    scene("scene.json", vdbScene("density"));
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--set", "media.0.grid=smoke"});
    expectCliError(r, {"grids.vdb", "'smoke'", "'density'", "'vel'"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// ===========================================================================
// 5. NaN, Inf and negative densities

TEST_F(BadInput, NonFiniteDensitiesRenderCleanlyCli) {
    scene("scene.json", vdbScene("bad"));
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--res", "8x8", "--spp", "1"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(countOccurrences(r.err, "vdbmarch: warning: "), 1) << r.err;
    EXPECT_CONTAINS(r.err, "'bad'");
    EXPECT_TRUE(hasNumberToken(r.err, std::to_string(kBadValues))) << r.err;
    Image img = readExr(work("out.exr"));
    EXPECT_EQ(img.width, 8);
    EXPECT_EQ(img.height, 8);
    EXPECT_TRUE(allFinite(img));
    EXPECT_GT(maxAlpha(img), 0.05f);
    EXPECT_TRUE(tempLeftovers(mWork).empty());
}

// ===========================================================================
// 6. Malformed JSON: file:line:column

TEST_F(BadInput, MalformedJsonCliPrintsFileLineColumn) {
    scene("broken.json", "{\n  \"camera\": {\n    \"position\": [0, 0, 5]\n    \"look_at\": [0, 0, 0]\n  }\n}\n");
    CliResult r = cli({"render", "broken.json", "-o", "out.exr"});
    // The comma missing at the end of line 3 is noticed at "look_at" (line 4, column 5).
    expectCliError(r, {"broken.json:4:5:", "malformed JSON"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// ===========================================================================
// 7. Unknown keys

TEST_F(BadInput, UnknownKeyCli) {
    scene("typo.json", homogeneousScene(", \"sigma_ss\": 0.5"));
    CliResult r = cli({"render", "typo.json", "-o", "out.exr"});
    expectCliError(r, {"typo.json", "media[0].sigma_ss", "did you mean 'sigma_s'"});
}

// ===========================================================================
// 8. Values out of range

TEST_F(BadInput, HugeResolutionFromResOptionCli) {
    scene("scene.json", homogeneousScene());
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--res", "100000x100000"});
    expectCliError(r, {"camera.resolution", "100000"});
    EXPECT_LT(r.seconds, 10) << "refused before any allocation or rendering";
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// A photon count the machine cannot hold is refused before tracing, with
// what it would need (2^32 paths: about 176 GiB).
TEST_F(BadInput, PhotonCountBeyondMemoryIsRefusedCli) {
    if (availableMemoryBytes() > (uint64_t(1) << 32) * 44) GTEST_SKIP() << "this machine could hold them";
    scene("scene.json", homogeneousScene());
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--method", "guided", "--set",
                       "photons.count=4294967296"});
    expectCliError(r, {"photons.count", "GiB"});
    EXPECT_LT(r.seconds, 10) << "refused before tracing";
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// ===========================================================================
// 9. An empty grid renders the background, with a warning

TEST_F(BadInput, EmptyGridRendersBackgroundCli) {
    scene("scene.json", vdbScene("empty"));
    CliResult r = cli({"render", "scene.json", "-o", "out.exr"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(countOccurrences(r.err, "vdbmarch: warning: "), 1) << r.err;
    EXPECT_CONTAINS(r.err, "'empty'");
    expectBackgroundEverywhere(readExr(work("out.exr")), Color(0.25f, 0.5f, 0.75f));
}

TEST_F(BadInput, BareEmptyVdbRendersBackgroundCli) {
    CliResult r = cli({"render", "empty_only.vdb", "-o", "out.exr", "--res", "8x8", "--spp", "1"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_GE(countOccurrences(r.err, "vdbmarch: warning: "), 1) << r.err;
    EXPECT_CONTAINS(r.err, "empty_only.vdb");
    // The automatic scene's background colour.
    nlohmann::json doc = autoSceneJson(work("empty_only.vdb"));
    std::vector<float> bg = doc.at("background").get<std::vector<float>>();
    ASSERT_EQ(bg.size(), 3u);
    expectBackgroundEverywhere(readExr(work("out.exr")), Color(bg[0], bg[1], bg[2]));
}

// ===========================================================================
// 10. Nothing is lost

// Control: the fixtures and the command work, so the failures below are about the defects.
TEST_F(BadInput, ValidRenderSucceedsAndLeavesNoTemporaries) {
    scene("scene.json", vdbScene("density"));
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--png", "out.png"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    Image img = readExr(work("out.exr"));
    EXPECT_EQ(img.width, 8);
    EXPECT_TRUE(allFinite(img));
    EXPECT_GT(maxAlpha(img), 0.05f);
    EXPECT_TRUE(fs::exists(work("out.png")));
    EXPECT_TRUE(tempLeftovers(mWork).empty());
}

TEST_F(BadInput, FailedRenderDoesNotClobberExistingOutputs) {
    const std::string exrBytes = "previous render: must survive a failed run\n";
    const std::string pngBytes = std::string("\x89PNG old preview\0\x01\x02", 20);
    writeText(work("out.exr"), exrBytes);
    writeText(work("out.png"), pngBytes);
    scene("broken.json", "{\"camera\": {\"resolution\": [8, 8]},,}");
    const auto before = listDir(mWork);
    CliResult r = cli({"render", "broken.json", "-o", "out.exr", "--png", "out.png"});
    expectCliError(r, {"broken.json"});
    EXPECT_EQ(readBytes(work("out.exr")), exrBytes);
    EXPECT_EQ(readBytes(work("out.png")), pngBytes);
    EXPECT_TRUE(tempLeftovers(mWork).empty());
    EXPECT_EQ(listDir(mWork), before);
}

TEST_F(BadInput, FailureWhileLoadingVolumesDoesNotClobberExistingOutput) {
    const std::string exrBytes = "previous render\n";
    writeText(work("out.exr"), exrBytes);
    scene("scene.json", vdbScene("vel"));  // parses, fails in buildScene
    const auto before = listDir(mWork);
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--stats", "stats.json", "--save-scene", "eff.json"});
    expectCliError(r, {"'vel'"});
    EXPECT_EQ(readBytes(work("out.exr")), exrBytes);
    EXPECT_TRUE(tempLeftovers(mWork).empty());
    EXPECT_FALSE(fs::exists(work("stats.json")));
    // --save-scene is written before volumes are loaded; it is the only file
    // a failed run may add, and only complete.
    auto after = listDir(mWork);
    after.erase("eff.json");
    EXPECT_EQ(after, before);
    if (fs::exists(work("eff.json"))) {
        EXPECT_TRUE(nlohmann::json::accept(readBytes(work("eff.json")))) << "a partial --save-scene file";
    }
}

TEST_F(BadInput, FailedRenderCreatesNoOutput) {
    scene("scene.json", vdbScene("density", "nowhere.vdb"));
    const auto before = listDir(mWork);
    CliResult r = cli({"render", "scene.json", "-o", "new.exr", "--png", "new.png"});
    expectCliError(r, {"nowhere.vdb"});
    EXPECT_EQ(listDir(mWork), before);
}

TEST_F(BadInput, NonExrOutputIsRefused) {
    scene("scene.json", homogeneousScene());
    const auto before = listDir(mWork);
    CliResult r = cli({"render", "scene.json", "-o", "out.png"});
    expectCliError(r, {"out.png", ".exr"});
    r = cli({"render", "scene.json", "-o", "out"});
    expectCliError(r, {"out", ".exr"});
    r = cli({"render", "scene.json", "-o", "out.exr.tmp"});
    expectCliError(r, {"out.exr.tmp", ".exr"});
    EXPECT_EQ(listDir(mWork), before);
}

TEST_F(BadInput, MissingOutputDirectoryIsRefusedBeforeRendering) {
    // A render that would take minutes: refusing it must take no time.
    scene("heavy.json", homogeneousScene());
    const std::string missingDir = work("no_such_dir");
    const std::string out = missingDir + "/out.exr";
    CliResult r = cli({"render", "heavy.json", "-o", out, "--res", "4096x4096", "--spp", "4096"}, 30);
    expectCliError(r, {missingDir});
    EXPECT_LT(r.seconds, 5) << "the output directory must be checked before rendering";
    EXPECT_FALSE(fs::exists(missingDir));
    EXPECT_TRUE(tempLeftovers(mWork).empty());

    std::string msg = errorOf<IoError>([&] { checkWritable(out); });
    EXPECT_CONTAINS(msg, out);
    EXPECT_CONTAINS(msg, missingDir);
}

TEST_F(BadInput, MissingPngDirectoryIsRefusedBeforeRendering) {
    scene("heavy.json", homogeneousScene());
    CliResult r = cli({"render", "heavy.json", "-o", "out.exr", "--png", "no_such_dir/p.png", "--res", "4096x4096",
                       "--spp", "4096"},
                      30);
    expectCliError(r, {"no_such_dir"});
    EXPECT_LT(r.seconds, 5);
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// ===========================================================================
// 11. --set overrides

TEST_F(BadInput, SetOverridesCli) {
    scene("scene.json", homogeneousScene());
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--set", "render.spp=0"});
    expectCliError(r, {"render.spp"});
    r = cli({"render", "scene.json", "-o", "out.exr", "--set", "media.5.g=0.5"});
    expectCliError(r, {"media.5.g", "\"5\""});
    r = cli({"render", "scene.json", "-o", "out.exr", "--set", "media.0.g=1.5"});
    expectCliError(r, {"media[0].g", "1.5"});
    r = cli({"render", "scene.json", "-o", "out.exr", "--set", "render.spp"});
    expectCliError(r, {"render.spp", "key.path=value"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// The command-line spelling of the same mistake: one "vdbmarch: error:" line
// naming the option and value, exit 1 like every other input error, and no
// nonsensical range ("0 not in range 0.000000 to 1797693...").
TEST_F(BadInput, SppZeroOptionCli) {
    scene("scene.json", homogeneousScene());
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--spp", "0"});
    EXPECT_EQ(r.exitCode, 1) << r.err;
    EXPECT_CONTAINS(r.err, "--spp");
    EXPECT_TRUE(hasNumberToken(r.err, "0")) << r.err;
    EXPECT_NOT_CONTAINS(r.err, "179769313486231570814527423731704356798070567525844996598917476803157260780028538760589558632766878171540458953514382464234321326889464182768467546703537516986049910576551282076245490090389328944075868508455133942304583236903222948165808559332123348274797826204144723168738177180919299881250404026184124858368");
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

}  // namespace
