// The feature-guided NL-means denoiser (src/denoise/): exact on noise-free
// input, a real reduction of the error on a synthetic noisy frame with the
// edges kept, features that help where the colour cannot see an edge,
// bit-identical for any thread count, finite on non-finite input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/rng.h"
#include "denoise/denoise.h"
#include "image/metrics.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using test::allFinite;

// Standard normal by Box-Muller from the project's PCG32 (portable, unlike
// std::normal_distribution).
float gaussian(Rng& rng) {
    const double u1 = 1.0 - rng.uniformDouble(), u2 = rng.uniformDouble();
    return float(std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2));
}

// A piecewise-smooth frame: a soft gradient with a disc of sharp edge, its
// two half renders (truth + independent Gaussian noise of known sigma per
// half) and a first-event albedo that shows the disc (with its own noise).
struct Synthetic {
    int width = 0, height = 0;
    float cx = 0, cy = 0, radius = 0;
    std::vector<Color> truth;
    std::vector<float> truthAlpha;
    DenoiseInput input;

    float edgeDistance(int x, int y) const {
        return std::fabs(std::hypot(x + 0.5f - cx, y + 0.5f - cy) - radius);
    }
    bool inDisc(int x, int y) const { return std::hypot(x + 0.5f - cx, y + 0.5f - cy) < radius; }
};

struct SceneSpec {
    int width = 160, height = 120;
    float sigma = 0.15f;        // colour noise of one half, per channel
    float alphaSigma = 0.1f;    // alpha noise of one half
    float albedoSigma = 0.05f;  // albedo noise (0: noiseless)
    bool gradient = true;       // false: flat grey background and disc
    float discContrast = 0.5f;  // disc minus background, when !gradient
    bool allFeatures = false;   // add normal and depth too
    uint64_t seed = 1;
};

Synthetic makeScene(const SceneSpec& s) {
    Synthetic sc;
    sc.width = s.width;
    sc.height = s.height;
    sc.cx = 0.5f * s.width;
    sc.cy = 0.5f * s.height;
    sc.radius = 0.3f * s.height;
    DenoiseInput& in = sc.input;
    in.width = s.width;
    in.height = s.height;
    Rng rng(s.seed);
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const float u = float(x) / float(s.width), v = float(y) / float(s.height);
            const bool disc = sc.inDisc(x, y);
            Color c;
            float alpha;
            if (s.gradient) {
                c = disc ? Color(0.9f - 0.2f * u, 0.7f, 0.4f + 0.2f * v)
                         : Color(0.2f + 0.3f * u, 0.25f + 0.2f * v, 0.3f + 0.1f * (u + v));
                alpha = disc ? 1.f : 0.5f + 0.3f * u;
            } else {
                c = Color(disc ? 0.5f + s.discContrast : 0.5f);
                alpha = 1.f;
            }
            sc.truth.push_back(c);
            sc.truthAlpha.push_back(alpha);
            auto noisy = [&](const Color& t) {
                return t + s.sigma * Color(gaussian(rng), gaussian(rng), gaussian(rng));
            };
            in.halfA.push_back(noisy(c));
            in.halfB.push_back(noisy(c));
            in.alphaA.push_back(alpha + s.alphaSigma * gaussian(rng));
            in.alphaB.push_back(alpha + s.alphaSigma * gaussian(rng));
            const Color albedo = disc ? Color(0.8f, 0.6f, 0.5f) : Color(0.3f);
            in.albedo.push_back(albedo + s.albedoSigma * Color(gaussian(rng), gaussian(rng), gaussian(rng)));
            if (s.allFeatures) {
                Vec3 n = disc ? Vec3(0, 0, 1) : Vec3(0, 1, 0);
                in.normal.push_back(n + 0.1f * Vec3(gaussian(rng), gaussian(rng), gaussian(rng)));
                in.depth.push_back((disc ? 5.f : 12.f) + 0.2f * gaussian(rng));
            }
        }
    return sc;
}

// Mean squared RGB error against the truth over the pixels `keep` accepts.
template <class Keep>
double mse(const Synthetic& sc, const Image& img, Keep keep) {
    double sum = 0;
    size_t n = 0;
    for (int y = 0; y < sc.height; ++y)
        for (int x = 0; x < sc.width; ++x) {
            if (!keep(x, y)) continue;
            const Color d = img.rgb(x, y) - sc.truth[size_t(y) * size_t(sc.width) + size_t(x)];
            sum += double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
            n += 3;
        }
    return sum / double(n);
}

double mseAll(const Synthetic& sc, const Image& img) {
    return mse(sc, img, [](int, int) { return true; });
}

// The plain estimate without denoising: the mean of the two halves.
Image noisyMean(const DenoiseInput& in) {
    Image img(in.width, in.height);
    for (int y = 0; y < in.height; ++y)
        for (int x = 0; x < in.width; ++x) {
            const size_t i = size_t(y) * size_t(in.width) + size_t(x);
            const float alpha = in.alphaA.empty() ? 1.f : 0.5f * (in.alphaA[i] + in.alphaB[i]);
            img.set(x, y, 0.5f * (in.halfA[i] + in.halfB[i]), alpha);
        }
    return img;
}

// An input of that size, to be filled.
DenoiseInput sizedInput(int width, int height) {
    DenoiseInput in;
    in.width = width;
    in.height = height;
    return in;
}

// Mean squared RGB error of a whole frame against a truth (row-major).
double mseAgainst(const std::vector<Color>& truth, const Image& img) {
    double sum = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const Color d = img.rgb(x, y) - truth[size_t(y) * size_t(img.width) + size_t(x)];
            sum += double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
        }
    return sum / double(3 * img.pixelCount());
}

double meanRgb(const Image& img) {
    double sum = 0;
    for (size_t i = 0; i < img.pixelCount(); ++i)
        sum += double(img.rgba[i * 4]) + img.rgba[i * 4 + 1] + img.rgba[i * 4 + 2];
    return sum / double(img.pixelCount() * 3);
}


TEST(DenoiseExact, AConstantNoiseFreeFrameComesBackUnchanged) {
    const int w = 45, h = 37;  // partial tiles on both axes
    const Color colour(0.3f, 0.55f, 0.7f);
    DenoiseInput in;
    in.width = w;
    in.height = h;
    in.halfA.assign(size_t(w * h), colour);
    in.halfB = in.halfA;
    in.alphaA.assign(size_t(w * h), 0.8f);
    in.alphaB = in.alphaA;
    in.albedo.assign(size_t(w * h), Color(0.5f));
    in.normal.assign(size_t(w * h), Color(0, 0, 1));
    in.depth.assign(size_t(w * h), 3.f);
    for (bool features : {true, false}) {
        DenoiseOptions o;
        o.useFeatures = features;
        // Every weight is exactly 1 here; what is left is the rounding of a
        // float sum of (2r+1)^2 equal values, divided by their count.
        const int window = (2 * o.searchRadius + 1) * (2 * o.searchRadius + 1);
        const float tolerance = float(window) * std::numeric_limits<float>::epsilon();
        const Image out = denoise(in, o);
        ASSERT_EQ(out.width, w);
        ASSERT_EQ(out.height, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(out.rgb(x, y)[c], colour[c], tolerance * colour[c]) << x << "," << y;
                ASSERT_NEAR(out.alpha(x, y), 0.8f, tolerance * 0.8f);
            }
    }
}

TEST(DenoiseQuality, SyntheticFrameErrorDropsAndTheDiscEdgeIsKept) {
    const Synthetic sc = makeScene({});
    const Image noisy = noisyMean(sc.input);
    const Image out = denoise(sc.input);
    ASSERT_TRUE(allFinite(out));

    const double before = mseAll(sc, noisy), after = mseAll(sc, out);
    auto band = [&](int x, int y) { return sc.edgeDistance(x, y) <= 2.f; };
    const double bandBefore = mse(sc, noisy, band), bandAfter = mse(sc, out, band);
    auto border = [&](int x, int y) { return x < 3 || y < 3 || x >= sc.width - 3 || y >= sc.height - 3; };
    const double borderBefore = mse(sc, noisy, border), borderAfter = mse(sc, out, border);
    std::printf("[ denoise ] synthetic 160x120, sigma 0.15 per half: MSE %.3g -> %.3g (ratio %.3f); "
                "edge band %.3g -> %.3g (ratio %.3f); border %.3g -> %.3g (ratio %.3f)\n",
                before, after, after / before, bandBefore, bandAfter, bandAfter / bandBefore, borderBefore,
                borderAfter, borderAfter / borderBefore);
    // Measured over seeds 1 to 7: the MSE ratio is 0.0086 to 0.010 over the
    // frame, 0.006 to 0.009 at its border (the window clamped there), 0.10
    // to 0.115 in the 5-pixel band around the disc's edge; the bounds leave a
    // margin of 3x and 2x for other compilers and platforms. An edge blurred
    // over the band would leave its error there near the step's, far above
    // the noise.
    EXPECT_LT(after, 0.03 * before);
    EXPECT_LT(bandAfter, 0.25 * bandBefore);
    EXPECT_LT(borderAfter, 0.03 * borderBefore);
}

// The denoiser's estimate of the noise variance it leaves (`variances`,
// what adaptive sampling weighs a block's noise by): the same image as
// without it; away from the disc's edge, where the error is the noise left,
// it bounds the squared error measured against the truth from above, within
// a factor 2; and the filter averages less in the band around the edge, so
// more noise is left there.
TEST(DenoiseVariance, EstimatesTheNoiseLeft) {
    for (uint64_t seed : {1, 2, 3}) {
        SceneSpec spec;
        spec.seed = seed;
        const Synthetic sc = makeScene(spec);
        std::vector<float> variances;
        const Image out = denoise(sc.input, {}, &variances);
        ASSERT_EQ(variances.size(), size_t(sc.width) * size_t(sc.height));
        EXPECT_EQ(out.rgba, denoise(sc.input).rgba);
        double flatEstimate = 0, flatMeasured = 0, band = 0;
        int flat = 0, inBand = 0;
        for (int y = 0; y < sc.height; ++y)
            for (int x = 0; x < sc.width; ++x) {
                const size_t p = size_t(y) * size_t(sc.width) + size_t(x);
                ASSERT_TRUE(std::isfinite(variances[p]));
                const Color d = out.rgb(x, y) - sc.truth[p];
                if (sc.edgeDistance(x, y) <= 2.f) band += variances[p], ++inBand;
                if (sc.edgeDistance(x, y) > 8.f && x >= 8 && y >= 8 && x < sc.width - 8 && y < sc.height - 8) {
                    flatEstimate += variances[p];
                    flatMeasured += double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
                    ++flat;
                }
            }
        std::printf("[ denoise ] seed %d: away from the edge estimated %.4g measured %.4g (ratio %.3f); band %.4g "
                    "(%.2fx)\n",
                    int(seed), flatEstimate / flat, flatMeasured / flat, flatEstimate / flatMeasured, band / inBand,
                    (band / inBand) / (flatEstimate / flat));
        // Measured 1.40-1.59 over seeds 1 to 3: the estimate adds the
        // filter's and the restored local means' variances, two averages of
        // the same noise (docs/denoise.md); an over-estimate, by less than 2.
        EXPECT_GT(flatEstimate / flatMeasured, 1.0) << "seed " << seed;
        EXPECT_LT(flatEstimate / flatMeasured, 2.0) << "seed " << seed;
        EXPECT_GT(band / inBand, flatEstimate / flat) << "seed " << seed;
    }
}

TEST(DenoiseQuality, AFeatureShowsAnEdgeTheNoisyColourHides) {
    SceneSpec s;
    s.gradient = false;
    s.discContrast = 0.15f;
    s.sigma = 0.3f;
    s.albedoSigma = 0;
    const Synthetic sc = makeScene(s);
    DenoiseOptions withFeatures, colourOnly;
    colourOnly.useFeatures = false;
    const Image a = denoise(sc.input, withFeatures), b = denoise(sc.input, colourOnly);
    auto band = [&](int x, int y) { return sc.edgeDistance(x, y) <= 2.f; };
    const double bandWith = mse(sc, a, band), bandWithout = mse(sc, b, band);
    const double bandNoisy = mse(sc, noisyMean(sc.input), band);
    std::printf("[ denoise ] low-contrast disc, noiseless albedo: edge band MSE noisy %.3g, colour only %.3g, "
                "with features %.3g (ratio %.3f)\n",
                bandNoisy, bandWithout, bandWith, bandWith / bandWithout);
    // Measured over seeds 1 to 7: 0.105 to 0.119 (the colour-only filter
    // blurs the edge it cannot see; the feature weights stop it). Bound with
    // a margin of 2.5x.
    EXPECT_LT(bandWith, 0.3 * bandWithout);
}

TEST(DenoiseDeterminism, BitIdenticalForAnyThreadCount) {
    SceneSpec s;
    s.width = 100;
    s.height = 70;
    s.allFeatures = true;
    const Synthetic sc = makeScene(s);
    std::vector<Image> outs;
    for (int threads : {1, 2, 3}) {
        DenoiseOptions o;
        o.threads = threads;
        outs.push_back(denoise(sc.input, o));
    }
    EXPECT_TRUE(outs[0].rgba == outs[1].rgba);
    EXPECT_TRUE(outs[0].rgba == outs[2].rgba);
}

TEST(DenoiseRobustness, NonFiniteInputsGiveAFiniteOutput) {
    SceneSpec s;
    s.width = 64;
    s.height = 48;
    s.allFeatures = true;
    Synthetic sc = makeScene(s);
    DenoiseInput& in = sc.input;
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    auto at = [&](int x, int y) { return size_t(y) * size_t(in.width) + size_t(x); };
    in.halfA[at(10, 10)] = Color(nan, 0.5f, inf);
    in.halfB[at(11, 10)] = Color(-inf);
    in.halfA[at(20, 20)] = in.halfB[at(20, 20)] = Color(nan);  // missing in both halves
    in.halfA[at(0, 0)] = in.halfB[at(0, 0)] = Color(inf);
    in.halfA[at(30, 5)] = Color(1e30f);  // finite but absurd
    in.alphaA[at(5, 40)] = nan;
    in.alphaB[at(6, 40)] = -inf;
    in.albedo[at(40, 30)] = Color(nan);
    in.normal[at(41, 30)] = Color(inf, -inf, nan);
    in.depth[at(42, 30)] = nan;
    in.depth[at(43, 30)] = inf;
    const Image out = denoise(in);
    EXPECT_TRUE(allFinite(out));
    // The pixel missing in both halves is filled from its neighbours: near
    // the truth. (Without the absurd value: clamped as a firefly, its light,
    // 5e14, comes back as a haze over the whole frame, as energy demands.)
    DenoiseInput sane = in;
    sane.halfA[at(30, 5)] = sane.halfB[at(30, 5)];
    const Color c = denoise(sane).rgb(20, 20), t = sc.truth[at(20, 20)];
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(c[k], t[k], 0.2f);

    // All features non-finite, every colour value NaN: still finite (0).
    DenoiseInput bad = in;
    for (auto& v : bad.halfA) v = Color(nan);
    for (auto& v : bad.halfB) v = Color(inf);
    for (auto& v : bad.albedo) v = Color(nan);
    for (auto& v : bad.normal) v = Color(-inf);
    for (auto& v : bad.depth) v = nan;
    EXPECT_TRUE(allFinite(denoise(bad)));
}

TEST(DenoiseRobustness, SizeMismatchesAndBadOptionsThrow) {
    SceneSpec s;
    s.width = 16;
    s.height = 12;
    const Synthetic sc = makeScene(s);
    EXPECT_NO_THROW(denoise(sc.input));
    auto throws = [&](auto change) {
        DenoiseInput in = sc.input;
        DenoiseOptions o;
        change(in, o);
        EXPECT_THROW(denoise(in, o), std::invalid_argument);
    };
    throws([](DenoiseInput& in, DenoiseOptions&) { in.halfB.pop_back(); });
    throws([](DenoiseInput& in, DenoiseOptions&) { in.halfA.clear(); });
    throws([](DenoiseInput& in, DenoiseOptions&) { in.alphaA.push_back(1.f); });
    throws([](DenoiseInput& in, DenoiseOptions&) { in.alphaB.clear(); });  // alpha in one half only
    throws([](DenoiseInput& in, DenoiseOptions&) { in.albedo.resize(5); });
    throws([](DenoiseInput& in, DenoiseOptions&) { in.normal.resize(in.halfA.size() + 1); });
    throws([](DenoiseInput& in, DenoiseOptions&) { in.depth.resize(3); });
    throws([](DenoiseInput& in, DenoiseOptions&) { in.width += 1; });
    throws([](DenoiseInput& in, DenoiseOptions&) { in.width = -16; in.height = -12; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.searchRadius = -1; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.candidates = 0; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.candidates = 5; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.colorStrength = 0; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.threads = -2; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.restoreSigma = -1; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.restoreSigma = std::numeric_limits<float>::quiet_NaN(); });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.fireflySigma = 65; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.regressionRidge = -1; });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.regressionNoiseRidge = -1; });
    throws([](DenoiseInput& in, DenoiseOptions&) { in.emittedA = in.halfA; });  // one emitted half only
    throws([](DenoiseInput& in, DenoiseOptions&) {
        in.emittedA = in.halfA;
        in.emittedB = in.halfB;
        in.emittedB.pop_back();
    });
    throws([](DenoiseInput&, DenoiseOptions& o) { o.regressionRidge = std::numeric_limits<float>::quiet_NaN(); });

    // Absent optional inputs are fine: an opaque, colour-only denoise.
    DenoiseInput bare;
    bare.width = s.width;
    bare.height = s.height;
    bare.halfA = sc.input.halfA;
    bare.halfB = sc.input.halfB;
    const Image out = denoise(bare);
    EXPECT_TRUE(allFinite(out));
    EXPECT_EQ(out.alpha(3, 4), 1.f);
    EXPECT_TRUE(denoise(DenoiseInput{}).empty());
}

TEST(DenoiseQuality, TheImageMeanIsNearlyUnchanged) {
    const Synthetic sc = makeScene({});
    const Image noisy = noisyMean(sc.input), out = denoise(sc.input);
    double truthSum = 0;
    for (const Color& c : sc.truth) truthSum += double(c.x) + c.y + c.z;
    const double truthMean = truthSum / double(sc.truth.size() * 3);
    const double n = double(sc.truth.size() * 3);
    // Standard error of the noisy mean: sigma / sqrt(2) per value (two halves averaged), over n values.
    const double standardError = 0.15 / std::sqrt(2.0) / std::sqrt(n);
    std::printf("[ denoise ] image mean: truth %.6f, noisy %.6f, denoised %.6f (standard error %.2g)\n", truthMean,
                meanRgb(noisy), meanRgb(out), standardError);
    // The denoiser moves the mean by less than two standard errors of the
    // noisy mean itself, relative to the mean (about 2e-3 here; measured over
    // seeds 1 to 7: 0.06 to 0.5 standard errors).
    const double relativeChange = std::fabs(meanRgb(out) - meanRgb(noisy)) / meanRgb(noisy);
    EXPECT_LT(relativeChange, 2 * standardError / meanRgb(noisy));
}

// Sparse bright detail (soft bumps of 0.7-2.2 pixels on a dim ground, as the
// fine structure of a cloud) under noise that grows with the value, as Monte
// Carlo noise does: NL-means averages bright pixels with dim ones whose
// patches look alike, and without restoring the local means the denoised
// image's low-frequency error (8x8 block means, issue 21's bias measure)
// exceeds the noisy image's (1.17-1.28x over seeds 1-5, as cloud_sun's
// 1.22-1.27x). Restored: 0.95-1.0x; the bound is 1.1x.
TEST(DenoiseQuality, SparseBrightDetailKeepsItsLowFrequencies) {
    const int w = 160, h = 120;
    Rng rng(11);
    Image truth(w, h);
    DenoiseInput in;
    in.width = w;
    in.height = h;
    std::vector<float> field(size_t(w) * h, 0.05f);
    for (int k = 0; k < w * h / 40; ++k) {
        const float cx = rng.uniform() * w, cy = rng.uniform() * h, r = 0.7f + 1.5f * rng.uniform();
        for (int y = std::max(0, int(cy - 3 * r)); y < std::min(h, int(cy + 3 * r) + 1); ++y)
            for (int x = std::max(0, int(cx - 3 * r)); x < std::min(w, int(cx + 3 * r) + 1); ++x)
                field[size_t(y) * w + x] += std::exp(-0.5f * (std::pow(x + 0.5f - cx, 2.f) + std::pow(y + 0.5f - cy, 2.f)) / (r * r));
    }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float t = field[size_t(y) * w + x];
            truth.set(x, y, Color(t), 1.f);
            const float sigma = 0.3f * std::sqrt(t);
            in.halfA.push_back(Color(t) + sigma * Color(gaussian(rng), gaussian(rng), gaussian(rng)));
            in.halfB.push_back(Color(t) + sigma * Color(gaussian(rng), gaussian(rng), gaussian(rng)));
        }
    DenoiseOptions restored, notRestored;
    notRestored.restoreSigma = 0;
    const double noisy = lowFrequencyError(noisyMean(in), truth);
    const double with = lowFrequencyError(denoise(in, restored), truth);
    const double without = lowFrequencyError(denoise(in, notRestored), truth);
    std::printf("[ denoise ] sparse detail, low-frequency error: noisy %.4f, denoised %.4f, not restored %.4f\n", noisy,
                with, without);
    EXPECT_LE(with, 1.1 * noisy);
    EXPECT_GT(without, 1.1 * noisy);
}

// A firefly (one sample 1000x the level, in one half only) in a noisy flat
// frame. Without the clamp, cross-filtering spreads it over the search window
// of every neighbour (a square blotch of 19 x 19 pixels). With it, the
// firefly's light is neither lost nor left as a blotch: it comes back as the
// Gaussian haze of fireflySigma that the design prescribes (here, in a small
// frame, over all of it).
// Candidate filters chosen per pixel by SURE (docs/denoise.md, step 7): on a
// frame whose left half is a smooth ramp (a strong filter is best) and whose
// right half holds fine low-contrast stripes (a strong filter blurs them),
// the blend is, on each half, nearly as good as the best single strength
// there, and better than every single strength over the whole frame.
TEST(DenoiseQuality, SureBlendsTheBestCandidateOfEachRegion) {
    const int w = 160, h = 120;
    const float sigma = 0.1f;
    for (uint64_t seed : {1u, 2u, 3u}) {
        DenoiseInput in;
        in.width = w;
        in.height = h;
        std::vector<Color> truth;
        Rng rng(seed);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float u = float(x) / float(w), v = float(y) / float(h);
                // Stripes of a 3-pixel period along a diagonal, 0.08 high.
                const float stripes = x < w / 2 ? 0.f : 0.08f * std::sin(2.f * 3.14159265f * float(x + 2 * y) / 3.f);
                const Color c(0.4f + 0.2f * u + stripes, 0.35f + 0.2f * v + stripes, 0.5f + stripes);
                truth.push_back(c);
                const float s = x < w / 2 ? 4 * sigma : sigma;
                in.halfA.push_back(c + s * Color(gaussian(rng), gaussian(rng), gaussian(rng)));
                in.halfB.push_back(c + s * Color(gaussian(rng), gaussian(rng), gaussian(rng)));
            }
        auto error = [&](const Image& img, int x0, int x1) {
            double sum = 0;
            for (int y = 0; y < h; ++y)
                for (int x = x0; x < x1; ++x) {
                    const Color d = img.rgb(x, y) - truth[size_t(y) * size_t(w) + size_t(x)];
                    sum += double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
                }
            return sum / double(3 * h * (x1 - x0));
        };
        // Step 9 (the restored local means) off: its noise floor would hide
        // the candidates' differences in the smooth half.
        DenoiseOptions blend;
        blend.restoreSigma = 0;
        double bestLeft = 1e30, bestRight = 1e30, bestAll = 1e30;
        for (int j = 0; j < blend.candidates; ++j) {
            DenoiseOptions single = blend;
            single.candidates = 1;
            single.colorStrength = blend.colorStrength * float(1 << j);
            const Image out = denoise(in, single);
            bestLeft = std::min(bestLeft, error(out, 0, w / 2));
            bestRight = std::min(bestRight, error(out, w / 2, w));
            bestAll = std::min(bestAll, error(out, 0, w));
        }
        const Image out = denoise(in, blend);
        const double left = error(out, 0, w / 2), right = error(out, w / 2, w), all = error(out, 0, w);
        std::printf("[ denoise ] SURE blend, seed %d: smooth half %.3g (best single %.3g), stripes %.3g (%.3g), "
                    "all %.3g (%.3g)\n",
                    int(seed), left, bestLeft, right, bestRight, all, bestAll);
        EXPECT_LT(left, 1.2 * bestLeft);
        EXPECT_LT(right, 1.2 * bestRight);
        EXPECT_LT(all, bestAll);
    }
}

// A colour that follows alpha, as in a cloud lit from the front: soft
// puffs of 1.5-4 pixels (alpha 1 - e^-density) whose colour is a + b alpha,
// under Monte Carlo-like noise, with alpha nearly noise-free. At a puff's
// rim the weights take in neighbours of more and less medium, and a
// weighted mean averages their colours; the alpha-regression candidate
// (docs/denoise.md, step 7) carries them over to the pixel's own alpha, so
// the denoised error falls (measured over seeds 1-3: 0.23-0.28x of the
// MSE without it).
TEST(DenoiseQuality, AColourThatFollowsAlphaKeepsItsRims) {
    const int w = 160, h = 120;
    for (uint64_t seed : {1u, 2u, 3u}) {
        Rng rng(seed);
        std::vector<float> density(size_t(w) * h, 0.f);
        for (int k = 0; k < 60; ++k) {
            const float cx = rng.uniform() * w, cy = rng.uniform() * h, r = 1.5f + 2.5f * rng.uniform();
            for (int y = std::max(0, int(cy - 4 * r)); y < std::min(h, int(cy + 4 * r) + 1); ++y)
                for (int x = std::max(0, int(cx - 4 * r)); x < std::min(w, int(cx + 4 * r) + 1); ++x)
                    density[size_t(y) * w + x] +=
                        3.f * std::exp(-0.5f * (std::pow(x + 0.5f - cx, 2.f) + std::pow(y + 0.5f - cy, 2.f)) / (r * r));
        }
        DenoiseInput in;
        in.width = w;
        in.height = h;
        std::vector<Color> truth;
        for (float d : density) {
            const float alpha = 1.f - std::exp(-d);
            const Color c = Color(0.2f, 0.25f, 0.35f) + alpha * Color(0.8f, 0.75f, 0.6f);
            truth.push_back(c);
            const float sigma = 0.08f + 0.15f * alpha;
            in.halfA.push_back(c + sigma * Color(gaussian(rng), gaussian(rng), gaussian(rng)));
            in.halfB.push_back(c + sigma * Color(gaussian(rng), gaussian(rng), gaussian(rng)));
            in.alphaA.push_back(alpha + 0.01f * gaussian(rng));
            in.alphaB.push_back(alpha + 0.01f * gaussian(rng));
        }
        auto error = [&](const Image& img) { return mseAgainst(truth, img); };
        DenoiseOptions without;
        without.alphaRegression = false;
        const double noisy = error(noisyMean(in)), plain = error(denoise(in, without)), with = error(denoise(in));
        std::printf("[ denoise ] colour following alpha, seed %d: MSE noisy %.3g, without regression %.3g, with %.3g "
                    "(%.2fx)\n",
                    int(seed), noisy, plain, with, with / plain);
        EXPECT_LT(with, 0.5 * plain);
    }
}

// The other side of the alpha regression: where alpha carries no structure,
// only noise (inside a cloud rendered with a few samples per pixel, alpha
// near 1 with noise of a few percent; the README's render), a line fitted
// against it is noise too, read at the pixel's own noisy alpha. The ridge
// on the slope by the alpha's noise variance shrinks it to the weighted mean
// there: the denoised MSE stays within 5 % of the denoiser's without the
// candidate (measured over seeds 1-3: 0.98-0.99x), where without that part
// of the ridge it grows (1.04-1.10x).
TEST(DenoiseQuality, ANoisyFlatAlphaAddsNoNoise) {
    const int w = 160, h = 120;
    for (uint64_t seed : {1u, 2u, 3u}) {
        Rng rng(seed);
        DenoiseInput in = sizedInput(w, h);
        std::vector<Color> truth;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const Color c(0.7f + 0.1f * float(x) / float(w), 0.7f, 0.75f);
                truth.push_back(c);
                // A sample that meets less medium is darker and more
                // transparent: colour and alpha noise are correlated.
                for (int half = 0; half < 2; ++half) {
                    const float shared = gaussian(rng);
                    const Color value = c + 0.1f * Color(shared + 0.5f * gaussian(rng), shared + 0.5f * gaussian(rng),
                                                         shared + 0.5f * gaussian(rng));
                    (half ? in.halfB : in.halfA).push_back(value);
                    (half ? in.alphaB : in.alphaA).push_back(0.95f + 0.04f * shared);
                }
            }
        auto error = [&](const Image& img) { return mseAgainst(truth, img); };
        DenoiseOptions without, noNoiseRidge;
        without.alphaRegression = false;
        noNoiseRidge.regressionNoiseRidge = 0;
        const double plain = error(denoise(in, without)), with = error(denoise(in)),
                     unshrunk = error(denoise(in, noNoiseRidge));
        std::printf("[ denoise ] noisy flat alpha, seed %d: MSE without regression %.3g, with %.3g (%.2fx), without "
                    "the noise ridge %.3g (%.2fx)\n",
                    int(seed), plain, with, with / plain, unshrunk, unshrunk / plain);
        EXPECT_LT(with, 1.05 * plain);
    }
}

// Emission seen straight, denoised apart (DenoiseInput::emittedA/B): a
// frame whose light is a sharp, noise-free emissive pattern (thin bright
// stripes, as a fire's base) over a smooth, noisy scattered glow. Denoised
// whole, the stripes make every patch distinct and the glow's noise stays
// (or the stripes blur); taken apart, the glow is smoothed on its own and
// the stripes come back exact. Measured over seeds 1-3: 0.11-0.12x the MSE
// of the whole-frame denoise (the floor is step 9's restored noise, the
// scattered part being restored at half the sigma). Emitted parts of zero
// change nothing, bit for bit.
TEST(DenoiseQuality, EmissionTakenApartKeepsItsEdgesAndTheGlowIsSmoothed) {
    const int w = 96, h = 72;
    for (uint64_t seed : {1u, 2u, 3u}) {
        Rng rng(seed);
        DenoiseInput in = sizedInput(w, h);
        std::vector<Color> truth;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float u = float(x) / float(w), v = float(y) / float(h);
                const Color glow = Color(0.3f + 0.2f * u, 0.25f + 0.1f * v, 0.2f);
                const Color fire = (x / 2 + y / 5) % 3 == 0 ? Color(2.f, 1.2f, 0.4f) : Color(0.f);
                truth.push_back(glow + fire);
                for (int half = 0; half < 2; ++half) {
                    const Color noisy = glow + 0.15f * Color(gaussian(rng), gaussian(rng), gaussian(rng));
                    (half ? in.halfB : in.halfA).push_back(noisy + fire);
                    (half ? in.emittedB : in.emittedA).push_back(fire);
                    (half ? in.alphaB : in.alphaA).push_back(1.f);
                }
            }
        DenoiseInput whole = in;
        whole.emittedA.clear();
        whole.emittedB.clear();
        const double apart = mseAgainst(truth, denoise(in)), together = mseAgainst(truth, denoise(whole));
        std::printf("[ denoise ] emission apart, seed %d: MSE noisy %.3g, denoised whole %.3g, apart %.3g (%.2fx)\n",
                    int(seed), mseAgainst(truth, noisyMean(in)), together, apart, apart / together);
        EXPECT_LT(apart, 0.25 * together);
        DenoiseInput zero = whole;
        zero.emittedA.assign(in.halfA.size(), Color(0));
        zero.emittedB.assign(in.halfA.size(), Color(0));
        EXPECT_EQ(denoise(zero).rgba, denoise(whole).rgba);
    }
}

TEST(DenoiseRobustness, AFireflysLightComesBackAsAFaintGlow) {
    const int w = 64, h = 48, fx = 32, fy = 24;
    const float level = 0.5f, firefly = 500.f;
    Rng rng(5);
    DenoiseInput in;
    in.width = w;
    in.height = h;
    for (int i = 0; i < w * h; ++i) {
        in.halfA.push_back(Color(level) + 0.05f * Color(gaussian(rng)));
        in.halfB.push_back(Color(level) + 0.05f * Color(gaussian(rng)));
    }
    in.halfA[size_t(fy * w + fx)] = Color(firefly);
    const DenoiseOptions glow;
    const double sigma = glow.fireflySigma;
    // The firefly's own light in the noisy image (the mean of the halves),
    // and the glow it should become: that light times the Gaussian, cut at
    // 3 sigma and normalised per axis over the pixels inside the image that
    // it reaches (no light leaves the frame).
    const double energy = (firefly - level) / 2;
    const int cut = int(std::ceil(3 * sigma));
    auto axis = [&](int p, int f, int size) {
        if (std::abs(p - f) > cut) return 0.0;
        double sum = 0;
        for (int q = std::max(0, f - cut); q <= std::min(size - 1, f + cut); ++q)
            sum += std::exp(-0.5 * (q - f) * (q - f) / (sigma * sigma));
        return std::exp(-0.5 * (p - f) * (p - f) / (sigma * sigma)) / sum;
    };
    // What lies above the level (red channel): in all, its largest value, and
    // its RMS difference from the prescribed glow.
    struct Light {
        double all = 0, peak = 0, offGlow = 0;
    };
    auto light = [&](const DenoiseOptions& o) {
        const Image d = denoise(in, o);
        Light l;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const double above = double(d.rgb(x, y).x) - level;
                const double off = above - energy * axis(x, fx, w) * axis(y, fy, h);
                l.all += above;
                l.peak = std::max(l.peak, above);
                l.offGlow += off * off;
            }
        l.offGlow = std::sqrt(l.offGlow / (w * h));
        return l;
    };
    const Light with = light(glow);
    DenoiseOptions unclamped;
    unclamped.suppressFireflies = false;
    const Light without = light(unclamped);
    DenoiseOptions dropped;
    dropped.fireflySigma = 0;
    const Light clampedOnly = light(dropped);
    std::printf("[ denoise ] firefly light %.1f, glow peak %.3f: kept %.1f (peak %.3f, RMS off the glow %.4f); "
                "unclamped %.1f (peak %.3f, off %.4f); clamp's light dropped %.1f\n",
                energy, energy / (2 * 3.14159265 * sigma * sigma), with.all, with.peak, with.offGlow, without.all,
                without.peak, without.offGlow, clampedOnly.all);
    // Kept: the whole light (the flat frame's noise adds about 0.05 / sqrt(2)
    // x sqrt(64 x 48) = 2 to the sum), and the prescribed glow to within the
    // denoised flat frame's own noise.
    EXPECT_NEAR(with.all, energy, 0.02 * energy);
    EXPECT_LT(with.offGlow, 0.02);
    // Without the clamp: a blotch, far from the glow; with the clamp's light
    // dropped, the light is lost.
    EXPECT_GT(without.offGlow, 10 * with.offGlow);
    EXPECT_LT(clampedOnly.all, 0.1 * energy);
}

}  // namespace
}  // namespace vdbmarch
