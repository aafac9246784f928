#include "app/denoise_frame.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.h"
#include "core/rng.h"
#include "core/threads.h"
#include "denoise/denoise.h"

namespace vdbmarch {

namespace {

// Channel `c` of every pixel of a layer; InputError when it has none.
std::vector<float> channel(const ExrLayer& l, const char* c, size_t pixels) {
    std::vector<float> out = layerChannel(l, c, pixels);
    if (out.empty() && pixels > 0) throw InputError(str("layer '", l.name, "' has no channel ", c));
    return out;
}

std::vector<Color> colors(const ExrLayer& l, const char* c0, const char* c1, const char* c2, size_t pixels) {
    const std::vector<float> a = channel(l, c0, pixels), b = channel(l, c1, pixels), c = channel(l, c2, pixels);
    std::vector<Color> out(pixels);
    for (size_t p = 0; p < pixels; ++p) out[p] = Color(a[p], b[p], c[p]);
    return out;
}

}  // namespace

ExrLayer rgbaLayer(const char* name, const Image& img) { return {name, {"R", "G", "B", "A"}, img.rgba}; }

ExrLayer rgbLayer(const char* name, const Image& img) {
    ExrLayer l{name, {"R", "G", "B"}, {}};
    l.pixels.reserve(img.pixelCount() * 3);
    for (size_t p = 0; p < img.pixelCount(); ++p)
        l.pixels.insert(l.pixels.end(), {img.rgba[4 * p], img.rgba[4 * p + 1], img.rgba[4 * p + 2]});
    return l;
}

void appendHalfLayers(std::vector<ExrLayer>& layers, Image&& even, Image&& odd, const Image& emittedEven,
                      const Image& emittedOdd) {
    layers.push_back({EvenHalfLayer, {"R", "G", "B", "A"}, std::move(even.rgba)});
    layers.push_back({OddHalfLayer, {"R", "G", "B", "A"}, std::move(odd.rgba)});
    if (emittedEven.empty()) return;
    layers.push_back(rgbLayer(EmittedEvenLayer, emittedEven));
    layers.push_back(rgbLayer(EmittedOddLayer, emittedOdd));
}

bool isDenoiserInput(const ExrLayer& l) {
    return l.name == EvenHalfLayer || l.name == OddHalfLayer || l.name == EmittedEvenLayer || l.name == EmittedOddLayer;
}

Image denoiseFrame(int width, int height, const std::vector<ExrLayer>& layers, int threads, std::vector<float>* variances) {
    const size_t pixels = size_t(width) * size_t(height);
    const ExrLayer* even = findLayer(layers, EvenHalfLayer);
    const ExrLayer* odd = findLayer(layers, OddHalfLayer);
    if (!even || !odd) throw InputError("denoising needs the layers 'even' and 'odd' (the two half renders)");
    DenoiseInput in;
    in.width = width;
    in.height = height;
    in.halfA = colors(*even, "R", "G", "B", pixels);
    in.halfB = colors(*odd, "R", "G", "B", pixels);
    in.alphaA = channel(*even, "A", pixels);
    in.alphaB = channel(*odd, "A", pixels);
    const ExrLayer* emittedEven = findLayer(layers, EmittedEvenLayer);
    const ExrLayer* emittedOdd = findLayer(layers, EmittedOddLayer);
    if (emittedEven && emittedOdd) {
        in.emittedA = colors(*emittedEven, "R", "G", "B", pixels);
        in.emittedB = colors(*emittedOdd, "R", "G", "B", pixels);
    }
    if (const ExrLayer* l = findLayer(layers, "albedo")) in.albedo = colors(*l, "R", "G", "B", pixels);
    if (const ExrLayer* l = findLayer(layers, "normal")) in.normal = colors(*l, "X", "Y", "Z", pixels);
    if (const ExrLayer* l = findLayer(layers, "depth")) in.depth = channel(*l, "Z", pixels);
    DenoiseOptions options;
    options.threads = threads;
    return denoise(in, options, variances);
}

double predictDenoiseSeconds(int width, int height, const DenoiseShape& shape, int threads) {
    if (width <= 0 || height <= 0) return 0;
    // The denoiser works in tiles of 64 x 64 pixels, one thread per tile; a
    // frame of as many tiles as threads (or the whole frame, if smaller)
    // keeps every thread busy, as the frame itself will.
    constexpr int Tile = 64;
    const long tilesX = (width + Tile - 1) / Tile, tilesY = (height + Tile - 1) / Tile;
    const long tiles = std::max(1L, std::min(tilesX * tilesY, long(resolveThreadCount(threads))));
    const int w = int(std::min(long(width), Tile * tiles));
    const long columns = (w + Tile - 1) / Tile;
    const int h = int(std::min(long(height), Tile * ((tiles + columns - 1) / columns)));
    // A smooth image with independent noise in each half, so that every
    // stage runs as on a render's: the emitted part noisy enough to be
    // filtered apart (the costlier case).
    const size_t n = size_t(w) * size_t(h);
    Rng rng(1);
    auto noise = [&] { return rng.uniform() - 0.5f; };
    DenoiseInput in;
    in.width = w;
    in.height = h;
    for (size_t p = 0; p < n; ++p) {
        const float x = float(p % size_t(w)), y = float(p / size_t(w));
        const float v = 0.5f + 0.3f * std::sin(x / 7) * std::cos(y / 5);
        in.halfA.push_back(Color(v + 0.2f * noise(), v + 0.2f * noise(), v + 0.2f * noise()));
        in.halfB.push_back(Color(v + 0.2f * noise(), v + 0.2f * noise(), v + 0.2f * noise()));
        in.alphaA.push_back(0.8f + 0.1f * noise());
        in.alphaB.push_back(0.8f + 0.1f * noise());
        if (shape.emitted) {
            in.emittedA.push_back(Color(0.2f * v + 0.1f * noise()));
            in.emittedB.push_back(Color(0.2f * v + 0.1f * noise()));
        }
        if (shape.albedo) in.albedo.push_back(Color(0.9f + 0.1f * noise()));
        if (shape.normal) in.normal.push_back(Color(0.f, 0.5f + noise(), 1.f));
        if (shape.depth) in.depth.push_back(3 + v + noise());
    }
    DenoiseOptions options;
    options.threads = threads;
    const auto t0 = std::chrono::steady_clock::now();
    denoise(in, options);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return seconds * (double(width) * double(height)) / double(n);
}

}  // namespace vdbmarch
