// Bad environment maps through the command: a clear message naming the file
// (and the bad size), exit 1, nothing written; bad texels become 0 with one
// warning that counts them.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "image/exr_io.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

// The homogeneous fog scene lit by the map `file` only.
std::string sceneWithMap(const std::string& file) {
    std::string s = homogeneousScene();
    const size_t at = s.rfind('}');
    return s.substr(0, at) + ", \"environment\": {\"file\": \"" + file + "\"}\n}\n";
}

Image flatMap(int w, int h, const Color& c) {
    Image img(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) img.set(x, y, c, 1);
    return img;
}

TEST_F(BadInput, MissingEnvironmentMapNamesTheFileCli) {
    scene("scene.json", sceneWithMap("no_sky.exr"));
    const CliResult r = cli({"render", "scene.json", "-o", "out.exr"});
    expectCliError(r, {"no_sky.exr"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

TEST_F(BadInput, EnvironmentMapThatIsNotAnExrCli) {
    writeText(work("sky.exr"), "not an image");
    scene("scene.json", sceneWithMap("sky.exr"));
    const CliResult r = cli({"render", "scene.json", "-o", "out.exr"});
    expectCliError(r, {"sky.exr", "not an OpenEXR file"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

TEST_F(BadInput, EnvironmentMapThatIsNotTwoToOneNamesItsSizeCli) {
    writeExr(work("square.exr"), flatMap(16, 16, Color(1)));
    scene("scene.json", sceneWithMap("square.exr"));
    const CliResult r = cli({"render", "scene.json", "-o", "out.exr"});
    expectCliError(r, {"square.exr", "environment.file", "16x16", "twice as wide"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

TEST_F(BadInput, EnvironmentWithABackgroundIsRefusedCli) {
    writeExr(work("sky.exr"), flatMap(16, 8, Color(1)));
    std::string s = sceneWithMap("sky.exr");
    s = s.substr(0, s.rfind('}')) + ", \"background\": [0.1, 0.1, 0.1]}\n";
    scene("scene.json", s);
    const CliResult r = cli({"render", "scene.json", "-o", "out.exr"});
    expectCliError(r, {"scene.json", "environment", "background"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

TEST_F(BadInput, EnvironmentKeysAreChecked) {
    writeExr(work("sky.exr"), flatMap(16, 8, Color(1)));
    scene("a.json", sceneWithMap("sky.exr"));
    CliResult r = cli({"render", "a.json", "-o", "out.exr", "--set", "environment.scale=-1"});
    expectCliError(r, {"environment.scale", "-1"});
    r = cli({"render", "a.json", "-o", "out.exr", "--set", "environment.rotaton=3"});
    expectCliError(r, {"environment.rotaton", "rotation"});
    EXPECT_FALSE(fs::exists(work("out.exr")));
}

// NaN, infinite and negative texels become 0, with one warning that counts
// them; the render finishes with finite pixels.
TEST_F(BadInput, BadTexelsAreZeroedWithOneCountingWarningCli) {
    Image map = flatMap(16, 8, Color(0.5f));
    map.set(1, 1, Color(std::numeric_limits<float>::quiet_NaN(), 1, 1), 1);
    map.set(2, 2, Color(std::numeric_limits<float>::infinity(), -3, 1), 1);
    writeExr(work("sky.exr"), map);
    scene("scene.json", sceneWithMap("sky.exr"));
    const CliResult r = cli({"render", "scene.json", "-o", "out.exr", "--spp", "2"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(countOccurrences(r.err, "NaN, infinite or negative"), 1) << r.err;
    EXPECT_CONTAINS(r.err, "3 texel channels");
    const Image out = readExr(work("out.exr"));
    EXPECT_TRUE(allFinite(out));
}

}  // namespace
}  // namespace vdbmarch
