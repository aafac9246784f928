// The denoiser (denoise/denoise.h) on a whole frame as the render command
// and merge hold it: the two half renders and the AOV layers that serve as
// its features, as EXR layers (docs/denoise.md, "In the EXR").
#pragma once

#include <vector>

#include "image/exr_io.h"
#include "image/image.h"

namespace vdbmarch {

// Names of the layers a denoised render writes: the noisy beauty and the
// means of its even- and odd-index samples (RGBA each).
inline constexpr const char* NoisyLayer = "noisy";
inline constexpr const char* EvenHalfLayer = "even";
inline constexpr const char* OddHalfLayer = "odd";
// The emitted part of each half (PathRadiance::emitted; RGB), where the
// render kept it: the denoiser filters the rest apart and adds it back.
inline constexpr const char* EmittedEvenLayer = "emitted_even";
inline constexpr const char* EmittedOddLayer = "emitted_odd";
// The four layers above: written with a denoised EXR, dropped from a
// preview-only one.
bool isDenoiserInput(const ExrLayer& l);

// An RGBA image as a layer named `name`.
ExrLayer rgbaLayer(const char* name, const Image& img);
// Its RGB only.
ExrLayer rgbLayer(const char* name, const Image& img);

// Appends the denoiser's input to `layers`: the halves (EvenHalfLayer,
// OddHalfLayer, their pixels moved in) and, where kept (not empty), their
// emitted parts.
void appendHalfLayers(std::vector<ExrLayer>& layers, Image&& even, Image&& odd, const Image& emittedEven,
                      const Image& emittedOdd);

// The denoised frame from the half layers (EvenHalfLayer, OddHalfLayer),
// their emitted parts (EmittedEvenLayer, EmittedOddLayer) and the albedo,
// normal and depth AOV layers among `layers` when present;
// channels are found by name, in any order. InputError when a half is
// missing.
// With `variances`, also the denoised image's estimated noise variance per
// pixel (denoise()).
Image denoiseFrame(int width, int height, const std::vector<ExrLayer>& layers, int threads,
                   std::vector<float>* variances = nullptr);

// What a frame's denoiser input holds besides the halves.
struct DenoiseShape {
    bool emitted = false;  // the emitted parts (EmittedEvenLayer, EmittedOddLayer)
    bool albedo = false, normal = false, depth = false;  // AOV features
};

// The seconds denoiseFrame is expected to take on a width x height frame of
// that shape with `threads` threads (0: all cores): a small synthetic frame
// of the same shape, as many 64-pixel tiles as threads, denoised here and
// now, its time scaled by the pixel count. What a timed render keeps back
// from its budget for the denoiser.
double predictDenoiseSeconds(int width, int height, const DenoiseShape& shape, int threads);

}  // namespace vdbmarch
