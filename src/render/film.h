// The film: what a render sums per pixel (radiance and transmittance, their
// odd-index halves, the emitted part, the AOVs) and the images made from it.
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"
#include "image/exr_io.h"
#include "image/image.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

// An RGB sum in double: thousands of samples add up without the float
// rounding of each addition.
struct ColorSum {
    double r = 0, g = 0, b = 0;
    ColorSum() = default;
    explicit ColorSum(const Color& c) : r(c.x), g(c.y), b(c.z) {}
    void add(const Color& c) {
        r += double(c.x);
        g += double(c.y);
        b += double(c.z);
    }
    Color rounded() const { return Color(float(r), float(g), float(b)); }
};

// The sums of one photon pass's samples per pixel, radiance and
// transmittance, each summed in sample order from zero, in double; a pass is
// stored (in a part file) and folded as the float rounding of its sums.
struct PhotonPassSums {
    int pass = 0;
    int samples = 0;
    std::vector<ColorSum> L;
    std::vector<double> T;
    // The same sums over the odd-index samples only: with the totals they
    // give two independent half renders (the noise estimate, the denoiser).
    std::vector<ColorSum> oddL;
    std::vector<double> oddT;
    // With RenderOptions::keepEmitted: the sums of PathRadiance::emitted (the
    // emission seen before any scattering), all samples and odd ones; empty
    // otherwise.
    std::vector<ColorSum> E, oddE;
};

// A render's per-pixel totals. Samples are summed per photon pass and the
// passes folded in pass order, so a render split by passes across machines
// (render --passes, merge) adds the same numbers in the same order as one
// process, and the image is bit-identical.
struct PixelSums {
    std::vector<Color> L;
    std::vector<double> T;
    std::vector<Color> oddL;  // over the odd-index samples (PhotonPassSums::oddL)
    std::vector<double> oddT;
    std::vector<Color> E, oddE;  // PhotonPassSums::E, oddE folded (empty without them)
    int samples = 0;
    // Adaptive sampling (render.noise): the samples a pixel had when it
    // stopped receiving more; 0 while it still samples (or without it).
    std::vector<int> convergedAt;
    explicit PixelSums(size_t pixels) : L(pixels, Color(0)), T(pixels, 0.0), oddL(pixels, Color(0)), oddT(pixels, 0.0) {}
    void fold(const PhotonPassSums& pass);
    // These sums with `open`, the photon pass still being rendered (pass -1:
    // none), folded in: the frame as it would be if that pass closed now.
    PixelSums withOpen(const PhotonPassSums& open) const {
        PixelSums all = *this;
        if (open.pass >= 0) all.fold(open);
        return all;
    }
    // Samples in pixel p's sums.
    int samplesOf(size_t p) const { return convergedAt.empty() || convergedAt[p] == 0 ? samples : convergedAt[p]; }
    // RGB = L / samples, alpha = 1 - T / samples.
    Image average(int width, int height) const;
    // The means of the even-index and of the odd-index samples (RGBA), two
    // independent estimates of each pixel.
    Image evenHalf(int width, int height) const;
    Image oddHalf(int width, int height) const;
    // The same halves of the emitted part (RGB, alpha 1); empty images
    // without E.
    Image emittedHalf(int width, int height, bool odd) const;
};

// Samples of [first, first + n) with even and with odd index.
inline void halfCounts(int first, int n, int& even, int& odd) {
    odd = (first + n) / 2 - first / 2;
    even = n - odd;
}

// The AOVs' per-pixel sums (only those render.aovs asks for are allocated).
struct AovSums {
    std::vector<double> depth;           // camera-space depth of the samples that met something
    std::vector<uint32_t> depthSamples;  // how many did
    std::vector<Color> albedo, normal, direct;

    AovSums() = default;
    AovSums(const AovSet& aovs, size_t pixels);
    // Bytes per pixel of the sums and the layers written from them.
    static uint64_t bytesPerPixel(const AovSet& a);
};

// Depth AOV of a pixel whose samples met nothing: far, but finite so that
// filters and defocus in a compositor stay finite (alpha says it is empty).
constexpr float NoDepth = 1e10f;

// The layers of the requested AOVs from their sums over each pixel's samples
// (sums.samplesOf), in the order depth, albedo, normal, direct, indirect. The
// indirect layer is the beauty minus the direct one, so they add up to the
// beauty exactly up to the rounding of that subtraction.
std::vector<ExrLayer> aovLayers(const AovSet& aovs, const AovSums& s, const PixelSums& sums);

// Everything a render sums while it runs. A photon pass's sums are folded
// into the totals when the next pass opens and at the end; with
// `keepPasses` (RenderOptions::photonPassRange) each closed pass is also
// kept apart, in order.
struct Film {
    PixelSums sums{0};
    PhotonPassSums open;                   // the pass being rendered (pass -1: none)
    std::vector<PhotonPassSums> passSums;  // the passes closed so far, with keepPasses
    AovSums aovs;

    Film(size_t pixels, const AovSet& aovSet, bool keepEmitted, bool keepPasses);
    // Adds `samples` to photon pass `pass`, opening it (and closing the one
    // open) where it is not the open one.
    void openPhotonPass(int pass, int samples);
    void closePhotonPass();

private:
    size_t mPixels;
    bool mKeepEmitted, mKeepPasses;
};

// Refuses (InputError naming camera.resolution) an image whose buffers do
// not fit in this machine's memory: per pixel the sums (PixelSums and the
// open pass's), the RGBA result, and the sums and layers of the AOVs and,
// with `emitted` (RenderOptions::keepEmitted), of the emitted part.
void checkImageMemory(int width, int height, const AovSet& aovs = {}, bool emitted = false);
// The bytes checkImageMemory checks.
uint64_t imageMemoryBytes(int width, int height, const AovSet& aovs = {}, bool emitted = false);

}  // namespace vdbmarch
