// `render --time` through the command: the budget is the whole run's, so a
// render denoised in the same process keeps the denoiser's predicted time
// back from its sweeps (docs/denoise.md, "Time budgets"); one that is not
// denoised here (--no-denoise, a tile denoised after merge) keeps nothing.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "app/denoise_frame.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

class TimeBudgetCli : public BadInput {
protected:
    // Renders the sample cloud at 96x72 for `seconds` with `extra`; its stats.
    nlohmann::json render(const std::string& name, const std::vector<std::string>& extra, const char* seconds = "1") {
        std::vector<std::string> args = {"render",  samplePath("cloud.json"), "-o",  name + ".exr", "--res",
                                         "96x72",   "--threads",              "2",   "--time",      seconds,
                                         "--stats", name + ".json",           "-q"};
        args.insert(args.end(), extra.begin(), extra.end());
        const CliResult r = cli(args);
        EXPECT_EQ(r.exitCode, 0) << r.err;
        std::ifstream in(work(name + ".json"));
        return nlohmann::json::parse(in);
    }
};

TEST_F(TimeBudgetCli, ARenderDenoisedHereKeepsTheDenoisersTimeBack) {
    const nlohmann::json s = render("preview", {"--png", "preview.png"});
    ASSERT_TRUE(s["seconds"].contains("denoise_reserved")) << s.dump();
    ASSERT_TRUE(s["seconds"].contains("denoise")) << s.dump();
    const double reserved = s["seconds"]["denoise_reserved"];
    EXPECT_GT(reserved, 0);
    EXPECT_LE(reserved, 0.5);  // at most half the budget
    // The same with the EXR denoised too.
    const nlohmann::json d = render("denoised", {"--denoise"});
    EXPECT_GT(double(d["seconds"]["denoise_reserved"]), 0);
}

TEST_F(TimeBudgetCli, ARenderNotDenoisedHereKeepsNothingBack) {
    for (const auto& [name, extra] :
         std::vector<std::pair<std::string, std::vector<std::string>>>{{"raw", {"--png", "raw.png", "--no-denoise"}},
                                                                       {"tile", {"--tile", "0/2", "--denoise"}}}) {
        const nlohmann::json s = render(name, extra);
        EXPECT_FALSE(s["seconds"].contains("denoise_reserved")) << name << ": " << s.dump();
        EXPECT_FALSE(s["seconds"].contains("denoise")) << name << ": " << s.dump();
    }
}

// auto in a timed render picks by pilots (app/method_pilot.h): each
// candidate's pilot is recorded with at least two samples per pixel, the
// pick is one of them, and the image keeps the pick's pilot samples (the
// render resumed from its pilot, so it has at least as many). Renders with
// a method or a sample count run no pilot.
TEST_F(TimeBudgetCli, AutoPicksByPilotsAndKeepsThePicksSamples) {
    const nlohmann::json s = render("auto", {"--no-denoise"}, "2");
    ASSERT_TRUE(s.contains("method_pilots")) << s.dump();
    const nlohmann::json& pilots = s["method_pilots"];
    ASSERT_GE(pilots.size(), 2u) << s.dump();
    EXPECT_NE(pilots[0]["method"], pilots[1]["method"]);
    const std::string method = s["method"];
    int pilotSpp = -1;
    for (int i = 0; i < 2; ++i) {
        EXPECT_TRUE(pilots[i]["method"] == "reference" || pilots[i]["method"] == "guided") << pilots[i].dump();
        EXPECT_GE(int(pilots[i]["spp"]), 2) << pilots[i].dump();
        EXPECT_GT(double(pilots[i]["noise_rmse"]), 0) << pilots[i].dump();
        if (pilots[i]["method"] == method) pilotSpp = pilots[i]["spp"];
    }
    ASSERT_GE(pilotSpp, 2) << "the pick is one of the pilots: " << s.dump();
    EXPECT_GE(int(s["spp"]), pilotSpp);
    EXPECT_NE(std::string(s["method_reason"]).find("the rule:"), std::string::npos) << s.dump();

    EXPECT_FALSE(render("pinned", {"--no-denoise", "--method", "reference"}, "1").contains("method_pilots"));
}

TEST_F(TimeBudgetCli, ASampleCountRenderKeepsTheRule) {
    const CliResult r = cli({"render", samplePath("cloud.json"), "-o", "spp.exr", "--res", "32x24", "--spp", "4",
                             "--stats", "spp.json", "-q"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    std::ifstream in(work("spp.json"));
    const nlohmann::json s = nlohmann::json::parse(in);
    EXPECT_FALSE(s.contains("method_pilots")) << s.dump();
    EXPECT_TRUE(bool(s["method_auto"]));
}

// The prediction is a measurement of this machine scaled by the pixel count:
// positive, and a frame of 16 times the pixels is predicted to take longer.
TEST(DenoisePrediction, GrowsWithThePixelCount) {
    for (const DenoiseShape shape : {DenoiseShape{}, DenoiseShape{true, true, true, true}}) {
        const double small = predictDenoiseSeconds(80, 60, shape, 2), large = predictDenoiseSeconds(320, 240, shape, 2);
        EXPECT_GT(small, 0);
        EXPECT_GT(large, small);
    }
    EXPECT_EQ(predictDenoiseSeconds(0, 10, DenoiseShape{}, 1), 0);
}

}  // namespace
}  // namespace vdbmarch
