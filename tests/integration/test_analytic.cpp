// Analytic scenes with known answers for the uniform marcher (eq. 5 with a
// random offset): transmittance, emission and single scattering in slabs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "core/blackbody.h"
#include "core/sampling.h"
#include "support/support.h"
#include "transport/phase.h"

namespace vdbmarch {
namespace {

using namespace test;

std::string orthoCamera(float width, int res, float z = 5) {
    return str(R"("camera": {"type": "orthographic", "position": [0.475, 0.475, )", z,
               R"(], "look_at": [0.475, 0.475, 0], "up": [0, 1, 0], "width_world": )", width,
               R"(, "resolution": [)", res, ", ", res, "]}");
}

// Homogeneous slab 1 unit thick, step 0.1: every ray takes exactly 10 samples,
// so the marched transmittance is exactly exp(-sigma_t).
TEST(AnalyticMarcher, HomogeneousSlabTransmittanceIsBeerLambert) {
    auto scene = sceneFromJson("{" + orthoCamera(0.5f, 16) + R"(,
        "media": [{"type": "homogeneous", "sigma_a": [0.7, 1.4, 0.1], "sigma_s": 0,
                   "bounds": {"min": [-10, -10, -0.5], "max": [10, 10, 0.5]}}],
        "render": {"step": 0.1, "seed": 3}})");
    RenderResult r = renderImage(*scene);
    double expectedAlpha = 1 - (std::exp(-0.7) + std::exp(-1.4) + std::exp(-0.1)) / 3;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) ASSERT_NEAR(r.image.alpha(x, y), expectedAlpha, 2e-5) << x << "," << y;
}

// A VDB box of constant density along a grid axis, stepped at one voxel: the
// trilinear hat functions form a partition of unity, so the samples' density
// sum is exactly the voxel count for any random offset.
TEST(AnalyticMarcher, VdbBoxTransmittanceIsExactAtOneVoxelStep) {
    TempDir dir;
    std::string vdb = writeBoxGrid(dir / "box20.vdb", 0, 19, 1.f, 0.05);
    auto scene = sceneFromJson("{" + orthoCamera(0.5f, 16) + R"(,
        "media": [{"type": "vdb", "file": ")" + vdb + R"(", "sigma_a": [2, 2, 2], "sigma_s": 0}],
        "render": {"seed": 5}})");
    EXPECT_FLOAT_EQ(scene->step, 0.05f);  // default: one voxel
    RenderResult r = renderImage(*scene);
    const double expectedAlpha = 1 - std::exp(-2.0 * 20 * 0.05);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) ASSERT_NEAR(r.image.alpha(x, y), expectedAlpha, 2e-5);
    // Empty space before and after the box is skipped, not marched.
    EXPECT_GT(r.counters.skippedLength, 0.0);
    EXPECT_LE(r.counters.marchSamples, uint64_t(16 * 16 * 24));
}

// Pure emission (sigma_s = 0): the per-step terms telescope, so
// L = scale * color * (1 - exp(-sigma_a * thickness)) exactly.
TEST(AnalyticMarcher, EmissionOfAbsorbingBoxIsExact) {
    TempDir dir;
    std::string vdb = writeEmissiveBox(dir / "emissive.vdb");
    auto scene = sceneFromJson("{" + orthoCamera(0.5f, 8) + R"(,
        "media": [{"type": "vdb", "file": ")" + vdb + R"(", "sigma_a": [1.5, 1.5, 1.5], "sigma_s": 0,
                   "emission": {"grid": "temperature", "scale": 2, "color": [1, 0.5, 0.25]}}],
        "render": {"seed": 2, "spp": 2}})");
    RenderResult r = renderImage(*scene);
    const double k = 2 * (1 - std::exp(-1.5));
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            Color c = r.image.rgb(x, y);
            ASSERT_NEAR(c.x, k * 1.0, 2e-5);
            ASSERT_NEAR(c.y, k * 0.5, 2e-5);
            ASSERT_NEAR(c.z, k * 0.25, 2e-5);
        }
}

// The same box with blackbody emission: the temperature grid (1) scaled to
// 2500 K, so L = intensity x tint x blackbodyRadiance(2500 K) x (1 - exp(-sigma_a)),
// the colour from the exact Planck sum (the table lookup is within 3e-5 of
// it in luminance-1 units: tests/core/test_blackbody.cpp).
TEST(AnalyticMarcher, BlackbodyEmissionOfAbsorbingBoxIsExact) {
    TempDir dir;
    std::string vdb = writeEmissiveBox(dir / "blackbody.vdb");
    auto scene = sceneFromJson("{" + orthoCamera(0.5f, 8) + R"(,
        "media": [{"type": "vdb", "file": ")" + vdb + R"(", "sigma_a": [1.5, 1.5, 1.5], "sigma_s": 0,
                   "emission": {"grid": "temperature", "blackbody": true, "temperature_scale": 2500,
                                "intensity": 2, "color": [1, 0.5, 1]}}],
        "render": {"seed": 2, "spp": 2}})");
    RenderResult r = renderImage(*scene);
    const double k = 2 * blackbodyLuminance(2500) * (1 - std::exp(-1.5));
    const Color c = blackbodyColorExact(2500);
    const double expected[3] = {k * c.x, k * 0.5 * c.y, k * c.z};
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            for (int ch = 0; ch < 3; ++ch) ASSERT_NEAR(r.image.rgb(x, y)[ch], expected[ch], 2e-5 + 3e-5 * k) << ch;
}

// Single scattering in a slab of thickness d lit by a directional light at
// angle theta, seen head-on:
//   L = sigma_s p(cos) E (1 - exp(-sigma_t d (1 + 1/mu))) / (sigma_t (1 + 1/mu)),  mu = cos theta.
// The random offset makes pixels vary; the test bound is 4 standard errors of
// the pixel mean plus the O((sigma_t dx)^2) discretisation bias of eq. 5 with
// S of eq. 7 (first-order terms of S and of the transmittance cancel).
class SingleScatteringSlab : public ::testing::TestWithParam<std::tuple<float, Method>> {};

TEST_P(SingleScatteringSlab, MatchesClosedForm) {
    const float g = std::get<0>(GetParam());
    const Method method = std::get<1>(GetParam());
    const double sigmaS = 0.8, sigmaT = 1.0, d = 1.0, theta = radians(40.f), E = 1.0;
    const double mu = std::cos(theta);
    auto scene = sceneFromJson("{" + orthoCamera(0.5f, 64) + str(R"(,
        "lights": [{"type": "directional", "direction": [0, )", -std::sin(theta), ", ", -mu, R"(], "irradiance": 1}],
        "media": [{"type": "homogeneous", "sigma_a": 0.2, "sigma_s": 0.8, "g": )", g, R"(,
                   "bounds": {"min": [-10, -10, -0.5], "max": [10, 10, 0.5]}}],
        "render": {"step": 0.01, "seed": 11, "max_depth": 1, "method": ")", methodName(method), R"(",
                   "spp": )", method == Method::Uniform ? 1 : 16, "}}"));
    RenderResult r = renderImage(*scene);
    // Phase argument: cos between the light's travel direction and the view ray's.
    double p = hgPhase(float(-mu), g);
    double k = sigmaT * (1 + 1 / mu);
    double expected = sigmaS * p * E * (1 - std::exp(-k * d)) / k;
    for (int c = 0; c < 3; ++c) {
        ChannelStats s = pixelStats(r.image, c);
        double tol = 4 * s.stdError + 2e-4 * expected;
        EXPECT_NEAR(s.mean, expected, tol) << methodName(method) << " g=" << g << " channel " << c;
    }
}

INSTANTIATE_TEST_SUITE_P(Anisotropy, SingleScatteringSlab,
                         ::testing::Combine(::testing::Values(0.f, 0.9f, -0.9f), ::testing::ValuesIn(estimatorMethods())),
                         [](const auto& info) {
                             float g = std::get<0>(info.param);
                             return std::string(methodName(std::get<1>(info.param))) +
                                    (g == 0 ? "_g0" : (g > 0 ? "_gPlus09" : "_gMinus09"));
                         });

// The same scene and seed give bit-identical pixels for any thread count,
// for every method and L_i source (photon tracing and the cache build
// included: max_depth 3), over several progressive photon passes (one per
// sample: fresh photon maps, and the cache refined at passes 1 and 3).
class Determinism : public ::testing::TestWithParam<std::tuple<Method, LiSource>> {};

std::string liOverride(LiSource li) { return str("render.li=\"", liSourceName(li), "\""); }

std::string methodLiName(const ::testing::TestParamInfo<std::tuple<Method, LiSource>>& info) {
    return str(methodName(std::get<0>(info.param)), "_", liSourceName(std::get<1>(info.param)));
}

TEST_P(Determinism, ImageIsIdenticalForAnyThreadCount) {
    const auto [method, li] = GetParam();
    std::string scenePath = samplePath("cloud.json");
    auto render = [&](int threads) {
        SceneDesc d = loadSceneFile(scenePath, {"camera.resolution=[40,30]", "render.spp=4", "render.max_depth=3",
                                                "photons.count=20000", "photons.spp_per_pass=1", liOverride(li),
                                                methodOverride(method), str("render.threads=", threads)});
        return renderImage(*buildScene(d));
    };
    RenderResult a = render(1), b = render(2), c = render(5);
    ASSERT_EQ(a.image.rgba.size(), b.image.rgba.size());
    EXPECT_EQ(0, std::memcmp(a.image.rgba.data(), b.image.rgba.data(), a.image.rgba.size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(a.image.rgba.data(), c.image.rgba.data(), a.image.rgba.size() * sizeof(float)));
    EXPECT_EQ(a.counters.marchSamples, c.counters.marchSamples);
    // Photons are re-traced when a photon map or a cache is used (never by
    // the reference tracer).
    const bool photonsUsed = method != Method::Reference && (li == LiSource::Photons || method == Method::Guided);
    EXPECT_EQ(a.photonPasses, photonsUsed ? 4 : 1);
    double sum = 0;
    for (float v : a.image.rgba) sum += v;
    EXPECT_GT(sum, 0);  // the cloud is lit: not a trivially black image
}

INSTANTIATE_TEST_SUITE_P(Methods, Determinism,
                         ::testing::Combine(::testing::ValuesIn(estimatorMethods()),
                                            ::testing::Values(LiSource::Path, LiSource::Photons)),
                         methodLiName);

// Work grows with active voxels, not with the bounding box: a far-away extra
// voxel that inflates the bbox 50x leaves the march sample count unchanged.
TEST(EmptySpace, MarchSamplesDoNotGrowWithTheBoundingBox) {
    TempDir dir;
    std::string small = writeBoxGrid(dir / "blob.vdb", 0, 9, 0.5f, 0.05);
    std::string large = writeBoxGrid(dir / "blob_far.vdb", 0, 9, 0.5f, 0.05, "density", {Index3(-500), Index3(500)});
    auto run = [&](const std::string& file) {
        auto scene = sceneFromJson(R"({"camera": {"type": "perspective", "position": [0.5, 0.4, 3], "look_at": [0.225, 0.225, 0.225],
            "fov_deg": 20, "resolution": [24, 24]},
            "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": 1}],
            "media": [{"type": "vdb", "file": ")" + file + R"(", "sigma_s": 4}],
            "render": {"method": "uniform"}})");  // deterministic march: counts compare exactly
        return renderImage(*scene).counters;
    };
    RenderCounters a = run(small), b = run(large);
    EXPECT_GT(a.marchSamples, 0u);
    EXPECT_EQ(a.marchSamples, b.marchSamples);
    EXPECT_EQ(a.shadowSamples, b.shadowSamples);
}

// A time budget renders whole sweeps of samples per pixel (one, then as many
// as fill a tenth of a second, ending at photon passes); the image is the
// same, bit for bit, as a render of that many samples per pixel (for guided,
// the cache lookups along a ray must not depend on earlier rays).
class TimeBudget : public ::testing::TestWithParam<std::tuple<Method, LiSource>> {};

TEST_P(TimeBudget, PassesGiveTheSameImageAsTheSameSampleCount) {
    const auto [method, li] = GetParam();
    std::string scenePath = samplePath("cloud.json");
    // Photon passes every other sample: the image depends on the sample
    // count only, not on where the budget ran out.
    // Adaptive sampling off: its stops depend on the measured time.
    SceneDesc d = loadSceneFile(scenePath, {"camera.resolution=[24,18]", "render.max_depth=2", "photons.count=5000",
                                            "photons.spp_per_pass=2", "experiments.adaptive=false", liOverride(li),
                                            methodOverride(method)});
    auto scene = buildScene(d);
    RenderOptions timed;
    timed.timeBudget = 0.5;
    RenderResult a = renderImage(*scene, timed);
    ASSERT_GE(a.spp, 1);
    d.render.spp = a.spp;
    RenderResult b = renderImage(*buildScene(d));
    EXPECT_EQ(b.spp, a.spp);
    EXPECT_EQ(b.photonPasses, a.photonPasses);
    EXPECT_EQ(0, std::memcmp(a.image.rgba.data(), b.image.rgba.data(), a.image.rgba.size() * sizeof(float)));
}

// Time kept back for what follows the render (the denoiser) ends the
// sweeps that much earlier: with 0.45 of 0.6 s kept back, the sweeps stop
// after about 0.15 s instead of 0.6 s.
TEST(TimeBudgetReserve, EndsTheSweepsEarlier) {
    SceneDesc d = loadSceneFile(samplePath("cloud.json"), {"camera.resolution=[24,18]", "render.max_depth=2"});
    auto scene = buildScene(d);
    RenderOptions plain, reserved;
    plain.timeBudget = reserved.timeBudget = 0.6;
    reserved.reserveSeconds = 0.45;
    const RenderResult a = renderImage(*scene, plain), b = renderImage(*scene, reserved);
    EXPECT_LT(b.seconds, a.seconds);
    EXPECT_LT(b.spp, a.spp);
    EXPECT_GE(b.spp, 1);
}

// A budget spent before the first sample still renders one sample per
// pixel, and two where the halves are kept (the denoiser needs both).
TEST(TimeBudgetReserve, ADenoisedRenderGetsTwoSamples) {
    auto scene = buildScene(loadSceneFile(samplePath("cloud.json"), {"camera.resolution=[24,18]"}));
    RenderOptions plain, halves;
    plain.timeBudget = halves.timeBudget = 1e-6;
    halves.keepHalves = true;
    EXPECT_EQ(renderImage(*scene, plain).spp, 1);
    EXPECT_EQ(renderImage(*scene, halves).spp, 2);
}

// A slab of medium fills the left half of the frame; the right half sees
// only the uniform background (no pixel noise at all).
SceneDesc halfSlabScene(const std::vector<std::string>& extra) {
    const std::string json = R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [32, 16]},
        "media": [{"type": "homogeneous", "sigma_a": 0.5, "sigma_s": 1, "g": 0.5,
                   "bounds": {"min": [-10, -10, -1], "max": [0, 10, 1]}}],
        "background": [1, 1, 1], "render": {"method": "reference", "max_depth": 4, "seed": 5}})";
    return parseSceneText(json, "slab.json", extra);
}

const ExrLayer* samplesLayer(const RenderResult& r) {
    for (const ExrLayer& l : r.layers)
        if (l.name == "samples") return &l;
    return nullptr;
}

// Adaptive sampling of a timed render (experiments.adaptive, docs/noise.md): the
// background's blocks, of zero noise, stop at the first check (16 samples)
// and the slab's sample on; blocks stop whole; the samples layer says so.
TEST(TimedAdaptive, BlocksOfNoNoiseStopAtTheFirstCheck) {
    auto scene = buildScene(halfSlabScene({}));
    RenderOptions timed;
    timed.timeBudget = 1.0;
    const RenderResult r = renderImage(*scene, timed);
    ASSERT_GT(r.spp, 24) << "too slow a machine for a second of rendering to pass the first checks";
    const ExrLayer* samples = samplesLayer(r);
    ASSERT_NE(samples, nullptr);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            const float n = samples->pixels[size_t(y) * 32 + size_t(x)];
            EXPECT_EQ(n, samples->pixels[size_t(y / 8 * 8) * 32 + size_t(x / 8 * 8)]);
            if (x >= 16) {
                EXPECT_EQ(n, 16.f) << x << ", " << y;
            } else {
                EXPECT_GT(n, 16.f) << x << ", " << y;
            }
        }
    EXPECT_LT(r.meanSpp, double(r.spp));
    EXPECT_EQ(*std::max_element(samples->pixels.begin(), samples->pixels.end()), float(r.spp));
}

// Stopping blocks by their noise does not move the image: the slab's mean
// agrees with that of an evenly sampled render of 2048 samples per pixel,
// within 4 standard errors of the difference (each from its halves).
TEST(TimedAdaptive, AgreesWithEvenSampling) {
    auto adaptive = buildScene(halfSlabScene({}));
    RenderOptions timed;
    timed.timeBudget = 1.0;
    timed.keepHalves = true;
    const RenderResult a = renderImage(*adaptive, timed);
    ASSERT_GT(a.spp, 24);
    RenderOptions even;
    even.keepHalves = true;
    const RenderResult b = renderImage(*buildScene(halfSlabScene({"render.spp=2048", "render.seed=6"})), even);
    // Mean over the slab's pixels and RGB, and the variance of that mean.
    auto slab = [](const RenderResult& r, double& variance) {
        double sum = 0;
        variance = 0;
        size_t n = 0;
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x, ++n)
                for (int c = 0; c < 3; ++c) {
                    sum += r.image.rgb(x, y)[c];
                    const double d = r.evenHalf.rgb(x, y)[c] - r.oddHalf.rgb(x, y)[c];
                    variance += d * d / 4;
                }
        const double values = 3.0 * double(n);
        variance /= values * values;
        return sum / values;
    };
    double va, vb;
    const double ma = slab(a, va), mb = slab(b, vb);
    EXPECT_NEAR(ma, mb, 4 * std::sqrt(va + vb)) << "adaptive " << ma << " even " << mb;
    EXPECT_GT(ma, 0.05);
}

// Where the render is denoised, a block's noise counts by what the
// denoiser leaves of it: with a denoised variance of 0 in the slab's first
// column of blocks (the denoiser's gain capped at 1000) and larger than the
// noise in the second (gain 1), the first stops far earlier.
TEST(TimedAdaptive, BlocksTheDenoiserCleansGetFewerSamples) {
    auto scene = buildScene(halfSlabScene({}));
    RenderOptions timed;
    timed.timeBudget = 1.0;
    int calls = 0;
    timed.denoisedVariance = [&](const FrameHalves& f) {
        ++calls;
        std::vector<float> variances(f.even.pixelCount());
        for (int y = 0; y < f.even.height; ++y)
            for (int x = 8; x < f.even.width; ++x) variances[size_t(y) * size_t(f.even.width) + size_t(x)] = 1e6f;
        return variances;
    };
    const RenderResult r = renderImage(*scene, timed);
    ASSERT_GT(r.spp, 24) << "too slow a machine for a second of rendering to pass the first checks";
    EXPECT_GT(calls, 0);
    const ExrLayer* samples = samplesLayer(r);
    ASSERT_NE(samples, nullptr);
    double first = 0, second = 0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) (x < 8 ? first : second) += samples->pixels[size_t(y) * 32 + size_t(x)];
    EXPECT_LT(first, 0.5 * second) << "first column " << first / 128 << " spp, second " << second / 128;
}

// experiments.adaptive = false: every pixel gets the same samples.
TEST(TimedAdaptive, OffSamplesEvenly) {
    auto scene = buildScene(halfSlabScene({"experiments.adaptive=false"}));
    RenderOptions timed;
    timed.timeBudget = 0.5;
    const RenderResult r = renderImage(*scene, timed);
    EXPECT_EQ(samplesLayer(r), nullptr);
    EXPECT_EQ(r.meanSpp, double(r.spp));
}

INSTANTIATE_TEST_SUITE_P(Methods, TimeBudget,
                         ::testing::Combine(::testing::ValuesIn(estimatorMethods()),
                                            ::testing::Values(LiSource::Path, LiSource::Photons)),
                         methodLiName);

std::string furnaceScene(const std::string& sigmaS) {
    return R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [24, 24]},
        "media": [{"type": "homogeneous", "sigma_a": 0, "sigma_s": )" + sigmaS + R"(, "g": 0.7,
                   "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
        "background": [1, 1, 1], "render": {"method": "reference", "spp": 16, "max_depth": 100000, "seed": 4}})";
}

// Furnace: a medium of albedo 1 under a uniform background of radiance 1
// neither absorbs nor emits, so every pixel's expectation is exactly 1. Paths
// only carry weights other than 1 through Russian roulette; the bound is 4
// standard errors of the pixel mean.
TEST(Reference, FurnaceWithAlbedoOneIsFlatAtTheBackground) {
    for (const char* sigma : {"4", "[1, 4, 9]"}) {  // grey, then chromatic extinction
        RenderResult r = renderImage(*sceneFromJson(furnaceScene(sigma)));
        EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
        for (int c = 0; c < 3; ++c) {
            ChannelStats s = pixelStats(r.image, c);
            EXPECT_NEAR(s.mean, 1.0, 4 * s.stdError + 1e-6) << "sigma_s " << sigma << " channel " << c;
        }
    }
}

// The same furnace with the medium filling an interface sphere (a region of
// constant media, whose free flights look for the surface only a few mean
// free paths ahead and go on from there: path_tracer.cpp, probeLength). With
// 30-60 mean free paths across the sphere most flights are cut short; any
// light lost or gained at a cut moves the mean off 1.
TEST(Reference, FurnaceHoldsWhereFreeFlightsAreCutShort) {
    for (const char* sigma : {"30", "[15, 30, 60]"}) {
        RenderResult r = renderImage(*sceneFromJson(str(
            R"({"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [24, 24]},
            "media": [{"name": "dense", "type": "homogeneous", "sigma_a": 0, "sigma_s": )", sigma, R"(, "g": 0.7}],
            "surfaces": [{"shape": "sphere", "material": {"type": "interface"}, "interior": "dense"}],
            "background": [1, 1, 1], "render": {"method": "reference", "spp": 8, "max_depth": 100000, "seed": 5}})")));
        EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
        for (int c = 0; c < 3; ++c) {
            ChannelStats s = pixelStats(r.image, c);
            EXPECT_NEAR(s.mean, 1.0, 4 * s.stdError + 1e-6) << "sigma_s " << sigma << " channel " << c;
        }
    }
}

// Transmittance through a VDB box: the reference's alpha is the fraction of
// paths that scattered or were absorbed, whose expectation is 1 - T.
TEST(Reference, VdbBoxAlphaIsBeerLambertInExpectation) {
    TempDir dir;
    std::string vdb = writeBoxGrid(dir / "refbox.vdb", 0, 19, 1.f, 0.05);
    auto scene = sceneFromJson(R"({"camera": {"type": "orthographic", "position": [0.475, 0.475, 5],
        "look_at": [0.475, 0.475, 0], "width_world": 0.5, "resolution": [32, 32]},
        "media": [{"type": "vdb", "file": ")" + vdb + R"(", "sigma_a": 0.6, "sigma_s": 0.4}],
        "render": {"method": "reference", "spp": 8, "seed": 8}})");
    RenderResult r = renderImage(*scene);
    ChannelStats a = pixelStats(r.image, 3);
    EXPECT_NEAR(a.mean, 1 - std::exp(-1.0), 4 * a.stdError);
}

// Alpha is the background seen with no scattering event, through glass
// too, for every method: a glass ball in vacuum (fog only out of view)
// covering about a quarter of the frame hides almost none of the background
// (paths end inside it only at the surface-bounce limit), where counting
// glass as opaque would give a mean alpha near 0.25.
TEST(Alpha, GlassHidesNoBackgroundForAnyMethod) {
    auto render = [](Method m) {
        auto scene = sceneFromJson(std::string(R"({"camera": {"type": "perspective", "position": [0, 0, 4], "look_at": [0, 0, 0],
            "fov_deg": 30, "resolution": [24, 24]},
            "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": 1}],
            "media": [{"type": "homogeneous", "sigma_a": 0.1, "sigma_s": 0.5,
                       "bounds": {"min": [5, 5, 5], "max": [6, 6, 6]}}],
            "surfaces": [{"shape": "sphere", "transform": {"scale": 0.55},
                          "material": {"type": "dielectric", "ior": 1.5}}],
            "render": {"spp": 8, "seed": 3, "max_depth": 2, "method": ")") +
                                   methodName(m) + R"("}})");
        return renderImage(*scene).image;
    };
    for (Method m : estimatorMethods()) {
        const Image img = render(m);
        const ChannelStats a = pixelStats(img, 3);
        EXPECT_LT(a.mean, 0.02) << methodName(m);
    }
}

// Agreement: with max_depth 1 the reference and the uniform marcher estimate
// the same single-scattering image of a heterogeneous VDB cloud behind a
// glass sphere (directional light and sky; straight shadow rays for both).
// The mean per-pixel difference over the image and over each quadrant is zero
// within 4 standard errors (paired) plus the marcher's O((kappa dx)^2) bias
// (well under 0.5%).
void expectReferenceAgreesWithUniformForSingleScattering(const std::vector<std::string>& medium) {
    std::string scenePath = samplePath("cloud.json");
    std::vector<std::string> common = {"camera.resolution=[32,24]", "render.max_depth=1",
        R"(surfaces=[{"shape": "sphere", "transform": {"scale": 0.35, "translate": [0.6, 0.45, 1.2]}, "material": {"type": "dielectric", "ior": 1.5}}])"};
    common.insert(common.end(), medium.begin(), medium.end());
    auto render = [&](const std::string& method, int spp) {
        std::vector<std::string> o = common;
        o.push_back("render.method=" + method);
        o.push_back(str("render.spp=", spp));
        return renderImage(*buildScene(loadSceneFile(scenePath, o))).image;
    };
    Image ref = render("reference", 512), uni = render("uniform", 24);
    for (int q = 0; q < 5; ++q) {  // whole image, then quadrants
        int x0 = q == 0 ? 0 : ((q - 1) % 2) * 16, y0 = q == 0 ? 0 : ((q - 1) / 2) * 12;
        int w = q == 0 ? 32 : 16, h = q == 0 ? 24 : 12;
        // Paired test on per-pixel differences: their spread is the two
        // estimators' noise, and their mean is zero if they agree.
        Image diff(w, h), base(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                diff.set(x, y, ref.rgb(x0 + x, y0 + y) - uni.rgb(x0 + x, y0 + y), 0);
                base.set(x, y, uni.rgb(x0 + x, y0 + y), 0);
            }
        for (int c = 0; c < 3; ++c) {
            ChannelStats d = pixelStats(diff, c), b = pixelStats(base, c);
            EXPECT_NEAR(d.mean, 0.0, 4 * d.stdError + 5e-3 * b.mean) << "region " << q << " channel " << c;
        }
    }
}

TEST(Reference, AgreesWithTheUniformMarcherForSingleScattering) { expectReferenceAgreesWithUniformForSingleScattering({}); }

// The same in a chromatic cloud (extinction 8.1, 5.3 and 2.9 per channel):
// the reference's spectral MIS (one path, a hero channel, the balance
// heuristic over channels) against the marcher's per-channel quadrature.
TEST(Reference, AgreesWithTheUniformMarcherInAChromaticMedium) {
    expectReferenceAgreesWithUniformForSingleScattering(
        {"media.0.sigma_a=[0.1, 0.3, 0.9]", "media.0.sigma_s=[8, 5, 2]"});
}

// Convergence: the reference is unbiased with finite variance, so its MSE
// against a high-sample image falls as 1/spp: doubling spp divides it by
// (1/n + 1/N) / (1/(2n) + 1/N) (N: the high image's spp, whose own noise adds
// 1/N). The ratio's tolerance is 4 standard errors from the measured spread of
// the per-pixel squared errors (delta method).
TEST(Reference, MseHalvesWhenSamplesDouble) {
    std::string scenePath = samplePath("cloud.json");
    auto render = [&](int spp, int seed) {
        SceneDesc d = loadSceneFile(scenePath, {"camera.resolution=[32,24]", "render.method=reference",
                                                "render.max_depth=4", str("render.spp=", spp), str("render.seed=", seed)});
        return renderImage(*buildScene(d)).image;
    };
    const int N = 1024, n = 16;
    Image high = render(N, 100), a = render(n, 1), b = render(2 * n, 2);
    auto mse = [&](const Image& img, double& se) {
        double s = 0, s2 = 0;
        size_t m = 0;
        for (size_t i = 0; i < img.rgba.size(); ++i) {
            if (i % 4 == 3) continue;
            double e = double(img.rgba[i]) - double(high.rgba[i]);
            s += e * e;
            s2 += e * e * e * e;
            ++m;
        }
        double mean = s / double(m);
        se = std::sqrt(std::max(0.0, s2 / double(m) - mean * mean) / double(m - 1));
        return mean;
    };
    double seA, seB;
    double mseA = mse(a, seA), mseB = mse(b, seB);
    double ratio = mseA / mseB;
    double expected = (1.0 / n + 1.0 / N) / (1.0 / (2 * n) + 1.0 / N);
    double relSe = std::sqrt((seA / mseA) * (seA / mseA) + (seB / mseB) * (seB / mseB));
    EXPECT_NEAR(ratio, expected, 4 * relSe * expected) << "MSE " << mseA << " -> " << mseB;
    EXPECT_LT(relSe, 0.25);  // the test has power: the ratio is resolved to better than 25%
    std::printf("MSE %g -> %g, ratio %g (expected %g, relative SE %g)\n", mseA, mseB, ratio, expected, relSe);
}

// Single scattering in a VDB box lit and seen along the grid's z axis
// (backscatter, cos = -1). Camera and light paths cross the same density, so
// with u = ∫ rho dz the integral becomes ∫ exp(-2 sigma_t u) du whatever the
// trilinear ramps at the faces: L = sigma_s p(-1) E (1 - exp(-2 sigma_t N h)) /
// (2 sigma_t). For the reference this checks delta tracking and ratio tracking
// against local VDB majorants; for the marchers, trilinear sampling and shadow
// marching. Bound: 4 standard errors plus the marchers' O((kappa dx)^2) bias.
class VdbSingleScattering : public ::testing::TestWithParam<Method> {};

TEST_P(VdbSingleScattering, MatchesClosedFormAlongTheAxis) {
    TempDir dir;
    std::string vdb = writeBoxGrid(dir / "ss_box.vdb", {0, 0, 0}, {39, 39, 19}, 0.5f, 0.05);
    const double sigmaS = 3, sigmaA = 1, g = 0.5, E = 2, Nh = 20 * 0.05 * 0.5;  // density 0.5
    // The uniform marcher's pixels vary only by the random offset; the
    // reference's by whole paths; the other marchers' by their sampled steps.
    const int spp = GetParam() == Method::Uniform ? 2 : isPathTracer(GetParam()) ? 64 : 16;
    auto scene = sceneFromJson(str(R"({"camera": {"type": "orthographic", "position": [0.975, 0.975, 3],
        "look_at": [0.975, 0.975, 0], "width_world": 0.6, "resolution": [32, 32]},
        "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": )", E, R"(}],
        "media": [{"type": "vdb", "file": ")", vdb, R"(", "sigma_a": )", sigmaA, R"(, "sigma_s": )", sigmaS,
        R"(, "g": )", g, R"(}],
        "render": {"method": ")", methodName(GetParam()), R"(", "max_depth": 1, "spp": )", spp,
        R"(, "step": 0.005, "seed": 21}})"));
    RenderResult r = renderImage(*scene);
    const double sigmaT = sigmaS + sigmaA;
    const double expected = sigmaS * hgPhase(-1.f, float(g)) * E * (1 - std::exp(-2 * sigmaT * Nh)) / (2 * sigmaT);
    ChannelStats s = pixelStats(r.image, 0);
    EXPECT_NEAR(s.mean, expected, 4 * s.stdError + 1e-3 * expected) << methodName(GetParam());
}

INSTANTIATE_TEST_SUITE_P(Methods, VdbSingleScattering, ::testing::ValuesIn(estimatorMethods()), methodParamName);

// The reference's emission estimator (sigma_a L_e / sigma_maj at tentative
// collisions) against the closed form of an absorbing, emitting VDB box.
TEST(Reference, EmissionOfAbsorbingBoxMatchesClosedForm) {
    TempDir dir;
    std::string vdb = writeEmissiveBox(dir / "emissive_ref.vdb");
    auto scene = sceneFromJson(R"({"camera": {"type": "orthographic", "position": [0.475, 0.475, 5],
        "look_at": [0.475, 0.475, 0], "width_world": 0.5, "resolution": [32, 32]},
        "media": [{"type": "vdb", "file": ")" + vdb + R"(", "sigma_a": [1.5, 1.5, 1.5], "sigma_s": 0,
                   "emission": {"grid": "temperature", "scale": 2, "color": [1, 0.5, 0.25]}}],
        "render": {"method": "reference", "seed": 2, "spp": 8}})");
    RenderResult r = renderImage(*scene);
    const double k = 2 * (1 - std::exp(-1.5));
    const double color[3] = {1, 0.5, 0.25};
    for (int c = 0; c < 3; ++c) {
        ChannelStats s = pixelStats(r.image, c);
        EXPECT_NEAR(s.mean, k * color[c], 4 * s.stdError + 1e-6) << "channel " << c;
    }
}

// The reference is deterministic for any thread count too.
TEST(Reference, ImageIsIdenticalForAnyThreadCount) {
    std::string scenePath = samplePath("glass.json");
    auto render = [&](int threads) {
        SceneDesc d = loadSceneFile(scenePath, {"camera.resolution=[32,24]", "render.spp=2", "render.method=reference",
                                                "render.max_depth=8", str("render.threads=", threads)});
        setWarningsQuiet(true);
        RenderResult r = renderImage(*buildScene(d));
        setWarningsQuiet(false);
        return r;
    };
    RenderResult a = render(1), b = render(2);
    EXPECT_EQ(0, std::memcmp(a.image.rgba.data(), b.image.rgba.data(), a.image.rgba.size() * sizeof(float)));
    EXPECT_EQ(a.counters.marchSamples, b.counters.marchSamples);
}

}  // namespace
}  // namespace vdbmarch
