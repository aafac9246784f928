// Tiles of a render (render --tile / --crop, docs/farm.md): the band split
// partitions the frame, and a cropped render is bit-identical to its part of
// the whole-frame render for every method (photons, progressive photon
// passes (three here) and the cache included), with AOVs, at another thread
// count.
#include <cstring>

#include "support/support.h"

namespace vdbmarch::test {
namespace {

TEST(TileOfFrame, BandsPartitionTheFrameInOrder) {
    for (int h : {1, 7, 72, 480})
        for (int n = 1; n <= std::min(h, 13); ++n) {
            int next = 0;
            for (int i = 0; i < n; ++i) {
                const PixelRect r = tileOfFrame(i, n, 33, h);
                EXPECT_EQ(r.x0, 0);
                EXPECT_EQ(r.x1, 33);
                EXPECT_EQ(r.y0, next) << i << "/" << n << " of " << h;
                EXPECT_GT(r.y1, r.y0) << i << "/" << n << " of " << h;  // never empty while n <= h
                next = r.y1;
            }
            EXPECT_EQ(next, h);
        }
}

TEST(TileOfFrame, RefusesCountsAndIndicesOutsideTheFrame) {
    expectErrorContaining<InputError>([] { tileOfFrame(0, 0, 8, 6); }, {"--tile 0/0", "6"});
    expectErrorContaining<InputError>([] { tileOfFrame(0, 7, 8, 6); }, {"--tile 0/7", "image height (6)"});
    expectErrorContaining<InputError>([] { tileOfFrame(3, 3, 8, 6); }, {"--tile 3/3", "0 to 2"});
    expectErrorContaining<InputError>([] { tileOfFrame(-1, 3, 8, 6); }, {"--tile -1/3"});
}

RenderResult renderPart(const std::string& sample, Method method, int threads, std::optional<PixelRect> crop,
                        const std::vector<std::string>& extra = {}) {
    std::vector<std::string> overrides = {"camera.resolution=[32,24]", "render.spp=6", "render.max_depth=4",
                                          "photons.count=20000", "photons.spp_per_pass=2", "render.step=0.12", methodOverride(method),
                                          str("render.threads=", threads)};
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    RenderOptions options;
    options.crop = crop;
    return renderImage(*buildScene(loadSceneFile(samplePath(sample), overrides)), options);
}

// The floats of `crop` cut out of a whole-frame buffer of `n` per pixel.
std::vector<float> cut(const std::vector<float>& frame, int frameWidth, const PixelRect& crop, size_t n) {
    std::vector<float> out;
    for (int y = crop.y0; y < crop.y1; ++y)
        out.insert(out.end(), frame.begin() + (int64_t(y) * frameWidth + crop.x0) * int64_t(n),
                   frame.begin() + (int64_t(y) * frameWidth + crop.x1) * int64_t(n));
    return out;
}


class TileMethods : public ::testing::TestWithParam<Method> {};

// A crop, and the band tiles 1/3 and 2/3, rendered with another thread count
// than the whole frame, hold exactly its pixels and AOV layers.
TEST_P(TileMethods, CropIsBitIdenticalToItsPartOfTheWholeFrame) {
    const std::vector<std::string> aovs = {R"(render.aovs=["depth","albedo","direct","indirect"])"};
    for (const char* sample : {"cloud.json", "glass.json"}) {
        SCOPED_TRACE(sample);
        const RenderResult whole = renderPart(sample, GetParam(), 2, std::nullopt, aovs);
        EXPECT_EQ(whole.window, (PixelRect{0, 0, 32, 24}));
        for (const PixelRect crop : {PixelRect{7, 5, 29, 19}, tileOfFrame(1, 3, 32, 24), tileOfFrame(2, 3, 32, 24)}) {
            const RenderResult part = renderPart(sample, GetParam(), 1, crop, aovs);
            EXPECT_EQ(part.window, crop);
            ASSERT_EQ(part.image.width, crop.width());
            ASSERT_EQ(part.image.height, crop.height());
            EXPECT_TRUE(sameBits(part.image.rgba, cut(whole.image.rgba, 32, crop, 4)));
            ASSERT_EQ(part.layers.size(), whole.layers.size());
            for (size_t i = 0; i < part.layers.size(); ++i)
                EXPECT_TRUE(sameBits(part.layers[i].pixels,
                                     cut(whole.layers[i].pixels, 32, crop, whole.layers[i].channels.size())))
                    << whole.layers[i].name;
            EXPECT_EQ(part.photonPasses, whole.photonPasses);
            EXPECT_EQ(part.photons, whole.photons);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, TileMethods, ::testing::ValuesIn(estimatorMethods()), methodParamName);

TEST(Tiles, CropOutsideTheFrameIsRefused) {
    RenderOptions options;
    options.crop = PixelRect{30, 0, 41, 30};
    const auto scene = buildScene(loadSceneFile(samplePath("cloud.json"), {"camera.resolution=[40,30]", "render.spp=1"}));
    expectErrorContaining<InputError>([&] { renderImage(*scene, options); }, {"40x30", "[30, 41)"});
}

}  // namespace
}  // namespace vdbmarch::test
