// Animation frames (parse/frames.h): the frame token in file paths, the
// --frames range, and scenes parsed for a frame (their paths substituted in
// the description and in the recorded document; without a frame, a token is
// an error naming the file, the key path and the value).
#include <gtest/gtest.h>

#include "core/error.h"
#include "parse/frames.h"
#include "parse/scene_desc.h"
#include "support/support.h"

using namespace vdbmarch;
using namespace vdbmarch::test;

namespace {

// ===========================================================================
// The token

TEST(FrameToken, PadsToTheRunsLength) {
    EXPECT_EQ(substituteFrame("cloud.####.vdb", 7), "cloud.0007.vdb");
    EXPECT_EQ(substituteFrame("cloud.####.vdb", 0), "cloud.0000.vdb");
    EXPECT_EQ(substituteFrame("cloud.####.vdb", 1234), "cloud.1234.vdb");
    EXPECT_EQ(substituteFrame("cloud.#.vdb", 7), "cloud.7.vdb");
    EXPECT_EQ(substituteFrame("c_######", 42), "c_000042");
}

TEST(FrameToken, LongNumbersAreNeverTruncated) {
    EXPECT_EQ(substituteFrame("cloud.####.vdb", 12345), "cloud.12345.vdb");
    EXPECT_EQ(substituteFrame("cloud.#.vdb", 999999999), "cloud.999999999.vdb");
}

TEST(FrameToken, EveryRunIsReplacedWithItsOwnPadding) {
    EXPECT_EQ(substituteFrame("shot_##/cloud.####.vdb", 7), "shot_07/cloud.0007.vdb");
    EXPECT_EQ(substituteFrame("###a#b##", 5), "005a5b05");
    EXPECT_EQ(substituteFrame("####", 3), "0003");
}

TEST(FrameToken, NoTokenLeavesThePathAsItIs) {
    EXPECT_FALSE(hasFrameToken("cloud.0001.vdb"));
    EXPECT_TRUE(hasFrameToken("cloud.#.vdb"));
    EXPECT_EQ(substituteFrame("cloud.0001.vdb", 7), "cloud.0001.vdb");
    EXPECT_EQ(substituteFrame("", 7), "");
}

TEST(FrameToken, NegativeFramesAreRefused) {
    expectErrorContaining<InputError>([] { substituteFrame("a.####.vdb", -1); }, {"-1", "non-negative"});
}

// ===========================================================================
// --frames

TEST(FrameRange, SingleFrameRangeAndStep) {
    EXPECT_EQ(parseFrameRange("7"), std::vector<int>({7}));
    EXPECT_EQ(parseFrameRange("0"), std::vector<int>({0}));
    EXPECT_EQ(parseFrameRange("1-3"), std::vector<int>({1, 2, 3}));
    EXPECT_EQ(parseFrameRange("5-5"), std::vector<int>({5}));
    EXPECT_EQ(parseFrameRange("1-5:2"), std::vector<int>({1, 3, 5}));
    EXPECT_EQ(parseFrameRange("1-6:2"), std::vector<int>({1, 3, 5}));
    EXPECT_EQ(parseFrameRange("10-12:1"), std::vector<int>({10, 11, 12}));
    EXPECT_EQ(parseFrameRange("3-3:10"), std::vector<int>({3}));
}

TEST(FrameRange, BadRangesNameTheOptionAndTheText) {
    // B < A
    expectErrorContaining<InputError>([] { parseFrameRange("5-1"); }, {"--frames 5-1", "last frame 1", "first 5"});
    // step < 1
    expectErrorContaining<InputError>([] { parseFrameRange("1-5:0"); }, {"--frames 1-5:0", "step", "at least 1"});
    expectErrorContaining<InputError>([] { parseFrameRange("1-5:-2"); }, {"--frames 1-5:-2", "step"});
    expectErrorContaining<InputError>([] { parseFrameRange("1-5:"); }, {"--frames 1-5:", "step"});
    // negative frames
    expectErrorContaining<InputError>([] { parseFrameRange("-3"); }, {"--frames -3", "non-negative"});
    expectErrorContaining<InputError>([] { parseFrameRange("-3-4"); }, {"--frames -3-4", "non-negative"});
    // garbage
    for (const char* bad : {"", "a", "1-", "1-b", "1..3", "1-3x", " 1-3", "1-3 ", "1,2,3", "1:2", "1-2-3", "0x10", "1.5"})
        expectErrorContaining<InputError>([&] { parseFrameRange(bad); }, {"--frames", "expected N, A-B or A-B:STEP"});
    // too large
    expectErrorContaining<InputError>([] { parseFrameRange("1-99999999999"); }, {"--frames 1-99999999999", "at most"});
    expectErrorContaining<InputError>([] { parseFrameRange("0-5000000"); }, {"--frames 0-5000000", "5000001 frames"});
}

// ===========================================================================
// Scenes for a frame

const char* const kFrameScene = R"({
  "media": [{"name": "smoke", "type": "vdb", "file": "smoke.####.vdb", "sigma_s": 1},
            {"name": "fog", "type": "homogeneous", "sigma_s": 0.1}],
  "surfaces": [{"shape": "mesh", "file": "/abs/mesh_##.obj"},
               {"shape": "vdb_isosurface", "file": "iso.###.vdb"},
               {"shape": "sphere"}],
  "environment": {"file": "sky.####.exr"}
}
)";

TEST(FrameScene, EveryFilePathIsSubstituted) {
    const SceneDesc d = parseSceneText(kFrameScene, "/shots/a/scene.json", {}, 12);
    ASSERT_EQ(d.media.size(), 2u);
    EXPECT_EQ(d.media[0].file, "/shots/a/smoke.0012.vdb");
    EXPECT_EQ(d.surfaces[0].file, "/abs/mesh_12.obj");
    EXPECT_EQ(d.surfaces[1].file, "/shots/a/iso.012.vdb");
    EXPECT_EQ(d.environment.file, "/shots/a/sky.0012.exr");
    ASSERT_TRUE(d.frame.has_value());
    EXPECT_EQ(*d.frame, 12);
    // The recorded document names the frame's files (no token left).
    EXPECT_NOT_CONTAINS(d.jsonText, "#");
    EXPECT_CONTAINS(d.jsonText, "smoke.0012.vdb");
    EXPECT_CONTAINS(d.jsonText, "sky.0012.exr");
    // sceneFilePaths lists what a frame opens, by key.
    const auto paths = sceneFilePaths(d);
    ASSERT_EQ(paths.size(), 4u);
    EXPECT_EQ(paths[0].first, "media[0].file");
    EXPECT_EQ(paths[1].first, "surfaces[0].file");
    EXPECT_EQ(paths[2].second, "/shots/a/iso.012.vdb");
    EXPECT_EQ(paths[3].first, "environment.file");
}

// A frame's scene is the scene that names its files directly: same
// description, same recorded document (hence the same scene hash: a cache
// baked for that frame is accepted).
TEST(FrameScene, SameAsTheSceneNamingTheFrameDirectly) {
    const SceneDesc framed = parseSceneText(kFrameScene, "/shots/a/scene.json", {}, 3);
    std::string text = kFrameScene;
    for (auto [from, to] : {std::pair<std::string, std::string>{"smoke.####", "smoke.0003"}, {"mesh_##", "mesh_03"},
                            {"iso.###", "iso.003"}, {"sky.####", "sky.0003"}})
        text.replace(text.find(from), from.size(), to);
    const SceneDesc plain = parseSceneText(text, "/shots/a/scene.json");
    EXPECT_EQ(framed.jsonText, plain.jsonText);
    EXPECT_EQ(sceneHash(framed), sceneHash(plain));
    EXPECT_FALSE(plain.frame.has_value());
}

TEST(FrameScene, TokenWithoutAFrameNamesFileKeyAndValue) {
    const std::string msg = errorOf<InputError>([] { parseSceneText(kFrameScene, "scene.json"); });
    EXPECT_CONTAINS(msg, "scene.json:2:");  // line and column of the key
    EXPECT_CONTAINS(msg, "media[0].file");
    EXPECT_CONTAINS(msg, "smoke.####.vdb");
    EXPECT_CONTAINS(msg, "--frames");
    // Each key is checked: a token only in the environment is named there.
    const std::string env = R"({"environment": {"file": "sky.##.exr"}})";
    expectErrorContaining<InputError>([&] { parseSceneText(env, "e.json"); },
                                      {"e.json", "environment.file", "sky.##.exr", "--frames"});
    const std::string surf = R"({"surfaces": [{"shape": "sphere"}, {"shape": "mesh", "file": "m#.obj"}]})";
    expectErrorContaining<InputError>([&] { parseSceneText(surf, "s.json"); },
                                      {"s.json", "surfaces[1].file", "m#.obj", "--frames"});
}

TEST(FrameScene, TokenSetByAnOverride) {
    const std::string text = R"({"media": [{"name": "smoke", "type": "vdb", "file": "smoke.vdb", "sigma_s": 1}]})";
    expectErrorContaining<InputError>(
        [&] { parseSceneText(text, "o.json", {"media.0.file=other.###.vdb"}); },
        {"o.json", "media[0].file", "other.###.vdb", "--frames"});
    const SceneDesc d = parseSceneText(text, "/x/o.json", {"media.0.file=other.###.vdb"}, 4);
    EXPECT_EQ(d.media[0].file, "/x/other.004.vdb");
}

TEST(FrameScene, ScenesWithoutTheTokenAreUnchangedByAFrame) {
    const std::string text = R"({"media": [{"name": "smoke", "type": "vdb", "file": "smoke.vdb", "sigma_s": 1}]})";
    const SceneDesc a = parseSceneText(text, "/x/s.json"), b = parseSceneText(text, "/x/s.json", {}, 9);
    EXPECT_EQ(a.jsonText, b.jsonText);
    EXPECT_EQ(b.media[0].file, "/x/smoke.vdb");
}

}  // namespace
