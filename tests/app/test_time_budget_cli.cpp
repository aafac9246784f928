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
