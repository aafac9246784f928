// The pipeline: scene -> photons -> cache -> marcher -> image.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/stats.h"
#include "parse/scene_desc.h"
#include "image/exr_io.h"
#include "image/image.h"
#include "illumination/illumination.h"
#include "scene/scene.h"
#include "strategies/strategy_set.h"

namespace vdbmarch {

struct RenderCheckpoint;

// Checkpoints (render --checkpoint, docs/farm.md): at sample boundaries the
// render hands its whole state to `save`, every `everySeconds` and when
// `stopRequested` says so (a signal); then, if a stop was requested, it
// returns with RenderResult::interrupted set. A render given `resume`
// continues from that state: its image is bit-identical to an
// uninterrupted one.
struct CheckpointHooks {
    double everySeconds = 300;
    std::function<void(const RenderCheckpoint&)> save;
    std::function<bool()> stopRequested;
    const RenderCheckpoint* resume = nullptr;
};

// A frame as the denoiser takes it, at a check of a timed render: the two
// half renders (RGBA), their emitted parts (empty without them) and the AOV
// layers (the features).
struct FrameHalves {
    Image even, odd, emittedEven, emittedOdd;
    std::vector<ExrLayer> aovs;
};

struct RenderOptions {
    bool progress = false;  // progress bar on stderr
    // > 0: render whole sweeps of one sample per pixel until this many
    // seconds (counted from runStart, so loading is included) are spent,
    // instead of render.spp samples.
    double timeBudget = 0;
    // Seconds of timeBudget kept back for the work after the render (the
    // denoiser): sweeps stop that much earlier.
    double reserveSeconds = 0;
    std::optional<std::chrono::steady_clock::time_point> runStart;
    IlluminationOptions illumination;  // a baked cache to load (render --cache)
    // Render only these pixels of the frame (render --tile / --crop). Every
    // pixel gets exactly the samples it gets in a whole-frame render, and
    // the photons and cache are those of the whole frame, so a tile is
    // bit-identical to its part of the whole render.
    std::optional<PixelRect> crop;
    // Render only the camera samples of photon passes [first, second)
    // (render --passes): the part of a progressive render one machine takes.
    // The result keeps each pass's sums (RenderResult::passSums) for merge.
    std::optional<std::pair<int, int>> photonPassRange;
    std::optional<CheckpointHooks> checkpoint;
    // Keep the two half renders in the result (the denoiser's input).
    bool keepHalves = false;
    // Where the render is denoised: the denoised image's estimated noise
    // variance per pixel of a frame (the window's pixels, row-major).
    // Adaptive sampling in a timed render then weighs each block's noise by
    // what the denoiser leaves of it (docs/noise.md, "Timed renders").
    std::function<std::vector<float>(const FrameHalves&)> denoisedVariance;
    // Also sum PathRadiance::emitted per pixel in halves (E, oddE), which the
    // denoiser takes apart from the scattered light (docs/denoise.md).
    bool keepEmitted = false;
    // The sampling strategies every path iterates (null: the scene's
    // defaults, StrategySet::build); tests plug their own in here.
    std::shared_ptr<const StrategySet> strategies;
};

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

// The noise of a render estimated from its two halves, without a
// reference: per pixel the variance of the mean is (m_even - m_odd)^2
// n_even n_odd / n^2, and rmse is its root mean over pixels and RGB, the
// figure `vdbmarch compare` prints against the truth (docs/noise.md).
struct NoiseEstimate {
    bool valid = false;  // at least 2 samples per pixel
    double rmse = 0;     // estimated RMSE of the RGB against the converged image
    double mean = 0;     // mean of the RGB
    double relative() const { return mean > 0 ? rmse / mean : 0.0; }
};
// `firstSample`: the index of the sums' first sample (a part by photon
// passes starts mid-render), which says which samples are the odd ones.
NoiseEstimate estimateNoise(const PixelSums& sums, int firstSample = 0);

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

// Everything a render has accumulated at a sample boundary (the photon pass
// it was at follows from nextSample): samples
// [firstSample, nextSample) of every pixel are in the sums.
struct RenderCheckpoint {
    int nextSample = 0;
    double seconds = 0;   // the run's time so far (counts in --time)
    RenderCounters counters;
    PixelSums sums{0};
    PhotonPassSums open;                    // the pass being rendered (pass -1: none)
    std::vector<PhotonPassSums> passSums;   // with RenderOptions::photonPassRange: the passes closed so far
    AovSums aovs;
};

struct RenderResult {
    Image image;          // the pixels of `window` (the whole frame unless cropped)
    PixelRect window;
    RenderCounters counters;
    double seconds = 0;   // photons, cache and rendering
    double illuminationSeconds = 0;  // photon tracing and cache (part of seconds)
    size_t photons = 0, cacheCells = 0;
    size_t photonBytes = 0, cacheBytes = 0;  // the photon maps and the cache held
    int threads = 0;      // worker threads used
    int spp = 0;          // samples per pixel actually rendered (the most any pixel got)
    double meanSpp = 0;   // averaged over the pixels (below spp with adaptive sampling)
    NoiseEstimate noise;  // of the beauty, from its two halves
    // Whether the render stopped because the noise target was met.
    bool reachedNoiseTarget = false;
    Image evenHalf, oddHalf;  // the two half renders (RenderOptions::keepHalves)
    Image emittedEven, emittedOdd;  // their emitted parts (keepHalves and keepEmitted)
    int photonPasses = 1; // progressive photon passes used (illumination/illumination.h)
    // The AOVs render.aovs asks for, as EXR layers (docs/aovs.md), in the
    // order depth, albedo, normal, direct, indirect.
    std::vector<ExrLayer> layers;
    std::vector<PhotonPassSums> passSums;  // with RenderOptions::photonPassRange: each pass rendered, in order
    int firstSample = 0;             // of the samples rendered (0 unless RenderOptions::photonPassRange)
    int totalPhotonPasses = 1;       // the passes of the whole render.spp
    // A checkpoint stop (CheckpointHooks::stopRequested): the state was
    // saved at sample `spp` and nothing else is valid.
    bool interrupted = false;
};

// Depth AOV of a pixel whose samples met nothing: far, but finite so that
// filters and defocus in a compositor stay finite (alpha says it is empty).
constexpr float NoDepth = 1e10f;

// Refuses (InputError naming camera.resolution) an image whose buffers do
// not fit in this machine's memory: per pixel the sums (PixelSums and the
// open pass's), the RGBA result, and the sums and layers of the AOVs and,
// with `emitted` (RenderOptions::keepEmitted), of the emitted part.
void checkImageMemory(int width, int height, const AovSet& aovs = {}, bool emitted = false);
// The scene emits light a camera ray can meet before any scattering: an
// emissive medium or a sphere light (RenderOptions::keepEmitted).
bool sceneEmitsLight(const SceneDesc& desc);
// The bytes checkImageMemory checks.
uint64_t imageMemoryBytes(int width, int height, const AovSet& aovs = {}, bool emitted = false);

// Tile `index` of `count` of a width x height frame: horizontal bands of
// whole rows (the unit an EXR scanline file stores), rows
// [floor(index h / count), floor((index + 1) h / count)). InputError when
// count is not in [1, height] or index not in [0, count).
PixelRect tileOfFrame(int index, int count, int width, int height);

// A timed render's last sample, when the time left buys only part of one:
// keeps about `share` of the blockSize x blockSize blocks that still sample
// (those with a pixel whose convergedAt is 0), taken in a fixed order spread
// over the frame, and stops the still-sampling pixels of the others at n
// samples (convergedAt = n). False, changing nothing, when it keeps none.
bool keepShareOfBlocks(std::vector<int>& convergedAt, int width, int height, int blockSize, double share, int n);

// Renders the scene with scene.desc.render's method, spp, seed and threads.
// Deterministic: each pixel sample has its own random stream, so the image is
// bit-identical for any thread count.
RenderResult renderImage(const Scene& scene, const RenderOptions& options = {});

}  // namespace vdbmarch
