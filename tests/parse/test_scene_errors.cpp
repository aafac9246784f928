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
// This file: scene files the parser refuses (missing or malformed files,
// unknown keys, values out of range, --set overrides, surfaces naming media
// that do not exist).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <regex>

#include "core/error.h"
#include "parse/scene_desc.h"
#include "parse/scene_json.h"
#include "scene/auto_scene.h"
#include "support/support.h"

using namespace vdbmarch;
using namespace vdbmarch::test;

namespace {

namespace fs = std::filesystem;

// ===========================================================================
// 1. Missing files

TEST_F(BadInput, MissingSceneFileIsIoErrorNamingThePath) {
    const std::string path = work("no_such_scene.json");
    std::string msg = errorOf<IoError>([&] { loadSceneFile(path); });
    EXPECT_CONTAINS(msg, path);
    EXPECT_CONTAINS(msg, "No such file");
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

// ===========================================================================
// 8. Values out of range

TEST_F(BadInput, NegativeSigmaA) {
    std::string text = homogeneousScene();
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

// Blackbody emission keys: each mode refuses the other's keys, values are
// range-checked, all naming the key path and the value.
TEST_F(BadInput, BlackbodyEmissionKeysAreChecked) {
    auto error = [&](const std::string& emission) {
        std::string text = vdbScene("density");
        size_t p = text.find("\"sigma_a\": 0.5");
        EXPECT_NE(p, std::string::npos);
        text.insert(p, "\"emission\": " + emission + ", ");
        return errorOf<InputError>([&] { parseSceneText(text, "bb.json"); });
    };
    std::string msg = error(R"({"blackbody": true, "scale": 3})");
    EXPECT_CONTAINS(msg, "bb.json");
    EXPECT_CONTAINS(msg, "media[0].emission.scale");
    EXPECT_CONTAINS(msg, "intensity");
    msg = error(R"({"intensity": 2})");
    EXPECT_CONTAINS(msg, "media[0].emission.intensity");
    EXPECT_CONTAINS(msg, "blackbody");
    msg = error(R"({"blackbody": true, "temperature_scale": -1})");
    EXPECT_CONTAINS(msg, "media[0].emission.temperature_scale");
    EXPECT_TRUE(hasNumberToken(msg, "-1")) << msg;
    msg = error(R"({"blackbody": true, "intensity": -0.5})");
    EXPECT_CONTAINS(msg, "media[0].emission.intensity");
    EXPECT_TRUE(hasNumberToken(msg, "-0.5")) << msg;
    msg = error(R"({"blackbody": "yes"})");
    EXPECT_CONTAINS(msg, "media[0].emission.blackbody");
    msg = error(R"({"blackbody": true, "temperature_ofset": 3})");
    EXPECT_CONTAINS(msg, "temperature_offset");
}

// Found by fuzzing (tools/fuzz.sh, fuzz_scene_json): a number too large for
// a double is nlohmann's out_of_range, not a parse_error, and escaped the
// parser without the file's name.
TEST_F(BadInput, NumberTooLargeForADoubleNamesTheFile) {
    for (const char* text : {"111111111111111E11000000002060149047", R"({"render": {"spp": 1e400}})"}) {
        std::string msg = errorOf<InputError>([&] { parseSceneText(text, "huge.json"); });
        EXPECT_CONTAINS(msg, "huge.json");
        EXPECT_CONTAINS(msg, "malformed JSON");
    }
}

TEST_F(BadInput, ProgressivePhotonSettingsOutOfRange) {
    std::string msg = errorOf<InputError>([&] { parseSceneText(R"({"photons": {"alpha": 1.5}})", "ppm.json"); });
    EXPECT_CONTAINS(msg, "ppm.json");
    EXPECT_CONTAINS(msg, "photons.alpha");
    EXPECT_CONTAINS(msg, "1.5");
    msg = errorOf<InputError>([&] { parseSceneText(R"({"photons": {"spp_per_pass": -2}})", "ppm.json"); });
    EXPECT_CONTAINS(msg, "photons.spp_per_pass");
    EXPECT_TRUE(hasNumberToken(msg, "-2")) << msg;
    msg = errorOf<InputError>([&] { parseSceneText(R"({"photons": {"progressive": "yes"}})", "ppm.json"); });
    EXPECT_CONTAINS(msg, "photons.progressive");
}

// Render keys of earlier versions: the A/B switches that moved to
// "experiments" say where they went; removed options say they were removed.
TEST_F(BadInput, MovedAndRemovedRenderKeysSaySo) {
    std::string msg = errorOf<InputError>([&] { parseSceneText(R"({"render": {"beam_directions": false}})", "old.json"); });
    EXPECT_CONTAINS(msg, "old.json");
    EXPECT_CONTAINS(msg, "render.beam_directions");
    EXPECT_CONTAINS(msg, "experiments.beam_directions");
    for (const char* key : {"product_sampling", "guided_roulette", "majorant"}) {
        msg = errorOf<InputError>([&] { parseSceneText(homogeneousScene(), "old.json", {str("render.", key, "=true")}); });
        EXPECT_CONTAINS(msg, str("render.", key));
        EXPECT_CONTAINS(msg, "removed");
    }
    msg = errorOf<InputError>([&] { parseSceneText(R"({"render": {"method": "guided_path"}})", "old.json"); });
    EXPECT_CONTAINS(msg, "render.method");
    EXPECT_CONTAINS(msg, "guided_path");
    const SceneDesc d = parseSceneText(homogeneousScene(), "new.json",
                                       {"experiments.beam_directions=false", "experiments.volume_sampling=\"distance\""});
    EXPECT_FALSE(d.experiments.beamDirections);
    EXPECT_TRUE(d.experiments.sphereCaustics);
    EXPECT_EQ(d.experiments.volumeSampling, VolumeSampling::Distance);
    msg = errorOf<InputError>([&] { parseSceneText(R"({"experiments": {"volume_sampling": "fast"}})", "x.json"); });
    EXPECT_CONTAINS(msg, "experiments.volume_sampling");
    EXPECT_CONTAINS(msg, "fast");
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
