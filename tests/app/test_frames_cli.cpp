// Animation frames through the command (docs/farm.md, "Frames"): `--frames
// A-B[:STEP]` renders (or bakes) each frame in turn, the frame token '####'
// replaced in the input, the scene's file paths and the output names; each
// frame's pixels equal, bit for bit, a render of a scene that names that
// frame's file directly (same seed). Bad ranges, a token without --frames,
// one output for several frames and a missing frame file are errors that
// name the option, key, file and frame, and leave no output behind.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>
#include <string>

#include "image/exr_io.h"
#include "support/support.h"

using namespace vdbmarch;
using namespace vdbmarch::test;

namespace {

namespace fs = std::filesystem;

class Frames : public BadInput {
protected:
    // smoke.<NNNN>.vdb for each frame: boxes of different size and density,
    // so the frames' images differ.
    void writeSequence(std::initializer_list<int> frames) const {
        for (int f : frames) {
            char name[32];
            std::snprintf(name, sizeof name, "smoke.%04d.vdb", f);
            writeBoxGrid(work(name), Index3(-2 - f % 3), Index3(1 + f % 2), 0.5f * float(f), kVoxel);
        }
    }
    static std::string frameName(const std::string& stem, int f, const std::string& ext) {
        char buf[16];
        std::snprintf(buf, sizeof buf, ".%04d", f);
        return stem + buf + ext;
    }
    // The pixels of an EXR of the work folder.
    Image exr(const std::string& name) const { return readExr(work(name)); }
    static bool bitIdentical(const Image& a, const Image& b) {
        return a.width == b.width && a.height == b.height && a.rgba.size() == b.rgba.size() &&
               std::memcmp(a.rgba.data(), b.rgba.data(), a.rgba.size() * sizeof(float)) == 0;
    }
    std::string header(const std::string& name, const std::string& key) const {
        for (const auto& [k, v] : readExrStringAttributes(work(name)))
            if (k == key) return v;
        return "(absent)";
    }
};

// ===========================================================================
// Sequences

TEST_F(Frames, SequenceEqualsEachFrameRenderedAlone) {
    writeSequence({1, 2, 3});
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    CliResult r = cli({"render", "shot.json", "--frames", "1-3", "-o", "out.####.exr", "--png", "out.####.png",
                       "--stats", "stats.####.json", "--save-scene", "saved.####.json", "--threads", "2", "-q"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (int f : {1, 2, 3}) {
        SCOPED_TRACE(f);
        for (const std::string& name : {frameName("out", f, ".exr"), frameName("out", f, ".png"),
                                        frameName("stats", f, ".json"), frameName("saved", f, ".json")})
            EXPECT_TRUE(fs::exists(work(name))) << name;
        EXPECT_EQ(header(frameName("out", f, ".exr"), "vdbmarch:frame"), std::to_string(f));
        EXPECT_CONTAINS(readBytes(work(frameName("saved", f, ".json"))), frameName("smoke", f, ".vdb"));
        // The same frame alone, from a scene that names its file directly.
        scene("alone.json", vdbScene("density", frameName("smoke", f, ".vdb")));
        CliResult one = cli({"render", "alone.json", "-o", "alone.exr", "--threads", "1", "-q"});
        ASSERT_EQ(one.exitCode, 0) << one.err;
        EXPECT_TRUE(bitIdentical(exr(frameName("out", f, ".exr")), exr("alone.exr")));
        EXPECT_EQ(header("alone.exr", "vdbmarch:frame"), "(absent)");
        EXPECT_CONTAINS(header(frameName("out", f, ".exr"), "vdbmarch:scene"), frameName("smoke", f, ".vdb"));
    }
    EXPECT_FALSE(fs::exists(work("out.####.exr")));
    // The frames differ, so the equality above is not vacuous.
    EXPECT_FALSE(bitIdentical(exr("out.0001.exr"), exr("out.0002.exr")));
    EXPECT_FALSE(bitIdentical(exr("out.0002.exr"), exr("out.0003.exr")));
    EXPECT_TRUE(tempLeftovers(mWork).empty());
}

TEST_F(Frames, StepRendersEveryStepthFrame) {
    writeSequence({1, 3, 5});  // 2 and 4 do not exist and are not needed
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    CliResult r = cli({"render", "shot.json", "--frames", "1-5:2", "-o", "out.####.exr", "-q"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    std::set<std::string> expected = {"out.0001.exr", "out.0003.exr", "out.0005.exr"};
    std::set<std::string> outputs;
    for (const std::string& name : listDir(mWork))
        if (name.rfind("out.", 0) == 0) outputs.insert(name);
    EXPECT_EQ(outputs, expected);
}

TEST_F(Frames, OneFrameNeedsNoTokenInTheOutput) {
    writeSequence({7});
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    CliResult r = cli({"render", "shot.json", "--frames", "7", "-o", "seven.exr", "-q"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(header("seven.exr", "vdbmarch:frame"), "7");
}

TEST_F(Frames, BareVdbSequenceEqualsEachFileRenderedAlone) {
    writeSequence({1, 2});
    CliResult r = cli({"render", "smoke.####.vdb", "--frames", "1-2", "-o", "auto.####.exr", "--res", "8x6",
                       "--spp", "1", "-q"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (int f : {1, 2}) {
        CliResult one = cli({"render", frameName("smoke", f, ".vdb"), "-o", "alone.exr", "--res", "8x6", "--spp", "1", "-q"});
        ASSERT_EQ(one.exitCode, 0) << one.err;
        EXPECT_TRUE(bitIdentical(exr(frameName("auto", f, ".exr")), exr("alone.exr"))) << f;
    }
}

// bake --frames writes a cache per frame; render --cache cache.####.vdb reads
// each frame's own (the scene hash follows the frame's files, so frame 2's
// scene refuses frame 1's cache).
TEST_F(Frames, BakePerFrameThenRenderWithEachFramesCache) {
    writeSequence({1, 2});
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    CliResult b = cli({"bake", "shot.json", "--frames", "1-2", "-o", "cache.####.vdb", "--photons", "2000",
                       "--stats", "bake.####.json", "-q"});
    ASSERT_EQ(b.exitCode, 0) << b.err;
    for (const char* name : {"cache.0001.vdb", "cache.0002.vdb", "bake.0001.json", "bake.0002.json"})
        EXPECT_TRUE(fs::exists(work(name))) << name;
    CliResult r = cli({"render", "shot.json", "--frames", "1-2", "-o", "out.####.exr", "--cache", "cache.####.vdb",
                       "--method", "guided", "--set", "render.li=cache", "-q"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(work("out.0002.exr")));
    scene("frame2.json", vdbScene("density", "smoke.0002.vdb"));
    r = cli({"render", "frame2.json", "-o", "wrong.exr", "--cache", "cache.0001.vdb", "--method", "guided", "-q"});
    EXPECT_EQ(r.exitCode, 1) << r.err;
    EXPECT_FALSE(fs::exists(work("wrong.exr")));
}

// ===========================================================================
// Errors

TEST_F(Frames, TokenWithoutFramesNamesTheSceneKeyAndValue) {
    writeSequence({1});
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    CliResult r = cli({"render", "shot.json", "-o", "out.exr"});
    expectCliError(r, {"shot.json", "media[0].file", "smoke.####.vdb", "--frames"});
    r = cli({"bake", "shot.json", "-o", "cache.vdb"});
    expectCliError(r, {"shot.json", "media[0].file", "smoke.####.vdb", "--frames"});
    // A bare .vdb input and the outputs too.
    r = cli({"render", "smoke.####.vdb", "-o", "out.exr"});
    expectCliError(r, {"smoke.####.vdb", "--frames"});
    r = cli({"render", "smoke.0001.vdb", "-o", "out.####.exr"});
    expectCliError(r, {"-o out.####.exr", "--frames"});
    r = cli({"render", "smoke.0001.vdb", "-o", "out.exr", "--cache", "c.####.vdb"});
    expectCliError(r, {"--cache c.####.vdb", "--frames"});
    r = cli({"bake", "smoke.0001.vdb", "-o", "c.####.vdb"});
    expectCliError(r, {"-o c.####.vdb", "--frames"});
    EXPECT_EQ(listDir(mWork).count("out.exr"), 0u);
}

TEST_F(Frames, SeveralFramesNeedTheTokenInEveryOutput) {
    writeSequence({1, 2, 3});
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    CliResult r = cli({"render", "shot.json", "--frames", "1-3", "-o", "out.exr"});
    expectCliError(r, {"-o out.exr", "--frames 1-3", "3 frames", "overwrite"});
    r = cli({"render", "shot.json", "--frames", "1-3", "-o", "out.####.exr", "--png", "out.png"});
    expectCliError(r, {"--png out.png", "overwrite"});
    r = cli({"render", "shot.json", "--frames", "1-3", "-o", "out.####.exr", "--stats", "s.json"});
    expectCliError(r, {"--stats s.json", "overwrite"});
    r = cli({"bake", "shot.json", "--frames", "2-3", "-o", "cache.vdb"});
    expectCliError(r, {"-o cache.vdb", "2 frames", "overwrite"});
    for (const std::string& name : listDir(mWork)) {
        EXPECT_EQ(name.find("out"), std::string::npos) << name;
        EXPECT_EQ(name.find("cache"), std::string::npos) << name;
    }
}

TEST_F(Frames, MissingFrameFileNamesFileAndFrameBeforeAnyFrameRenders) {
    writeSequence({1, 3});
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    CliResult r = cli({"render", "shot.json", "--frames", "1-3", "-o", "out.####.exr"});
    expectCliError(r, {"smoke.0002.vdb", "frame 2", "media[0].file", "No such file"});
    EXPECT_FALSE(fs::exists(work("out.0001.exr"))) << "all frames' files are checked first";
    r = cli({"render", "smoke.####.vdb", "--frames", "1-3", "-o", "out.####.exr"});
    expectCliError(r, {"smoke.0002.vdb", "frame 2", "No such file"});
    r = cli({"render", "shot.json", "--frames", "1", "-o", "out.####.exr", "--cache", "c.####.vdb"});
    expectCliError(r, {"c.0001.vdb", "frame 1", "--cache"});
    r = cli({"bake", "shot.json", "--frames", "1-3", "-o", "c.####.vdb"});
    expectCliError(r, {"smoke.0002.vdb", "frame 2"});
    EXPECT_FALSE(fs::exists(work("c.0001.vdb")));
}

// A frame that fails while it runs (a damaged file) stops the run: the frames
// before it stay, complete; nothing of it or after it is written.
TEST_F(Frames, FailedFrameStopsTheRunAndKeepsEarlierFrames) {
    writeSequence({1, 3});
    writeText(work("smoke.0002.vdb"), "not a vdb file\n");
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    CliResult r = cli({"render", "shot.json", "--frames", "1-3", "-o", "out.####.exr", "-q"});
    expectCliError(r, {"frame 2", "smoke.0002.vdb"});
    EXPECT_TRUE(fs::exists(work("out.0001.exr")));
    EXPECT_EQ(exr("out.0001.exr").width, 8);
    EXPECT_FALSE(fs::exists(work("out.0002.exr")));
    EXPECT_FALSE(fs::exists(work("out.0003.exr")));
    EXPECT_TRUE(tempLeftovers(mWork).empty());
}

TEST_F(Frames, BadRangesAreRefusedNamingTheText) {
    writeSequence({1});
    scene("shot.json", vdbScene("density", "smoke.####.vdb"));
    for (auto [range, needle] : {std::pair<const char*, const char*>{"3-1", "before the first"},
                                 {"1-3:0", "step"},
                                 {"x", "expected N, A-B or A-B:STEP"},
                                 {"1-3:2:1", "step"},
                                 {"-2", "non-negative"}}) {
        // "--frames=-2": a value that starts with '-' must be attached.
        CliResult r = cli({"render", "shot.json", std::string("--frames=") + range, "-o", "out.####.exr"});
        expectCliError(r, {std::string("--frames ") + range, needle});
        r = cli({"bake", "shot.json", std::string("--frames=") + range, "-o", "c.####.vdb"});
        expectCliError(r, {std::string("--frames ") + range, needle});
    }
    EXPECT_FALSE(fs::exists(work("out.0001.exr")));
}

}  // namespace
