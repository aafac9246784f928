// Bad input gets a clear error and nothing is lost.
//
// Every test feeds the library or the vdbmarch command one specific defect and
// checks (a) the error type (InputError for bad content, IoError for the file
// system), (b) that the message names the file / key path / grid AND the bad
// value, and, for the command, (c) exit status 1, the "vdbmarch: error:" line,
// and that no output file is created, clobbered or left half-written.
//
// VDB fixtures are generated with OpenVDB in a temporary directory per test.

#include <gtest/gtest.h>

#include <regex>

#include "core/error.h"
#include "core/atomic_file.h"
#include "image/exr_io.h"
#include "render/render.h"
#include "scene/auto_scene.h"
#include "scene/scene.h"
#include "parse/scene_desc.h"
#include "volume/medium.h"

#include "test_helpers.h"

using namespace vdbmarch;
using namespace vdbmarch_test;

namespace {

// Replaces every "@KEY@" in `text`.
std::string subst(std::string text, const std::vector<std::pair<std::string, std::string>>& pairs) {
    for (const auto& [key, value] : pairs) {
        const std::string k = "@" + key + "@";
        for (size_t p = text.find(k); p != std::string::npos; p = text.find(k, p + value.size()))
            text.replace(p, k.size(), value);
    }
    return text;
}

// A VDB medium seen by an 8x8 camera; @GRID@ and @FILE@ are filled in.
const char* kVdbScene = R"({
  "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [8, 8]},
  "lights": [{"type": "directional", "direction": [0.3, -1, -0.2], "irradiance": 2}],
  "media": [{"name": "smoke", "type": "vdb", "file": "@FILE@", "grid": "@GRID@", "sigma_a": 0.5, "sigma_s": 2}],
  "background": [0.25, 0.5, 0.75],
  "render": {"spp": 1, "seed": 7}
}
)";

// A homogeneous medium; @MEDIUM@ (extra medium keys) and @CAMERA@ (extra camera keys) are filled in.
const char* kHomogeneousScene = R"({
  "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [8, 8]@CAMERA@},
  "media": [{"name": "fog", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 0.5@MEDIUM@,
             "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
  "render": {"spp": 1}
}
)";

std::string vdbScene(const std::string& grid, const std::string& file = "grids.vdb") {
    return subst(kVdbScene, {{"GRID", grid}, {"FILE", file}});
}

std::string homogeneousScene(const std::string& mediumExtra = "", const std::string& cameraExtra = "") {
    return subst(kHomogeneousScene, {{"MEDIUM", mediumExtra}, {"CAMERA", cameraExtra}});
}

bool allFinite(const Image& img) {
    for (float v : img.rgba)
        if (!std::isfinite(v)) return false;
    return true;
}

float maxAlpha(const Image& img) {
    float a = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) a = std::max(a, img.alpha(x, y));
    return a;
}

// Every pixel shows exactly `bg` with alpha 0 (nothing in front of it).
void expectBackgroundEverywhere(const Image& img, const Color& bg, float tol = 1e-6f) {
    ASSERT_FALSE(img.empty());
    int bad = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            Color c = img.rgb(x, y);
            bool ok = std::fabs(c.x - bg.x) <= tol && std::fabs(c.y - bg.y) <= tol && std::fabs(c.z - bg.z) <= tol &&
                      img.alpha(x, y) == 0.f;
            if (!ok && bad++ < 3)
                ADD_FAILURE() << "pixel (" << x << ", " << y << ") = (" << c.x << ", " << c.y << ", " << c.z
                              << ", a=" << img.alpha(x, y) << "), expected background (" << bg.x << ", " << bg.y
                              << ", " << bg.z << ", a=0)";
        }
    EXPECT_EQ(bad, 0) << "pixels that are not the background";
}

// True when `msg` contains `number` as a whole token (not part of a longer number).
bool hasNumberToken(const std::string& msg, const std::string& number) {
    std::regex re("(^|[^0-9.])" + std::regex_replace(number, std::regex(R"([.+\-])"), R"(\$&)") + "([^0-9]|$)");
    return std::regex_search(msg, re);
}

class BadInput : public ::testing::Test {
protected:
    void SetUp() override {
        setWarningsQuiet(true);
        mWork = mRoot / "work";
        fs::create_directory(mWork);
        writeVdbFixtures(mWork);
    }
    void TearDown() override { setWarningsQuiet(false); }

    std::string work(const std::string& name) const { return (fs::path(mWork) / name).string(); }

    // Writes a scene file into the work directory and returns its path.
    std::string scene(const std::string& name, const std::string& text) const {
        std::string p = work(name);
        writeText(p, text);
        return p;
    }

    CliResult cli(const std::vector<std::string>& args, int timeoutSeconds = 60) const {
        return runCli(args, mWork, mRoot.path(), timeoutSeconds);
    }

    // The command failed the documented way: exit 1 and one "vdbmarch: error:" line naming every needle.
    static void expectCliError(const CliResult& r, const std::vector<std::string>& needles) {
        EXPECT_EQ(r.exitCode, 1) << "stderr: " << r.err;
        EXPECT_EQ(r.err.rfind("vdbmarch: error: ", 0), 0u) << "stderr: " << r.err;
        EXPECT_EQ(countOccurrences(r.err, "vdbmarch: error: "), 1) << "stderr: " << r.err;
        for (const auto& n : needles) EXPECT_CONTAINS(r.err, n);
    }

    TempDir mRoot;
    std::string mWork;
};

// ===========================================================================
// 1. Missing files

TEST_F(BadInput, MissingSceneFileIsIoErrorNamingThePath) {
    const std::string path = work("no_such_scene.json");
    std::string msg = errorOf<IoError>([&] { loadSceneFile(path); });
    EXPECT_CONTAINS(msg, path);
    EXPECT_CONTAINS(msg, "No such file");
}

TEST_F(BadInput, MissingSceneFileCli) {
    CliResult r = cli({"render", "no_such_scene.json", "-o", "out.exr"});
    expectCliError(r, {"no_such_scene.json", "No such file"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// A directory given as the scene is a file-system problem, not "malformed JSON at 1:1".
TEST_F(BadInput, DirectoryAsSceneFileIsIoErrorNamingIt) {
    const std::string dir = work("a_folder.json");
    fs::create_directory(dir);
    std::string msg = errorOf<IoError>([&] { loadSceneFile(dir); });
    EXPECT_CONTAINS(msg, dir);
    EXPECT_CONTAINS(msg, "directory");
    EXPECT_NOT_CONTAINS(msg, "malformed JSON");
}

TEST_F(BadInput, MissingVdbFileReferencedBySceneNamesThePath) {
    const std::string sceneFile = work("scene.json");
    SceneDesc desc = parseSceneText(vdbScene("density", "missing/nowhere.vdb"), sceneFile);
    const std::string resolved = work("missing/nowhere.vdb");
    EXPECT_EQ(desc.media.at(0).file, resolved) << "relative VDB paths resolve against the scene's folder";
    std::string msg = errorOf<IoError>([&] { buildScene(desc); });
    EXPECT_CONTAINS(msg, resolved);
    EXPECT_CONTAINS(msg, "No such file");
}

TEST_F(BadInput, MissingVdbFileCli) {
    scene("scene.json", vdbScene("density", "nowhere.vdb"));
    CliResult r = cli({"render", "scene.json", "-o", "out.exr"});
    // Run from the scene's folder, the path is reported relative to it ("./nowhere.vdb").
    expectCliError(r, {"nowhere.vdb", "No such file"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
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

TEST_F(BadInput, UnknownGridNameCli) {
    scene("scene.json", vdbScene("density"));
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--set", "media.0.grid=smoke"});
    expectCliError(r, {"grids.vdb", "'smoke'", "'density'", "'vel'"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
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

TEST_F(BadInput, MalformedJsonMissingCommaReportsLineAndColumn) {
    const std::string line3 = R"(  "camera": {"position": [0, 0, 5] "look_at": [0, 0, 0]},)";
    const std::string text = "{\n  \"background\": [0, 0, 0],\n" + line3 + "\n  \"render\": {\"spp\": 1}\n}\n";
    // The comma is missing before "look_at": the error is at its first character.
    const size_t col = line3.find("\"look_at\"") + 1;
    ASSERT_EQ(col, 36u);
    const std::string path = scene("broken.json", text);
    std::string msg = errorOf<InputError>([&] { loadSceneFile(path); });
    EXPECT_EQ(msg.rfind(path + ":3:" + std::to_string(col) + ":", 0), 0u)
        << "expected the message to start with " << path << ":3:" << col << ": ; got:\n" << msg;
    EXPECT_CONTAINS(msg, "malformed JSON");
    EXPECT_CONTAINS(msg, line3);  // the offending line is quoted
}

TEST_F(BadInput, MalformedJsonTrailingCommaReportsLineAndColumn) {
    // Line 4, column 23 is the '}' after a trailing comma.
    const std::string text = "{\n  \"camera\": {\"resolution\": [8, 8]},\n\n  \"render\": {\"spp\": 1,}\n}\n";
    std::string msg = errorOf<InputError>([&] { parseSceneText(text, "trailing.json"); });
    EXPECT_EQ(msg.rfind("trailing.json:4:23:", 0), 0u) << msg;
    EXPECT_CONTAINS(msg, "malformed JSON");
}

TEST_F(BadInput, MalformedJsonCliPrintsFileLineColumn) {
    scene("broken.json", "{\n  \"camera\": {\n    \"position\": [0, 0, 5]\n    \"look_at\": [0, 0, 0]\n  }\n}\n");
    CliResult r = cli({"render", "broken.json", "-o", "out.exr"});
    // The comma missing at the end of line 3 is noticed at "look_at" (line 4, column 5).
    expectCliError(r, {"broken.json:4:5:", "malformed JSON"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// ===========================================================================
// 7. Unknown keys

TEST_F(BadInput, UnknownMediumKeySuggestsNearest) {
    std::string text = homogeneousScene(", \"sigma_ss\": 0.5");
    std::string msg = errorOf<InputError>([&] { parseSceneText(text, "typo.json"); });
    EXPECT_CONTAINS(msg, "typo.json");
    EXPECT_CONTAINS(msg, "media[0].sigma_ss");
    EXPECT_CONTAINS(msg, "did you mean 'sigma_s'");
}

TEST_F(BadInput, UnknownCameraAndRootKeysSuggestNearest) {
    std::string msg = errorOf<InputError>([&] { parseSceneText(homogeneousScene("", ", \"lookat\": [0, 0, 0]"), "typo.json"); });
    EXPECT_CONTAINS(msg, "camera.lookat");
    EXPECT_CONTAINS(msg, "did you mean 'look_at'");

    msg = errorOf<InputError>([&] { parseSceneText(R"({"backgroud": [0, 0, 0]})", "typo.json"); });
    EXPECT_CONTAINS(msg, "'backgroud'");
    EXPECT_CONTAINS(msg, "did you mean 'background'");

    msg = errorOf<InputError>([&] { parseSceneText(R"({"render": {"sppp": 4}})", "typo.json"); });
    EXPECT_CONTAINS(msg, "render.sppp");
    EXPECT_CONTAINS(msg, "did you mean 'spp'");
}

TEST_F(BadInput, UnknownKeyCli) {
    scene("typo.json", homogeneousScene(", \"sigma_ss\": 0.5"));
    CliResult r = cli({"render", "typo.json", "-o", "out.exr"});
    expectCliError(r, {"typo.json", "media[0].sigma_ss", "did you mean 'sigma_s'"});
}

// ===========================================================================
// 8. Values out of range

TEST_F(BadInput, NegativeSigmaA) {
    std::string text = subst(kHomogeneousScene, {{"MEDIUM", ""}, {"CAMERA", ""}});
    size_t p = text.find("\"sigma_a\": 0.1");
    ASSERT_NE(p, std::string::npos);
    text.replace(p, std::strlen("\"sigma_a\": 0.1"), "\"sigma_a\": [0.1, -0.25, 0.1]");
    std::string msg = errorOf<InputError>([&] { parseSceneText(text, "neg.json"); });
    EXPECT_CONTAINS(msg, "neg.json");
    EXPECT_CONTAINS(msg, "media[0].sigma_a");
    EXPECT_CONTAINS(msg, "-0.25");
}

TEST_F(BadInput, NegativeScalarSigmaAOnVdbMedium) {
    std::string text = vdbScene("density");
    size_t p = text.find("\"sigma_a\": 0.5");
    ASSERT_NE(p, std::string::npos);
    text.replace(p, std::strlen("\"sigma_a\": 0.5"), "\"sigma_a\": -3");
    std::string msg = errorOf<InputError>([&] { parseSceneText(text, "neg.json"); });
    EXPECT_CONTAINS(msg, "media[0].sigma_a");
    EXPECT_TRUE(hasNumberToken(msg, "-3")) << msg;
}

TEST_F(BadInput, HenyeyGreensteinGOfOne) {
    std::string msg = errorOf<InputError>([&] { parseSceneText(homogeneousScene(", \"g\": 1"), "g.json"); });
    EXPECT_CONTAINS(msg, "g.json");
    EXPECT_CONTAINS(msg, "media[0].g");
    EXPECT_TRUE(std::regex_search(msg, std::regex(R"((got|=|value)\s*1(\.0*)?([^0-9.]|$))"))) << msg;
}

TEST_F(BadInput, HenyeyGreensteinGOfMinusOnePointFive) {
    std::string msg = errorOf<InputError>([&] { parseSceneText(homogeneousScene(", \"g\": -1.5"), "g.json"); });
    EXPECT_CONTAINS(msg, "media[0].g");
    EXPECT_TRUE(hasNumberToken(msg, "-1.5")) << msg;
}

TEST_F(BadInput, ZeroResolution) {
    std::string msg =
        errorOf<InputError>([&] { parseSceneText(R"({"camera": {"resolution": [0, 480]}})", "res.json"); });
    EXPECT_CONTAINS(msg, "res.json");
    EXPECT_CONTAINS(msg, "camera.resolution");
    EXPECT_TRUE(msg.find("0x480") != std::string::npos || msg.find("[0,480]") != std::string::npos) << msg;
}

TEST_F(BadInput, HugeResolution) {
    std::string msg =
        errorOf<InputError>([&] { parseSceneText(R"({"camera": {"resolution": [100000, 100000]}})", "res.json"); });
    EXPECT_CONTAINS(msg, "camera.resolution");
    EXPECT_CONTAINS(msg, "100000");
}

TEST_F(BadInput, HugeResolutionFromResOptionCli) {
    scene("scene.json", homogeneousScene());
    CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--res", "100000x100000"});
    expectCliError(r, {"camera.resolution", "100000"});
    EXPECT_LT(r.seconds, 10) << "refused before any allocation or rendering";
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

TEST_F(BadInput, CameraPositionEqualsLookAt) {
    std::string msg = errorOf<InputError>([&] {
        parseSceneText(R"({"camera": {"position": [1, 2, 3], "look_at": [1, 2, 3]}})", "cam.json");
    });
    EXPECT_CONTAINS(msg, "cam.json");
    EXPECT_TRUE(msg.find("camera.look_at") != std::string::npos || msg.find("camera.position") != std::string::npos)
        << msg;
    EXPECT_TRUE(mentionsVec3(msg, "1", "2", "3")) << msg;
}

TEST_F(BadInput, UpParallelToViewDirection) {
    // Looking down -z with up = +2z: parallel (and not unit length, to make the value recognisable).
    std::string msg = errorOf<InputError>([&] {
        parseSceneText(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 0, 2]}})", "cam.json");
    });
    EXPECT_CONTAINS(msg, "cam.json");
    EXPECT_CONTAINS(msg, "camera.up");
    EXPECT_TRUE(mentionsVec3(msg, "0", "0", "2")) << "the message should show the bad up vector: " << msg;
}

TEST_F(BadInput, UpAntiParallelToViewDirection) {
    std::string msg = errorOf<InputError>([&] {
        parseSceneText(R"({"camera": {"position": [0, 4, 0], "look_at": [0, 0, 0], "up": [0, 1, 0]}})", "cam.json");
    });
    EXPECT_CONTAINS(msg, "camera.up");
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
    scene("heavy.json", subst(kHomogeneousScene, {{"MEDIUM", ""}, {"CAMERA", ""}}));
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

TEST_F(BadInput, SetSppZeroIsRefusedWithKeyPath) {
    std::string msg = errorOf<InputError>([&] { parseSceneText(homogeneousScene(), "s.json", {"render.spp=0"}); });
    EXPECT_CONTAINS(msg, "s.json");
    EXPECT_CONTAINS(msg, "render.spp");
    EXPECT_TRUE(hasNumberToken(msg, "0")) << msg;
}

TEST_F(BadInput, SetOutOfRangeIndexNamesIt) {
    nlohmann::json doc = nlohmann::json::parse(homogeneousScene());
    const nlohmann::json original = doc;
    std::string msg = errorOf<InputError>([&] { applyOverride(doc, "media.5.g=0.5"); });
    EXPECT_CONTAINS(msg, "media.5.g");
    EXPECT_CONTAINS(msg, "\"5\"");
    EXPECT_CONTAINS(msg, "1 item");
    EXPECT_EQ(doc, original) << "a refused override must not modify the document";

    msg = errorOf<InputError>([&] { loadAutoScene(work("grids.vdb"), {"media.5.g=0.5"}); });
    EXPECT_CONTAINS(msg, "media.5.g");
}

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

// ===========================================================================
// 12. Surfaces naming media that do not exist

TEST_F(BadInput, SurfaceInteriorNamingUnknownMediumSuggestsNearest) {
    const char* text = R"({
  "media": [{"name": "smoke", "type": "homogeneous", "sigma_s": 1},
            {"name": "water", "type": "homogeneous", "sigma_s": 0.1}],
  "surfaces": [{"shape": "sphere", "interior": "smoke"},
               {"shape": "box", "interior": "smok"}]
})";
    std::string msg = errorOf<InputError>([&] { parseSceneText(text, "surf.json"); });
    EXPECT_CONTAINS(msg, "surf.json");
    EXPECT_CONTAINS(msg, "surfaces[1].interior");
    EXPECT_CONTAINS(msg, "\"smok\"");
    EXPECT_CONTAINS(msg, "did you mean \"smoke\"");
}

TEST_F(BadInput, SurfaceExteriorNamingUnknownMediumSuggestsNearest) {
    const char* text = R"({
  "media": [{"name": "water", "type": "homogeneous", "sigma_s": 0.1}],
  "surfaces": [{"shape": "sphere", "exterior": "watr"}]
})";
    std::string msg = errorOf<InputError>([&] { parseSceneText(text, "surf.json"); });
    EXPECT_CONTAINS(msg, "surfaces[0].exterior");
    EXPECT_CONTAINS(msg, "\"watr\"");
    EXPECT_CONTAINS(msg, "did you mean \"water\"");
}

TEST_F(BadInput, SurfaceInteriorWithNoMediaAtAll) {
    std::string msg = errorOf<InputError>(
        [&] { parseSceneText(R"({"surfaces": [{"shape": "sphere", "interior": "smoke"}]})", "surf.json"); });
    EXPECT_CONTAINS(msg, "surfaces[0].interior");
    EXPECT_CONTAINS(msg, "\"smoke\"");
}

}  // namespace
