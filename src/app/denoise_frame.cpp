#include "app/denoise_frame.h"

#include <algorithm>

#include "core/error.h"
#include "denoise/denoise.h"

namespace vdbmarch {

namespace {

const ExrLayer* findLayer(const std::vector<ExrLayer>& layers, const char* name) {
    for (const ExrLayer& l : layers)
        if (l.name == name) return &l;
    return nullptr;
}

// Channel `c` of every pixel of a layer (the file stores channels in name order).
std::vector<float> channel(const ExrLayer& l, const char* c, size_t pixels) {
    const auto it = std::find(l.channels.begin(), l.channels.end(), c);
    if (it == l.channels.end()) throw InputError(str("layer '", l.name, "' has no channel ", c));
    const size_t k = size_t(it - l.channels.begin()), n = l.channels.size();
    std::vector<float> out(pixels);
    for (size_t p = 0; p < pixels; ++p) out[p] = l.pixels[p * n + k];
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

bool isDenoiserInput(const ExrLayer& l) {
    return l.name == EvenHalfLayer || l.name == OddHalfLayer || l.name == EmittedEvenLayer || l.name == EmittedOddLayer;
}

Image denoiseFrame(int width, int height, const std::vector<ExrLayer>& layers, int threads) {
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
    return denoise(in, options);
}

}  // namespace vdbmarch
