// The pipeline: scene -> photons -> cache -> marcher -> image. What it sums
// is in film.h, the noise estimate in noise_estimate.h, adaptive sampling in
// adaptive_sampling.h and checkpoints in checkpoint.h.
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
#include "render/checkpoint.h"
#include "render/film.h"
#include "render/noise_estimate.h"
#include "scene/scene.h"
#include "strategies/strategy_set.h"

namespace vdbmarch {

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

// The scene emits light a camera ray can meet before any scattering: an
// emissive medium or an area light (RenderOptions::keepEmitted).
bool sceneEmitsLight(const SceneDesc& desc);

// Tile `index` of `count` of a width x height frame: horizontal bands of
// whole rows (the unit an EXR scanline file stores), rows
// [floor(index h / count), floor((index + 1) h / count)). InputError when
// count is not in [1, height] or index not in [0, count).
PixelRect tileOfFrame(int index, int count, int width, int height);

// Renders the scene with scene.desc.render's method, spp, seed and threads.
// Deterministic: each pixel sample has its own random stream, so the image is
// bit-identical for any thread count.
RenderResult renderImage(const Scene& scene, const RenderOptions& options = {});

}  // namespace vdbmarch
