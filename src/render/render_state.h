// One renderImage call while it runs, private to src/render: its set-up,
// sweeps, photon passes, checkpoints and result are in render.cpp, the
// schedules that split its samples into sweeps in sample_schedule.cpp.
#pragma once

#include <chrono>
#include <memory>
#include <vector>

#include <tbb/task_arena.h>

#include "estimators/estimator.h"
#include "paths/first_event.h"
#include "render/adaptive_sampling.h"
#include "render/progress_bar.h"
#include "render/render.h"

namespace vdbmarch {

// Threads take the image in work blocks of WorkBlockSize^2 pixels (not the
// farm's tiles, app/tiles.h, nor adaptive sampling's blocks).
constexpr int WorkBlockSize = 16;

// What a render takes, decided (and refused, with InputError) before any
// buffer is allocated: the window, the photon passes and the samples.
struct RenderPlan {
    RenderPlan(const Scene& scene, const RenderOptions& options);

    const Scene& scene;
    const RenderOptions& options;
    const RenderSettings& rs;
    const AovSet& aovs;
    const int w, h;  // the frame
    // The pixels rendered: buffers hold the window's pixels; random streams
    // are keyed by the pixel's index in the whole frame.
    const PixelRect window;
    const int ww, wh;
    const size_t pixels;
    const bool timed;  // RenderOptions::timeBudget
    // Adaptive sampling: towards the noise target (render.noise), or in a
    // timed render by each block's noise and measured time (experiments.adaptive).
    const bool timedAdaptive, adaptive;
    const CheckpointHooks* const hooks;  // null: no checkpoints
    // What the photon passes are (nothing is traced yet).
    const IlluminationRequest request;
    const PhotonPasses photonPasses;
    const int totalPasses;  // the photon passes of the whole render.spp
    // The samples [first, last) this render takes: those of the photon
    // passes asked for (RenderOptions::photonPassRange), else all.
    int first = 0, last = 0;
};

// The running state: the film, the photons and marcher, the clocks and
// counters, and the result as it fills in.
struct RenderState : RenderPlan {
    RenderState(const Scene& scene, const RenderOptions& options);

    // The marcher and what it reads: the sampling strategies, the photons
    // and the cache.
    void buildMarcher();
    // Takes over the state of a checkpoint (CheckpointHooks::resume).
    void resume(const RenderCheckpoint& c);

    // The schedules (sample_schedule.cpp): how samples [first, last), or
    // as many as the time budget buys, are split into sweeps. The sums do
    // not depend on the split.
    void renderAllSamples();
    void renderInChunks();  // checkpoints and noise checks between chunks
    void renderTimed();     // RenderOptions::timeBudget

    // Samples [s0, s1) of every still-sampling pixel, photon pass by pass.
    void renderSamples(int s0, int s1);
    // At a sample boundary (`next` samples done): saves a checkpoint when
    // one is due or a stop was asked for; true: stop.
    bool checkpointAt(int next);
    // The noise target (render.noise) at a check after n samples; true: met.
    bool checkNoise(int n);
    // The counters so far, those of a resumed render's first runs included.
    RenderCounters counters() const;
    // The result: the image and layers from the sums (only the counters and
    // the sample count where a checkpoint stop interrupted the render).
    RenderResult finish();

    const int workBlocksX, workBlocks;
    RenderResult result;
    Film film;
    PixelTimes times;  // with timedAdaptive
    std::vector<RenderCounters> workBlockCounters;
    ProgressBar progress;
    const int threads;
    // When this call started, and when the run did: RenderOptions::runStart
    // (loading counts in a time budget), moved back by a resumed render's time.
    const std::chrono::steady_clock::time_point start;
    std::chrono::steady_clock::time_point runStart;
    tbb::task_arena arena;
    // The sampling strategies and their tables, once per render.
    std::shared_ptr<const StrategySet> strategies;
    std::shared_ptr<Illumination> illumination;
    std::unique_ptr<Estimator> marcher;
    std::unique_ptr<FirstEventTracer> firstEvents;  // the feature AOVs' paths (null: none asked)
    double firstIlluminationSeconds = 0;  // what the first photons and cache took
    // A resumed render's sample, counters and time before this run.
    int resumeSample = 0;
    RenderCounters resumedCounters;
    double resumedSeconds = 0;
    std::chrono::steady_clock::time_point lastCheckpoint;
    bool reachedTarget = false;  // the noise target was met
    int spp = 0;                 // samples rendered from `first` on (RenderResult::spp)

private:
    void renderSweep(int s0, int s1);
};

}  // namespace vdbmarch
