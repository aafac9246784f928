// The noise estimate and the noise target (render.noise, docs/noise.md):
// the two half renders' estimate of the variance agrees with the spread of
// independent renders; a render to a noise target stops near the error it
// was asked for, measured between independent renders; adaptive sampling
// gives the same image for any thread count and across a checkpoint; bad
// targets are refused.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "denoise/denoise.h"
#include "render/adaptive_sampling.h"
#include "support/support.h"

namespace vdbmarch::test {
namespace {

std::unique_ptr<Scene> cloud(const std::vector<std::string>& extra) {
    std::vector<std::string> o = {"camera.resolution=[24,18]", "render.max_depth=3", "render.method=\"reference\""};
    o.insert(o.end(), extra.begin(), extra.end());
    return buildScene(loadSceneFile(samplePath("cloud.json"), o));
}

// Mean over pixels and RGB of (a - b)^2.
double meanSquaredDifference(const Image& a, const Image& b) {
    double s = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const Color d = a.rgb(x, y) - b.rgb(x, y);
            s += double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
        }
    return s / (3.0 * double(a.pixelCount()));
}

double meanOf(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s / double(v.size());
}

double standardError(const std::vector<double>& v) {
    const double m = meanOf(v);
    double s = 0;
    for (double x : v) s += (x - m) * (x - m);
    return std::sqrt(s / double(v.size() - 1) / double(v.size()));
}

// Each render's estimate of its MSE (rmse^2 from its halves) against the
// MSE measured between pairs of independent renders, (a - b)^2 / 2: both
// are unbiased estimates of the mean variance of a pixel, so their means
// agree within their standard errors.
TEST(NoiseEstimate, MatchesTheSpreadOfIndependentRenders) {
    const int renders = 24;
    std::vector<double> estimated, measured;
    Image previous;
    for (int i = 0; i < renders; ++i) {
        const RenderResult r = renderImage(*cloud({"render.spp=16", str("render.seed=", 100 + i)}));
        ASSERT_TRUE(r.noise.valid);
        EXPECT_GT(r.noise.mean, 0);
        estimated.push_back(r.noise.rmse * r.noise.rmse);
        if (i % 2 == 1) measured.push_back(meanSquaredDifference(r.image, previous) / 2);
        previous = r.image;
    }
    const double se = std::hypot(standardError(estimated), standardError(measured));
    EXPECT_NEAR(meanOf(estimated), meanOf(measured), 4 * se)
        << "estimated " << meanOf(estimated) << " measured " << meanOf(measured);
    // Not vacuous: the standard error is a small part of the value.
    EXPECT_LT(se, 0.2 * meanOf(measured));
}

// Fewer than two samples: no estimate.
TEST(NoiseEstimate, NeedsTwoSamples) {
    EXPECT_FALSE(renderImage(*cloud({"render.spp=1"})).noise.valid);
    EXPECT_TRUE(renderImage(*cloud({"render.spp=2"})).noise.valid);
}

// Two independent renders to the target: the RMSE of each against the truth
// is their pair RMSE / sqrt(2); it lands within a factor 1.5 of the target
// (the estimate's own error and the last check's overshoot).
TEST(NoiseTarget, StopsNearTheErrorAskedFor) {
    for (double target : {0.08, 0.04}) {
        const std::vector<std::string> o = {"camera.resolution=[48,36]", str("render.noise=", target),
                                            "render.spp=65536"};
        std::vector<std::string> a = o, b = o;
        a.push_back("render.seed=1");
        b.push_back("render.seed=2");
        const RenderResult ra = renderImage(*cloud(a)), rb = renderImage(*cloud(b));
        ASSERT_TRUE(ra.reachedNoiseTarget && rb.reachedNoiseTarget);
        EXPECT_LE(ra.noise.relative(), target);
        const double mean = 0.5 * (ra.noise.mean + rb.noise.mean);
        const double measured = std::sqrt(meanSquaredDifference(ra.image, rb.image) / 2) / mean;
        EXPECT_GT(measured, target / 1.5) << "target " << target;
        EXPECT_LT(measured, target * 1.5) << "target " << target;
        // Adaptive: some 8x8 blocks stopped before others, and the layer says so.
        const ExrLayer* samples = nullptr;
        for (const ExrLayer& l : ra.layers)
            if (l.name == "samples") samples = &l;
        ASSERT_NE(samples, nullptr);
        const auto [lo, hi] = std::minmax_element(samples->pixels.begin(), samples->pixels.end());
        EXPECT_GE(*lo, 16.f);
        EXPECT_EQ(*hi, float(ra.spp));
        EXPECT_LT(ra.meanSpp, double(ra.spp));
        for (int y = 0; y < 36; ++y)
            for (int x = 0; x < 48; ++x)
                EXPECT_EQ(samples->pixels[size_t(y) * 48 + size_t(x)],
                          samples->pixels[size_t(y / 8 * 8) * 48 + size_t(x / 8 * 8)]);
    }
}

TEST(NoiseTarget, SameImageForAnyThreadCount) {
    const std::vector<std::string> o = {"camera.resolution=[40,30]", "render.noise=0.06", "render.spp=65536"};
    std::vector<std::string> one = o, two = o;
    one.push_back("render.threads=1");
    two.push_back("render.threads=2");
    const RenderResult a = renderImage(*cloud(one)), b = renderImage(*cloud(two));
    EXPECT_EQ(a.spp, b.spp);
    ASSERT_EQ(a.image.rgba.size(), b.image.rgba.size());
    EXPECT_EQ(0, std::memcmp(a.image.rgba.data(), b.image.rgba.data(), a.image.rgba.size() * sizeof(float)));
    ASSERT_EQ(a.layers.size(), b.layers.size());
    for (size_t i = 0; i < a.layers.size(); ++i) EXPECT_EQ(a.layers[i].pixels, b.layers[i].pixels);
}

// The spp cap comes first: the render stops there, short of the target.
TEST(NoiseTarget, SppCapsIt) {
    const RenderResult r = renderImage(*cloud({"render.noise=0.001", "render.spp=20"}));
    EXPECT_EQ(r.spp, 20);
    EXPECT_FALSE(r.reachedNoiseTarget);
    EXPECT_GT(r.noise.relative(), 0.001);
}

// A timed render's partial last sample: whole blocks that still sample keep
// it, about the share asked for, the rest stop where they are; blocks and
// pixels already stopped are left alone.
TEST(PartialLastSample, KeepsAShareOfTheStillSamplingBlocks) {
    const int w = 100, h = 70, block = 16;  // 7 x 5 blocks, the last row and column partial
    const int blocksX = 7, blocks = 35;
    std::vector<int> start(size_t(w * h), 0);
    auto blockOf = [&](int p) { return (p % w) / block + ((p / w) / block) * blocksX; };
    // Blocks 3 and 10 stopped entirely at 6 samples; one pixel of block 20 stopped too.
    for (int p = 0; p < w * h; ++p)
        if (blockOf(p) == 3 || blockOf(p) == 10) start[size_t(p)] = 6;
    const int lonePixel = 4 * block * w + 4 * block + 3;  // block 4 + 4 * 7 = 32
    ASSERT_EQ(blockOf(lonePixel), 32);
    start[size_t(lonePixel)] = 5;
    for (double share : {0.0, 0.01, 0.25, 0.5, 0.99, 1.0}) {
        std::vector<int> c = start;
        const bool kept = keepShareOfBlocks(c, w, h, block, share, 9);
        const int active = blocks - 2;
        const int expectKept = int(std::lround(share * active));
        EXPECT_EQ(kept, expectKept > 0) << share;
        int keptBlocks = 0;
        for (int b = 0; b < blocks; ++b) {
            int open = 0, sampling = 0, stopped = 0;
            for (int p = 0; p < w * h; ++p) {
                if (blockOf(p) != b) continue;
                if (start[size_t(p)] != 0) {
                    EXPECT_EQ(c[size_t(p)], start[size_t(p)]);  // already stopped: untouched
                    continue;
                }
                ++open;
                sampling += c[size_t(p)] == 0;
                stopped += c[size_t(p)] == 9;
            }
            if (open == 0) continue;  // blocks 3 and 10
            // A block keeps sampling or stops as a whole.
            EXPECT_TRUE(sampling == open || stopped == open) << "block " << b << " share " << share;
            keptBlocks += sampling == open;
        }
        if (kept) {
            EXPECT_EQ(keptBlocks, expectKept) << share;
        } else {
            EXPECT_EQ(c, start) << share;
        }
    }
    // The same share keeps the same blocks, a larger one keeps those and more.
    std::vector<int> a = start, b = start;
    keepShareOfBlocks(a, w, h, block, 0.3, 9);
    keepShareOfBlocks(b, w, h, block, 0.6, 9);
    for (int p = 0; p < w * h; ++p) {
        if (a[size_t(p)] == 0) {
            EXPECT_EQ(b[size_t(p)], 0);
        }
    }
}

TEST(NoiseTarget, BadValuesAreRefused) {
    for (const char* v : {"0", "-0.1", "20", "\"x\""})
        expectErrorContaining<InputError>([&] { cloud({str("render.noise=", v)}); }, {"render.noise"});
    TempDir dir("noise_cli");
    for (const char* v : {"0", "-1", "nan"}) {
        const CliResult r = runCli({"render", samplePath("cloud.json"), "-o", "x.exr", "--noise", v}, dir.path(), dir.path());
        EXPECT_NE(r.exitCode, 0);
        EXPECT_NE(r.err.find("--noise"), std::string::npos) << r.err;
    }
}

// A furnace (albedo 1 under a uniform background of 1): every pixel's
// expectation is 1, and denoising the render's halves keeps the mean within
// the raw image's standard error.
TEST(Denoise, FurnaceKeepsItsMean) {
    auto scene = sceneFromJson(R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_deg": 40,
        "resolution": [32, 32]}, "media": [{"type": "homogeneous", "sigma_a": 0, "sigma_s": 4, "g": 0.7,
        "bounds": {"min": [-3, -3, -3], "max": [3, 3, 3]}}], "background": [1, 1, 1],
        "render": {"method": "reference", "spp": 8, "max_depth": 100000, "seed": 4}})");
    RenderOptions options;
    options.keepHalves = true;
    const RenderResult r = renderImage(*scene, options);
    DenoiseInput in;
    in.width = in.height = 32;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            in.halfA.push_back(r.evenHalf.rgb(x, y));
            in.halfB.push_back(r.oddHalf.rgb(x, y));
        }
    const Image d = denoise(in);
    for (int c = 0; c < 3; ++c) {
        const ChannelStats raw = pixelStats(r.image, c), denoised = pixelStats(d, c);
        EXPECT_NEAR(raw.mean, 1.0, 4 * raw.stdError + 1e-6);
        EXPECT_NEAR(denoised.mean, raw.mean, 3 * raw.stdError + 1e-6) << "channel " << c;
    }
}

}  // namespace
}  // namespace vdbmarch::test
