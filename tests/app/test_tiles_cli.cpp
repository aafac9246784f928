// `render --tile / --crop / --passes` and `merge` through the command
// (docs/farm.md): tiles (or parts by photon passes) merged in any order are
// bit-identical to a one-process render (`compare --identical`), and merge
// refuses, naming the file, a missing,
// duplicate, overlapping, foreign or non-tile input, writing nothing and
// leaving an existing output as it was.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include "image/exr_io.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

class TilesCli : public BadInput {
protected:
    // Renders the sample cloud at 48x36, 3 spp, 2 threads (unless `extra`
    // gives --res or --threads) with the `extra` options to `out`.
    void render(const std::string& out, std::vector<std::string> extra = {}) {
        std::vector<std::string> args = {"render", samplePath("cloud.json"), "--spp", "3", "-q", "-o", out};
        auto given = [&](const char* o) { return std::find(extra.begin(), extra.end(), o) != extra.end(); };
        if (!given("--res")) args.insert(args.end(), {"--res", "48x36"});
        if (!given("--threads")) args.insert(args.end(), {"--threads", "2"});
        args.insert(args.end(), extra.begin(), extra.end());
        const CliResult r = cli(args);
        ASSERT_EQ(r.exitCode, 0) << r.err;
    }
    void renderTiles(int n, const std::vector<std::string>& extra = {}) {
        for (int i = 0; i < n; ++i) {
            std::vector<std::string> e = {"--tile", str(i, "/", n)};
            e.insert(e.end(), extra.begin(), extra.end());
            render(str("t", i, ".exr"), e);
        }
    }
    CliResult merge(std::vector<std::string> tiles, const std::string& out = "merged.exr") {
        tiles.insert(tiles.begin(), "merge");
        tiles.insert(tiles.end(), {"-o", out, "-q"});
        return cli(tiles);
    }
    CliResult identical(const std::string& a, const std::string& b) { return cli({"compare", a, b, "--identical"}); }
};

// Tiles are denoised after merge, on the whole frame (a tile alone would
// show seams at its edges): the merged, denoised frame and its PNG are those
// of one process, with the denoised RGBA, the noisy beauty and the halves;
// with the default (the PNG alone denoised) the merged EXR is the noisy one.
TEST_F(TilesCli, TilesAreDenoisedAfterMergeLikeOneProcess) {
    const std::vector<std::string> features = {"--aovs", "albedo,normal,depth"};
    auto with = [&](std::vector<std::string> a, const std::vector<std::string>& b) {
        a.insert(a.end(), b.begin(), b.end());
        return a;
    };
    render("single.exr", with(features, {"--denoise", "--png", "single.png"}));
    renderTiles(3, with(features, {"--denoise", "--threads", "1"}));
    ASSERT_EQ(merge({"t0.exr", "t1.exr", "t2.exr", "--png", "merged.png"}).exitCode, 0);
    const CliResult same = identical("merged.exr", "single.exr");
    EXPECT_EQ(same.exitCode, 0) << same.out;
    EXPECT_EQ(readBytes(work("merged.png")), readBytes(work("single.png")));
    std::set<std::string> names;
    for (const ExrLayer& l : readExrContents(work("single.exr")).layers) names.insert(l.name);
    for (const char* n : {"noisy", "even", "odd", "albedo", "normal", "depth"}) EXPECT_TRUE(names.count(n)) << n;
    // The denoised RGBA is not the noisy one.
    const ExrContents single = readExrContents(work("single.exr"));
    for (const ExrLayer& l : single.layers)
        if (l.name == "noisy") {
            EXPECT_NE(l.pixels, single.image.rgba);
        }

    render("p_single.exr", with(features, {"--png", "p_single.png"}));
    renderTiles(2, features);
    ASSERT_EQ(merge({"t0.exr", "t1.exr", "--png", "p_merged.png"}, "p_merged.exr").exitCode, 0);
    EXPECT_EQ(identical("p_merged.exr", "p_single.exr").exitCode, 0);
    EXPECT_EQ(readBytes(work("p_merged.png")), readBytes(work("p_single.png")));
    for (const ExrLayer& l : readExrContents(work("p_single.exr")).layers) EXPECT_NE(l.name, "even");
}

// The sample plume emits light: a denoised render keeps the emitted part
// of each half (layers emitted_even, emitted_odd), which the denoiser takes
// apart from the scattered light; tiles carry them to merge, and the merged
// frame is denoised as one process denoises it.
TEST_F(TilesCli, AnEmissiveSceneIsDenoisedAfterMergeLikeOneProcess) {
    auto plume = [&](const std::string& out, std::vector<std::string> extra) {
        std::vector<std::string> args = {"render", samplePath("plume.json"), "--spp", "4", "--res", "40x30",
                                         "--step", "0.05", "-q", "-o", out};
        args.insert(args.end(), extra.begin(), extra.end());
        const CliResult r = cli(args);
        ASSERT_EQ(r.exitCode, 0) << r.err;
    };
    plume("single.exr", {"--denoise", "--threads", "2"});
    plume("t0.exr", {"--denoise", "--tile", "0/2", "--threads", "1"});
    plume("t1.exr", {"--denoise", "--tile", "1/2", "--threads", "2"});
    ASSERT_EQ(merge({"t0.exr", "t1.exr"}).exitCode, 0);
    const CliResult same = identical("merged.exr", "single.exr");
    EXPECT_EQ(same.exitCode, 0) << same.out;
    std::set<std::string> names;
    for (const ExrLayer& l : readExrContents(work("single.exr")).layers) names.insert(l.name);
    for (const char* n : {"noisy", "even", "odd", "emitted_even", "emitted_odd"}) EXPECT_TRUE(names.count(n)) << n;
}

TEST_F(TilesCli, MergedTilesAreBitIdenticalToOneProcess) {
    render("single.exr", {"--aovs", "depth,albedo,direct,indirect"});
    renderTiles(4, {"--aovs", "depth,albedo,direct,indirect", "--threads", "1"});
    const ExrContents tile = readExrContents(work("t1.exr"));
    EXPECT_EQ(tile.window.display, (PixelRect{0, 0, 48, 36}));
    EXPECT_EQ(tile.window.data, (PixelRect{0, 9, 48, 18}));
    const CliResult m = merge({"t2.exr", "t0.exr", "t3.exr", "t1.exr"});  // any order
    ASSERT_EQ(m.exitCode, 0) << m.err;
    const CliResult same = identical("merged.exr", "single.exr");
    EXPECT_EQ(same.exitCode, 0) << same.out;
    EXPECT_NE(same.out.find("identical yes"), std::string::npos) << same.out;
    // The header keeps the render's settings, without the tile's own.
    bool tileAttr = false, merged = false;
    for (const auto& [k, v] : readExrStringAttributes(work("merged.exr"))) {
        tileAttr |= k == "vdbmarch:tile";
        merged |= k == "vdbmarch:mergedFrom" && v == "4 tiles (4 bands)";
    }
    EXPECT_FALSE(tileAttr);
    EXPECT_TRUE(merged);
}

TEST_F(TilesCli, CropsThatCoverTheFrameMerge) {
    render("single.exr");
    render("a.exr", {"--crop", "0,0,20,36"});
    render("b.exr", {"--crop", "20,0,48,10"});
    render("c.exr", {"--crop", "20,10,48,36"});
    ASSERT_EQ(merge({"a.exr", "b.exr", "c.exr"}).exitCode, 0);
    EXPECT_EQ(identical("merged.exr", "single.exr").exitCode, 0);
}

TEST_F(TilesCli, IdenticalSeesOneChangedPixel) {
    render("a.exr");
    render("b.exr", {"--seed", "8"});
    const CliResult r = identical("a.exr", "b.exr");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.out.find("identical no"), std::string::npos) << r.out;
    render("c.exr", {"--crop", "0,0,48,18"});
    EXPECT_EQ(identical("a.exr", "c.exr").exitCode, 1);  // the windows differ
}

TEST_F(TilesCli, MissingDuplicateAndForeignTilesAreNamedAndNothingIsWritten) {
    renderTiles(3);
    writeText(work("merged.exr"), "keep me");
    expectCliError(merge({"t0.exr", "t2.exr"}), {"1 of 3 tiles missing", "1/3", "rows 12-23", "nothing written"});
    expectCliError(merge({"t0.exr", "t1.exr", "t1.exr", "t2.exr"}), {"tile 1/3 is given twice", "t1.exr"});
    render("seed.exr", {"--tile", "1/3", "--seed", "5"});
    expectCliError(merge({"t0.exr", "seed.exr", "t2.exr"}), {"seed.exr", "t0.exr", "vdbmarch:seed", "\"5\"", "\"1\""});
    render("split.exr", {"--tile", "1/4"});
    expectCliError(merge({"t0.exr", "split.exr", "t2.exr"}), {"split.exr", "vdbmarch:split", "4 bands", "3 bands"});
    render("res.exr", {"--tile", "1/3", "--res", "50x36"});
    expectCliError(merge({"t0.exr", "res.exr", "t2.exr"}), {"res.exr", "t0.exr"});
    render("whole.exr");
    expectCliError(merge({"t0.exr", "whole.exr"}), {"whole.exr", "not a vdbmarch tile"});
    expectCliError(merge({"t0.exr", "t1.exr", "nope.exr"}), {"nope.exr"});
    EXPECT_EQ(readBytes(work("merged.exr")), "keep me");
    EXPECT_TRUE(tempLeftovers(mWork).empty());
}

TEST_F(TilesCli, OverlapsAndHolesAreNamed) {
    render("a.exr", {"--crop", "0,0,30,36"});
    render("b.exr", {"--crop", "20,0,48,36"});
    expectCliError(merge({"a.exr", "b.exr"}), {"a.exr and b.exr overlap", "[20, 48)"});
    render("c.exr", {"--crop", "30,0,48,20"});
    expectCliError(merge({"a.exr", "c.exr"}), {"the first hole is at pixel (30, 20)", "nothing written"});
    EXPECT_FALSE(fs::exists(work("merged.exr")));
}

TEST_F(TilesCli, BadTileOptionsAreRefusedBeforeRendering) {
    const std::string s = samplePath("cloud.json");
    expectCliError(cli({"render", s, "-o", "o.exr", "--tile", "4/4"}), {"--tile 4/4", "0 to 3"});
    expectCliError(cli({"render", s, "-o", "o.exr", "--tile", "two"}), {"--tile two", "INDEX/COUNT"});
    expectCliError(cli({"render", s, "-o", "o.exr", "--tile", "0/500", "--res", "64x48"}),
                   {"--tile 0/500", "image height (48)"});
    expectCliError(cli({"render", s, "-o", "o.exr", "--crop", "0,0,65,10", "--res", "64x48"}),
                   {"--crop 0,0,65,10", "64x48"});
    expectCliError(cli({"render", s, "-o", "o.exr", "--crop", "5,0,5,10"}), {"--crop 5,0,5,10", "empty"});
    expectCliError(cli({"render", s, "-o", "o.exr", "--crop", "0,0,1,1", "--tile", "0/2"}), {"--tile 0/2", "--crop"});
    EXPECT_FALSE(fs::exists(work("o.exr")));
}

// A tile given --time renders the samples that fit its own budget; merge
// accepts timed tiles whose sample counts differ, records their range and
// warns when they differ.
TEST_F(TilesCli, TimedTilesMergeWithTheirSampleRange) {
    auto attribute = [&](const std::string& file, const std::string& name) {
        for (const auto& [k, v] : readExrStringAttributes(work(file)))
            if (k == name) return v;
        return std::string();
    };
    for (int i = 0; i < 2; ++i) {
        const CliResult r = cli({"render", samplePath("cloud.json"), "--res", "48x36", "--time", "0.6", "--tile",
                                 str(i, "/2"), "-q", "-o", str("t", i, ".exr")});
        ASSERT_EQ(r.exitCode, 0) << r.err;
    }
    const CliResult m = cli({"merge", "t0.exr", "t1.exr", "-o", "merged.exr"});
    ASSERT_EQ(m.exitCode, 0) << m.err;
    const int a = std::stoi(attribute("t0.exr", "vdbmarch:spp")), b = std::stoi(attribute("t1.exr", "vdbmarch:spp"));
    const std::string expected = a == b ? str(a) : str(std::min(a, b), "-", std::max(a, b));
    EXPECT_EQ(attribute("merged.exr", "vdbmarch:spp"), expected);
    EXPECT_EQ(m.err.find("time budget") != std::string::npos, a != b) << m.err;
    // Another budget is another render.
    const CliResult other = cli({"render", samplePath("cloud.json"), "--res", "48x36", "--time", "0.4", "--tile", "1/2",
                                 "-q", "-o", "t1b.exr"});
    ASSERT_EQ(other.exitCode, 0) << other.err;
    expectCliError(merge({"t0.exr", "t1b.exr"}), {"t1b.exr", "vdbmarch:timeBudget"});
}

// Shared light transport baked once: tiles that read one baked cache
// (render --cache) merge bit-identically to one process with that cache,
// and a tile with another cache is another render.
TEST_F(TilesCli, TilesSharingABakedCacheMergeBitIdentically) {
    const std::vector<std::string> common = {"--set", "camera.resolution=[32,24]", "--set", "photons.count=20000",
                                             "--set", "render.step=0.06"};
    auto run = [&](std::vector<std::string> args) {
        args.insert(args.end(), common.begin(), common.end());
        const CliResult r = cli(args);
        ASSERT_EQ(r.exitCode, 0) << r.err;
    };
    const std::string glass = samplePath("glass.json");
    run({"bake", glass, "-o", "cache.vdb", "-q"});
    run({"bake", glass, "-o", "other.vdb", "--seed", "2", "-q"});
    const std::vector<std::string> r = {"render", glass, "--method", "guided", "--spp", "4", "--cache", "cache.vdb", "-q"};
    auto withOut = [&](std::vector<std::string> extra) {
        std::vector<std::string> args = r;
        args.insert(args.end(), extra.begin(), extra.end());
        return args;
    };
    run(withOut({"-o", "single.exr", "--threads", "2"}));
    run(withOut({"-o", "t0.exr", "--tile", "0/2", "--threads", "1"}));
    run(withOut({"-o", "t1.exr", "--tile", "1/2", "--threads", "2"}));
    ASSERT_EQ(merge({"t0.exr", "t1.exr"}).exitCode, 0);
    EXPECT_EQ(identical("merged.exr", "single.exr").exitCode, 0);
    std::vector<std::string> other = {"render", glass, "--method", "guided", "--spp", "4", "--cache", "other.vdb",
                                      "--force", "-q", "-o", "t1b.exr", "--tile", "1/2"};
    run(other);
    expectCliError(merge({"t0.exr", "t1b.exr"}), {"t1b.exr", "vdbmarch:cache"});
}

// A progressive render split by photon passes (render --passes): parts
// rendered apart, each tracing its passes' own photon batches and the cache
// refinements of the passes before them, merge bit-identically; a missing
// or doubled pass is named.
TEST_F(TilesCli, PartsByPhotonPassesMergeBitIdentically) {
    auto renderGlass = [&](const std::string& out, std::vector<std::string> extra) {
        std::vector<std::string> args = {"render", samplePath("glass.json"), "--res", "32x24", "--spp", "9", "--method",
                                         "guided", "--set", "photons.spp_per_pass=2", "--set", "photons.count=20000",
                                         "--step", "0.06", "-q", "-o", out};
        args.insert(args.end(), extra.begin(), extra.end());
        const CliResult r = cli(args);
        ASSERT_EQ(r.exitCode, 0) << r.err;
    };
    renderGlass("single.exr", {"--threads", "2"});
    renderGlass("a.exr", {"--passes", "0-1", "--threads", "1"});
    renderGlass("b.exr", {"--passes", "1-4", "--threads", "2"});  // crosses the refinements at passes 1 and 3
    renderGlass("c.exr", {"--passes", "4-5", "--threads", "1"});  // starts after both: makes them itself
    const ExrContents c = readExrContents(work("c.exr"));
    // The pass's sums, and those of its odd-index samples (the noise
    // estimate); and, as the sample's sphere light is seen, the sums of the
    // emission seen straight, which the denoiser takes apart.
    ASSERT_EQ(c.layers.size(), 4u);
    EXPECT_EQ(c.layers[0].name, "pass4");
    EXPECT_EQ(c.layers[1].name, "pass4emitted");
    EXPECT_EQ(c.layers[2].name, "pass4emittedodd");  // the file keeps layers in name order
    EXPECT_EQ(c.layers[3].name, "pass4odd");
    ASSERT_EQ(merge({"c.exr", "a.exr", "b.exr"}).exitCode, 0);
    const CliResult same = identical("merged.exr", "single.exr");
    EXPECT_EQ(same.exitCode, 0) << same.out;
    std::map<std::string, std::string> merged, single;
    for (const auto& [k, v] : readExrStringAttributes(work("merged.exr"))) merged[k] = v;
    for (const auto& [k, v] : readExrStringAttributes(work("single.exr"))) single[k] = v;
    EXPECT_EQ(merged["vdbmarch:spp"], "9");
    // The same sums in the same order: the same noise estimate.
    ASSERT_TRUE(single.count("vdbmarch:noiseEstimate"));
    EXPECT_EQ(merged["vdbmarch:noiseEstimate"], single["vdbmarch:noiseEstimate"]);
    // Denoised: the halves and their emitted parts rebuilt from the passes'
    // sums are one process's, and so is the denoised frame.
    renderGlass("d_single.exr", {"--denoise"});
    renderGlass("d_a.exr", {"--denoise", "--passes", "0-2"});
    renderGlass("d_b.exr", {"--denoise", "--passes", "2-5"});
    ASSERT_EQ(merge({"d_a.exr", "d_b.exr"}, "d_merged.exr").exitCode, 0);
    const CliResult denoised = identical("d_merged.exr", "d_single.exr");
    EXPECT_EQ(denoised.exitCode, 0) << denoised.out;
    expectCliError(merge({"a.exr", "c.exr"}), {"3 of 5 photon passes missing: 1, 2, 3", "nothing written"});
    renderGlass("b2.exr", {"--passes", "0-2"});
    expectCliError(merge({"a.exr", "b2.exr", "c.exr"}), {"a.exr and b2.exr both hold photon pass 0"});
    // Beyond the render's passes, or a render without progressive passes.
    expectCliError(cli({"render", samplePath("glass.json"), "--res", "32x24", "--spp", "9", "--method", "guided", "--set",
                        "photons.spp_per_pass=2", "--passes", "3-6", "-o", "x.exr"}),
                   {"--passes 3-6", "passes 0 to 4"});
    // The sums of every pass a part holds must fit in memory: refused before anything is traced.
    expectCliError(cli({"render", samplePath("glass.json"), "--res", "1000x1000", "--spp", "100000", "--method", "guided",
                        "--set", "photons.spp_per_pass=1", "--passes", "0-100000", "-o", "x.exr"}),
                   {"--passes 0-100000", "the sums of 100000 passes of 1000x1000 pixels"});
    expectCliError(cli({"render", samplePath("cloud.json"), "--method", "reference", "--passes", "0-1", "-o", "x.exr"}),
                   {"--passes 0-1", "no progressive photon passes", "tiles"});
    expectCliError(cli({"render", samplePath("cloud.json"), "--passes", "0-1", "--tile", "0/2", "-o", "x.exr"}),
                   {"--passes 0-1", "--tile 0/2"});
    EXPECT_FALSE(fs::exists(work("x.exr")));
}

}  // namespace
}  // namespace vdbmarch
