// The AOVs (render.aovs, docs/aovs.md): direct + indirect is the beauty for
// every method, the beauty does not change when AOVs are on, the direct part
// is what one scattering event brings, the feature layers' values on scenes
// whose answers are known, the EXR layer names, determinism across thread
// counts, and bad names refused.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>

#include <cstring>

#include "image/exr_io.h"
#include "support/support.h"

namespace vdbmarch::test {
namespace {

const char* const kAllAovs = R"(render.aovs=["depth","albedo","normal","direct","indirect"])";

const ExrLayer* findLayer(const RenderResult& r, const std::string& name) {
    for (const ExrLayer& l : r.layers)
        if (l.name == name) return &l;
    return nullptr;
}

RenderResult renderCloud(Method method, const std::vector<std::string>& extra) {
    std::vector<std::string> overrides = {"camera.resolution=[24,18]", "render.spp=4", "render.max_depth=3",
                                          "photons.count=20000", methodOverride(method)};
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    return renderImage(*buildScene(loadSceneFile(samplePath("cloud.json"), overrides)));
}


class AovMethods : public ::testing::TestWithParam<Method> {};

// AOVs on: the beauty is bit-identical to AOVs off, every layer is
// bit-identical for 1 and 3 threads, and direct + indirect is the beauty up
// to the rounding of one subtraction.
TEST_P(AovMethods, BeautyUnchangedDeterministicAndSplitAddsUp) {
    const RenderResult off = renderCloud(GetParam(), {"render.threads=2"});
    const RenderResult on1 = renderCloud(GetParam(), {kAllAovs, "render.threads=1"});
    const RenderResult on3 = renderCloud(GetParam(), {kAllAovs, "render.threads=3"});
    EXPECT_TRUE(off.layers.empty());
    EXPECT_TRUE(sameBits(off.image.rgba, on1.image.rgba));
    EXPECT_TRUE(sameBits(on1.image.rgba, on3.image.rgba));
    ASSERT_EQ(on1.layers.size(), 5u);
    ASSERT_EQ(on3.layers.size(), 5u);
    for (size_t i = 0; i < on1.layers.size(); ++i) {
        EXPECT_EQ(on1.layers[i].name, on3.layers[i].name);
        EXPECT_TRUE(sameBits(on1.layers[i].pixels, on3.layers[i].pixels)) << on1.layers[i].name;
    }
    const ExrLayer* direct = findLayer(on1, "direct");
    const ExrLayer* indirect = findLayer(on1, "indirect");
    ASSERT_TRUE(direct && indirect);
    double directSum = 0, indirectSum = 0;
    for (int y = 0; y < on1.image.height; ++y)
        for (int x = 0; x < on1.image.width; ++x) {
            const Color b = on1.image.rgb(x, y);
            for (int c = 0; c < 3; ++c) {
                const size_t i = (size_t(y) * size_t(on1.image.width) + size_t(x)) * 3 + size_t(c);
                const float d = direct->pixels[i], n = indirect->pixels[i];
                EXPECT_NEAR(d + n, b[c], 1e-6f * std::max(1.f, std::abs(b[c])));
                EXPECT_GE(d, 0.f);
                directSum += d;
                indirectSum += n;
            }
        }
    // The cloud is lit and scatters more than once at max_depth 3.
    EXPECT_GT(directSum, 0);
    EXPECT_GT(indirectSum, 0.01 * directSum);
}

// With max_depth 1 nothing scatters twice: the indirect layer is zero up to
// the rounding of direct and beauty accumulated in a different order.
TEST_P(AovMethods, SingleScatteringHasNoIndirectLight) {
    const RenderResult r = renderCloud(GetParam(), {R"(render.aovs=["indirect"])", "render.max_depth=1"});
    ASSERT_EQ(r.layers.size(), 1u);
    const ExrLayer& indirect = r.layers[0];
    double beautySum = 0;
    for (size_t p = 0; p < r.image.pixelCount(); ++p)
        for (int c = 0; c < 3; ++c) {
            const float b = r.image.rgba[4 * p + size_t(c)];
            beautySum += b;
            EXPECT_NEAR(indirect.pixels[3 * p + size_t(c)], 0.f, 1e-5f * std::max(1e-2f, b));
        }
    EXPECT_GT(beautySum, 0);
}

// The direct layer at max_depth 4 estimates the same image as the beauty at
// max_depth 1 (one scattering event). Independent seeds make the per-pixel
// differences independent zero-mean noise, so their mean over the pixels
// must be zero within 4 standard errors.
TEST_P(AovMethods, DirectLayerIsSingleScattering) {
    const std::vector<std::string> common = {"camera.resolution=[32,24]", "render.spp=8", "photons.count=20000",
                                             methodOverride(GetParam())};
    std::vector<std::string> a = common, b = common;
    a.insert(a.end(), {R"(render.aovs=["direct"])", "render.max_depth=4", "render.seed=1"});
    b.insert(b.end(), {"render.max_depth=1", "render.seed=2"});
    const RenderResult deep = renderImage(*buildScene(loadSceneFile(samplePath("cloud.json"), a)));
    const RenderResult single = renderImage(*buildScene(loadSceneFile(samplePath("cloud.json"), b)));
    ASSERT_EQ(deep.layers.size(), 1u);
    SampleStats diff, beautyDiff;  // the latter: what the test tells apart (multiple scattering)
    double singleSum = 0;
    for (size_t p = 0; p < single.image.pixelCount(); ++p) {
        double d = 0, bd = 0;
        for (int c = 0; c < 3; ++c) {
            d += double(deep.layers[0].pixels[3 * p + size_t(c)]) - double(single.image.rgba[4 * p + size_t(c)]);
            bd += double(deep.image.rgba[4 * p + size_t(c)]) - double(single.image.rgba[4 * p + size_t(c)]);
            singleSum += single.image.rgba[4 * p + size_t(c)];
        }
        diff.add(d);
        beautyDiff.add(bd);
    }
    ASSERT_GT(singleSum, 0);
    RecordProperty("direct_minus_single_z", str(diff.mean() / diff.stdError()));
    RecordProperty("beauty_minus_single_z", str(beautyDiff.mean() / beautyDiff.stdError()));
    EXPECT_GT(beautyDiff.mean(), 4 * beautyDiff.stdError());
    EXPECT_LE(std::abs(diff.mean()), 4 * diff.stdError())
        << "mean difference " << diff.mean() << ", standard error " << diff.stdError() << ", mean single "
        << singleSum / double(single.image.pixelCount());
}

INSTANTIATE_TEST_SUITE_P(Methods, AovMethods, ::testing::ValuesIn(estimatorMethods()), methodParamName);

// The emitted part of each half (RenderOptions::keepEmitted; what the
// denoiser takes apart): on the sample plume with scattering off and a
// black background, everything a camera sees is emission seen straight, so
// the emitted halves are the halves; with the emission off they are zero.
// Every method, 1 and 3 threads alike.
TEST_P(AovMethods, TheEmittedPartIsTheEmissionSeenStraight) {
    auto plume = [&](const std::vector<std::string>& extra, int threads) {
        std::vector<std::string> o = {"camera.resolution=[24,18]", "render.spp=4", "render.step=0.05",
                                      "photons.count=20000", "background=[0,0,0]", methodOverride(GetParam()),
                                      str("render.threads=", threads)};
        o.insert(o.end(), extra.begin(), extra.end());
        RenderOptions options;
        options.keepHalves = options.keepEmitted = true;
        return renderImage(*buildScene(loadSceneFile(samplePath("plume.json"), o)), options);
    };
    const RenderResult emissionOnly = plume({"media.0.sigma_s=[0,0,0]"}, 3);
    ASSERT_FALSE(emissionOnly.emittedEven.empty());
    double sum = 0;
    for (const auto& [half, emitted] : {std::pair{&emissionOnly.evenHalf, &emissionOnly.emittedEven},
                                        std::pair{&emissionOnly.oddHalf, &emissionOnly.emittedOdd}})
        for (size_t i = 0; i < half->pixelCount(); ++i)
            for (int c = 0; c < 3; ++c) {
                const float l = half->rgba[4 * i + size_t(c)], e = emitted->rgba[4 * i + size_t(c)];
                EXPECT_NEAR(e, l, 1e-5f * std::max(1.f, std::fabs(l))) << "pixel " << i;
                sum += double(l);
            }
    EXPECT_GT(sum, 0);  // the plume glows
    const RenderResult one = plume({"media.0.sigma_s=[0,0,0]"}, 1);
    EXPECT_TRUE(sameBits(one.emittedEven.rgba, emissionOnly.emittedEven.rgba));
    EXPECT_TRUE(sameBits(one.emittedOdd.rgba, emissionOnly.emittedOdd.rgba));
    const RenderResult dark = plume({"media.0.emission.intensity=0"}, 2);
    ASSERT_FALSE(dark.emittedEven.empty());
    for (size_t i = 0; i < dark.emittedEven.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(dark.emittedEven.rgba[4 * i + size_t(c)], 0.f);
            EXPECT_EQ(dark.emittedOdd.rgba[4 * i + size_t(c)], 0.f);
        }
}

// An orthographic camera 2 units in front of a slab face, in a medium of
// extinction 1000 and albedo 0.8: every sample's first event is an
// exponential free flight past the face (mean 1/1000), its albedo is
// sigma_s / sigma_t and its normal points back to the camera.
TEST(AovFeatures, OrthographicSlab) {
    const float sigmaT = 1000, spp = 16;
    auto scene = sceneFromJson(R"({
      "camera": {"type": "orthographic", "position": [0, 0, 3], "look_at": [0, 0, 0], "width_world": 1,
                 "resolution": [8, 8]},
      "media": [{"name": "slab", "type": "homogeneous", "sigma_a": 200, "sigma_s": 800,
                 "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
      "render": {"spp": 16, "method": "reference", "aovs": ["depth", "albedo", "normal"]}
    })");
    const RenderResult r = renderImage(*scene);
    const ExrLayer *depth = findLayer(r, "depth"), *albedo = findLayer(r, "albedo"), *normal = findLayer(r, "normal");
    ASSERT_TRUE(depth && albedo && normal);
    EXPECT_EQ(depth->channels, std::vector<std::string>{"Z"});
    const float expected = 2 + 1 / sigmaT, sigmaMean = (1 / sigmaT) / std::sqrt(spp);
    for (size_t p = 0; p < r.image.pixelCount(); ++p) {
        EXPECT_EQ(r.image.rgba[4 * p + 3], 1.f);
        EXPECT_NEAR(depth->pixels[p], expected, 4 * sigmaMean);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(albedo->pixels[3 * p + size_t(c)], 0.8f, 1e-6f);
            EXPECT_NEAR(normal->pixels[3 * p + size_t(c)], c == 2 ? 1.f : 0.f, 1e-6f);
        }
    }
}

// Background pixels: depth NoDepth, albedo and normal zero, alpha zero.
TEST(AovFeatures, BackgroundPixels) {
    auto scene = sceneFromJson(R"({
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [4, 4], "fov_deg": 10},
      "media": [{"name": "fog", "type": "homogeneous", "sigma_a": 1, "sigma_s": 1,
                 "bounds": {"min": [5, 5, 5], "max": [6, 6, 6]}}],
      "render": {"spp": 2, "aovs": "depth, albedo,normal"}
    })");
    const RenderResult r = renderImage(*scene);
    ASSERT_EQ(r.layers.size(), 3u);
    for (size_t p = 0; p < r.image.pixelCount(); ++p) {
        EXPECT_EQ(r.image.rgba[4 * p + 3], 0.f);
        EXPECT_EQ(r.layers[0].pixels[p], NoDepth);
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(r.layers[1].pixels[3 * p + size_t(c)], 0.f);
            EXPECT_EQ(r.layers[2].pixels[3 * p + size_t(c)], 0.f);
        }
    }
}

// A perspective camera: depth is camera-space z, not the distance along the
// ray (Cycles' Z pass): a diffuse wall at z = 0 seen from z = 4 is at depth 4
// in every pixel, the corner ones included; its normal faces the camera.
TEST(AovFeatures, PerspectiveDepthIsViewAxisDistance) {
    auto scene = sceneFromJson(R"({
      "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "resolution": [6, 6], "fov_deg": 60},
      "surfaces": [{"shape": "box", "transform": {"scale": [20, 20, 1], "translate": [0, 0, -0.5]},
                    "material": {"type": "diffuse", "albedo": [0.5, 0.25, 0.125]}}],
      "render": {"spp": 2, "aovs": ["depth", "albedo", "normal"]}
    })");
    const RenderResult r = renderImage(*scene);
    ASSERT_EQ(r.layers.size(), 3u);
    const float albedo[3] = {0.5f, 0.25f, 0.125f};
    for (size_t p = 0; p < r.image.pixelCount(); ++p) {
        EXPECT_NEAR(r.layers[0].pixels[p], 4.f, 1e-4f);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(r.layers[1].pixels[3 * p + size_t(c)], albedo[c], 1e-6f);
            EXPECT_NEAR(r.layers[2].pixels[3 * p + size_t(c)], c == 2 ? 1.f : 0.f, 1e-5f);
        }
    }
}

// Glass is a surface for depth, but albedo follows it to the first diffuse
// event (OpenImageDenoise's advice for delta surfaces): through a glass slab
// (ior 1.5) at normal incidence a sample reaches the wall behind with the
// slab's transmittance (1 - R)^2 / (1 - R^2), R = 0.04, and Fresnel choices
// weigh 1, so the albedo is 0.5 times that (binomial standard error).
TEST(AovFeatures, AlbedoFollowsGlassDepthStopsAtIt) {
    const int spp = 64, pixels = 16;
    auto scene = sceneFromJson(R"({
      "camera": {"type": "orthographic", "position": [0, 0, 3], "look_at": [0, 0, 0], "width_world": 1,
                 "resolution": [4, 4]},
      "surfaces": [
        {"shape": "box", "transform": {"scale": [4, 4, 1]}, "material": {"type": "dielectric", "ior": 1.5}},
        {"shape": "box", "transform": {"scale": [8, 8, 1], "translate": [0, 0, -2.5]},
         "material": {"type": "diffuse", "albedo": 0.5}}],
      "render": {"spp": 64, "pixel_jitter": false, "aovs": ["depth", "albedo", "normal"]}
    })");
    const RenderResult r = renderImage(*scene);
    ASSERT_EQ(r.layers.size(), 3u);
    const double R = 0.04, T = (1 - R) * (1 - R) / (1 - R * R);
    const double sigma = 0.5 * std::sqrt(T * (1 - T) / (spp * pixels));
    double albedo = 0;
    for (size_t p = 0; p < r.image.pixelCount(); ++p) {
        EXPECT_NEAR(r.layers[0].pixels[p], 2.5f, 1e-5f);
        albedo += r.layers[1].pixels[3 * p] / double(pixels);
        EXPECT_EQ(r.layers[1].pixels[3 * p], r.layers[1].pixels[3 * p + 2]);  // grey
    }
    RecordProperty("albedo", str(albedo, " expected ", 0.5 * T, " sigma ", sigma));
    EXPECT_NEAR(albedo, 0.5 * T, 4 * sigma);
}

// Layers are written into the beauty's single-part EXR under the names a
// compositor groups ("depth.Z", "albedo.R", ...), read back by OpenEXR;
// readExr still reads the beauty.
TEST(AovExr, LayerNamesAndValuesRoundTrip) {
    TempDir dir("aovs");
    Image img(3, 2);
    for (size_t i = 0; i < img.rgba.size(); ++i) img.rgba[i] = float(i);
    std::vector<ExrLayer> layers = {{"depth", {"Z"}, std::vector<float>(6)},
                                    {"normal", {"X", "Y", "Z"}, std::vector<float>(18)}};
    for (size_t i = 0; i < 6; ++i) layers[0].pixels[i] = 10.f + float(i);
    for (size_t i = 0; i < 18; ++i) layers[1].pixels[i] = -float(i);
    const std::string path = dir / "aovs.exr";
    writeExr(path, img, {}, layers);
    EXPECT_TRUE(tempLeftovers(dir.path()).empty());

    Imf::InputFile in(path.c_str());
    std::set<std::string> names;
    for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it) {
        names.insert(it.name());
        EXPECT_EQ(it.channel().type, Imf::FLOAT) << it.name();
    }
    EXPECT_EQ(names, (std::set<std::string>{"A", "B", "G", "R", "depth.Z", "normal.X", "normal.Y", "normal.Z"}));
    std::vector<float> z(6), ny(6);
    Imf::FrameBuffer fb;
    fb.insert("depth.Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(z.data()), sizeof(float), 3 * sizeof(float)));
    fb.insert("normal.Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(ny.data()), sizeof(float), 3 * sizeof(float)));
    in.setFrameBuffer(fb);
    in.readPixels(0, 1);
    for (size_t i = 0; i < 6; ++i) {
        EXPECT_EQ(z[i], 10.f + float(i));
        EXPECT_EQ(ny[i], -float(3 * i + 1));
    }
    const Image back = readExr(path);
    EXPECT_TRUE(sameBits(back.rgba, img.rgba));
}

TEST(AovExr, BadLayersRefused) {
    TempDir dir("aovs");
    Image img(2, 2);
    // Layers come from the renderer or from tiles read back: a bad one is a caller bug.
    expectErrorContaining<std::logic_error>(
        [&] { writeExr(dir / "a.exr", img, {}, {{"depth", {"Z"}, std::vector<float>(3)}}); },
        {"layer 'depth'", "2x2"});
    expectErrorContaining<std::logic_error>(
        [&] {
            writeExr(dir / "b.exr", img, {},
                     {{"depth", {"Z"}, std::vector<float>(4)}, {"depth", {"Z"}, std::vector<float>(4)}});
        },
        {"duplicate channel 'depth.Z'"});
    EXPECT_TRUE(listDir(dir.path()).empty());  // nothing written, no temporaries left
}

TEST(AovParse, BadNamesRefusedWithTheAllowedList) {
    auto withAovs = [](const std::string& value) {
        std::string scene = homogeneousScene();
        const std::string render = "\"render\": {\"spp\": 1";
        return scene.replace(scene.find(render), render.size(), render + ", \"aovs\": " + value);
    };
    const std::string allowed = "allowed: depth, albedo, normal, direct, indirect";
    expectErrorContaining<InputError>([&] { sceneFromJson(withAovs(R"(["depth", "Z"])")); },
                                      {"render.aovs", "\"Z\"", allowed});
    expectErrorContaining<InputError>([&] { sceneFromJson(withAovs(R"("albedo,beauty")")); },
                                      {"render.aovs", "\"beauty\"", allowed});
    expectErrorContaining<InputError>([&] { sceneFromJson(withAovs(R"(["depth", "depth"])")); },
                                      {"render.aovs", "\"depth\" twice"});
    expectErrorContaining<InputError>([&] { sceneFromJson(withAovs("[1]")); }, {"render.aovs", "strings"});
    expectErrorContaining<InputError>([&] { sceneFromJson(withAovs("true")); }, {"render.aovs", "array"});
}

class AovCli : public BadInput {};

TEST_F(AovCli, FlagWritesLayersAndRefusesUnknownNames) {
    const std::string scene = this->scene("s.json", homogeneousScene());
    CliResult ok = cli({"render", scene, "-o", work("out.exr"), "-q", "--aovs", "depth,direct,indirect"});
    ASSERT_EQ(ok.exitCode, 0) << ok.err;
    Imf::InputFile in(work("out.exr").c_str());
    std::set<std::string> names;
    for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it) names.insert(it.name());
    EXPECT_EQ(names, (std::set<std::string>{"A", "B", "G", "R", "depth.Z", "direct.B", "direct.G", "direct.R",
                                            "indirect.B", "indirect.G", "indirect.R"}));

    CliResult bad = cli({"render", scene, "-o", work("bad.exr"), "-q", "--aovs", "depth,nromal"});
    expectCliError(bad, {"render.aovs", "\"nromal\"", "allowed: depth, albedo, normal, direct, indirect"});
    EXPECT_FALSE(fs::exists(work("bad.exr")));
}

}  // namespace
}  // namespace vdbmarch::test
