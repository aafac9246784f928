// `vdbmarch compare --layer`: a layer of the test image measured in place of
// its RGBA, so a denoised render's raw beauty (layer `noisy`) is measured
// from the same samples as its denoised RGBA (tools/bench_denoise.sh).
#include <gtest/gtest.h>

#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

class CompareCli : public BadInput {
protected:
    // The rmse line of `compare` as a number.
    double rmse(const std::vector<std::string>& args) {
        std::vector<std::string> all = {"compare"};
        all.insert(all.end(), args.begin(), args.end());
        const CliResult r = cli(all);
        EXPECT_EQ(r.exitCode, 0) << r.err;
        const size_t at = r.out.find("rmse ");
        return at == std::string::npos ? -1.0 : std::stod(r.out.substr(at + 5));
    }
    void renderBoth() {
        for (const char* mode : {"--denoise", "--no-denoise"}) {
            const CliResult r = cli({"render", samplePath("cloud.json"), "-o", mode[2] == 'd' ? "d.exr" : "raw.exr",
                                     "--res", "32x24", "--spp", "4", "--seed", "3", mode, "-q"});
            ASSERT_EQ(r.exitCode, 0) << r.err;
        }
    }
};

// The noisy layer of a denoised render is the raw render of the same seed
// and samples, pixel for pixel; its RGBA is not.
TEST_F(CompareCli, TheNoisyLayerIsTheRawRender) {
    renderBoth();
    EXPECT_EQ(rmse({work("d.exr"), work("raw.exr"), "--layer", "noisy"}), 0.0);
    EXPECT_GT(rmse({work("d.exr"), work("raw.exr")}), 0.0);
    EXPECT_GT(rmse({work("d.exr"), work("raw.exr"), "--layer", "even"}), 0.0);
}

TEST_F(CompareCli, AMissingLayerIsNamedWithThoseThereAre) {
    renderBoth();
    expectCliError(cli({"compare", work("raw.exr"), work("d.exr"), "--layer", "noisy"}),
                   {"--layer noisy", "raw.exr", "no such layer", "none"});
    expectCliError(cli({"compare", work("d.exr"), work("raw.exr"), "--layer", "nosiy"}),
                   {"--layer nosiy", "noisy", "even", "odd"});
    expectCliError(cli({"compare", work("d.exr"), work("raw.exr"), "--layer", "noisy", "--identical"}),
                   {"--layer", "--identical"});
}

}  // namespace
}  // namespace vdbmarch
