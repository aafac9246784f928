// How a render's samples are split into sweeps: all at once, in chunks
// between checkpoints and noise checks, or in timed sweeps while the budget
// lasts. Every pixel sums its samples in index order, so the sums never
// depend on the split, only on how many samples each pixel gets.
#include <algorithm>
#include <chrono>
#include <vector>

#include "render/render_state.h"

namespace vdbmarch {

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0, std::chrono::steady_clock::time_point t1) {
    return std::chrono::duration<double>(t1 - t0).count();
}

// A timed render (RenderOptions::timeBudget): sweeps of whole samples per
// pixel while the next sample is expected to finish within the budget
// (which also covers loading, measured from runStart, less what is kept
// back for the denoiser); always at least one sweep, and two samples where
// the halves are kept. The first sweep is one sample; later ones as many as
// fill about TimedSweepSeconds and fit in the time left (a sweep sets up a
// thread context per work block: BENCHMARKS.md, "Timed renders in sweeps of
// a tenth of a second"), ending at noise checks and photon passes. A sample
// that starts a photon pass is expected to take as long as the first
// photons did.
class TimedSweeps {
public:
    explicit TimedSweeps(RenderState& r)
        : r(r), budget(r.options.timeBudget - std::max(r.options.reserveSeconds, 0.0)) {}
    void run();

private:
    static constexpr double TimedSweepSeconds = 0.1;
    static constexpr int MaxTimedSweep = 64;
    // Where the frame is denoised, the denoiser's gain per block is measured
    // again at a check while a denoise costs at most this share of the time
    // left.
    static constexpr double DenoiseCheckShare = 0.02;

    // The samples of a sweep starting at `p0`, once a sample was timed.
    int sweepLength(std::chrono::steady_clock::time_point p0) const;
    // The photon tracing expected before `sample` can be rendered.
    double photonsBeforeSample(int sample) const;
    // Adaptive sampling at a noise check (timedAdaptiveStep), `elapsed`
    // seconds into the run (a denoise for the gains adds to them); true
    // when every pixel stopped.
    bool adaptiveStep(double& elapsed);
    void measureDenoiserGains(double& elapsed);
    // The time left buys part of one more sample (after its photon pass,
    // where it starts one): the pixels of a share of the still-sampling work
    // blocks take it, the others stop where they are (docs/noise.md, "The
    // last sample").
    void renderPartOfLastSample(double elapsed, double photonsNext);

    RenderState& r;
    const double budget;
    double perSample = 0;            // the camera part of one sample per pixel, last measured
    double cameraSeconds = 0;        // the sweeps' camera time so far (wall)
    std::vector<double> gains;       // the denoiser's per block, last measured
    double lastDenoiseSeconds = -1;  // none yet
};

void TimedSweeps::run() {
    int& spp = r.spp;
    do {
        if (r.checkpointAt(r.first + spp)) {
            r.result.interrupted = true;
            break;
        }
        const auto p0 = std::chrono::steady_clock::now();
        const int n = perSample > 0 ? sweepLength(p0) : 1;
        const double photonsBefore = r.illumination->stats.seconds;
        r.renderSamples(spp, spp + n);
        spp += n;
        const auto now = std::chrono::steady_clock::now();
        // The camera part of the sweep (photons are predicted apart).
        const double camera = secondsSince(p0, now) - (r.illumination->stats.seconds - photonsBefore);
        perSample = camera / double(n);
        cameraSeconds += camera;
        double elapsed = secondsSince(r.runStart, now);
        r.progress.set(elapsed / budget);
        if (r.checkNoise(spp)) break;
        if (r.timedAdaptive && isNoiseCheck(spp) && adaptiveStep(elapsed)) break;
        // At least two samples where the halves are kept: the denoiser
        // needs both (a one-sample render is written noisy).
        const int fewest = r.options.keepHalves ? 2 : 1;
        const double photonsNext = photonsBeforeSample(spp);
        if (r.first + spp >= fewest && elapsed + 1.05 * perSample + photonsNext > budget * 0.98) {
            if (r.timedAdaptive && !r.options.photonPassRange) renderPartOfLastSample(elapsed, photonsNext);
            break;
        }
    } while (spp < (1 << 24));
    r.progress.set(1.0);
}

int TimedSweeps::sweepLength(std::chrono::steady_clock::time_point p0) const {
    const int spp = r.spp;
    const double room = budget * 0.98 - secondsSince(r.runStart, p0) - photonsBeforeSample(spp);
    // A checkpoint is due at a sweep's end every hooks->everySeconds.
    const double sweep = std::min(TimedSweepSeconds, r.hooks ? r.hooks->everySeconds : TimedSweepSeconds);
    int n = int(std::clamp(std::min(sweep, room / 1.05) / perSample, 1.0, double(MaxTimedSweep)));
    if (r.adaptive) n = std::min(n, nextNoiseCheck(spp) - spp);
    if (r.photonPasses.progressive())
        n = std::min(n, r.photonPasses.firstSampleOf(r.photonPasses.passOf(spp) + 1) - spp);
    return std::max(n, 1);
}

double TimedSweeps::photonsBeforeSample(int sample) const {
    const int pass = r.photonPasses.passOf(sample);
    return pass != r.illumination->photonPass && r.photonPasses.needsWork(pass) ? r.firstIlluminationSeconds : 0.0;
}

bool TimedSweeps::adaptiveStep(double& elapsed) {
    // The time left in the pixels' seconds: wall time times the threads'
    // measured pixel seconds per wall second.
    double pixelSeconds = 0;
    for (double t : r.times.seconds) pixelSeconds += t;
    measureDenoiserGains(elapsed);
    const double left = (budget * 0.98 - elapsed) * (cameraSeconds > 0 ? pixelSeconds / cameraSeconds : 0.0);
    return timedAdaptiveStep(r.film.sums, r.film.open, r.times, gains, r.ww, r.wh, r.spp, left);
}

void TimedSweeps::measureDenoiserGains(double& elapsed) {
    // The first denoise is expected to take what the render keeps back for
    // the final one.
    const double expected = lastDenoiseSeconds >= 0 ? lastDenoiseSeconds : r.options.reserveSeconds;
    if (r.options.denoisedVariance && expected <= DenoiseCheckShare * (budget * 0.98 - elapsed)) {
        const auto d0 = std::chrono::steady_clock::now();
        const PixelSums frame = r.film.sums.withOpen(r.film.open);
        const int ww = r.ww, wh = r.wh;
        FrameHalves halves{frame.evenHalf(ww, wh), frame.oddHalf(ww, wh), frame.emittedHalf(ww, wh, false),
                           frame.emittedHalf(ww, wh, true), aovLayers(r.aovs, r.film.aovs, frame)};
        const std::vector<float> denoised = r.options.denoisedVariance(halves);
        if (denoised.size() == r.pixels) gains = denoiserGains(frame, denoised, ww, wh);
        lastDenoiseSeconds = secondsSince(d0, std::chrono::steady_clock::now());
        elapsed += lastDenoiseSeconds;
    }
}

void TimedSweeps::renderPartOfLastSample(double elapsed, double photonsNext) {
    const double share = (budget * 0.98 - elapsed - photonsNext) / (1.05 * perSample);
    if (share > 0.05 && keepShareOfBlocks(r.film.sums.convergedAt, r.ww, r.wh, WorkBlockSize, share, r.spp)) {
        r.renderSamples(r.spp, r.spp + 1);
        ++r.spp;
    }
}

}  // namespace

void RenderState::renderAllSamples() {
    renderSamples(first, last);
    spp = last - first;
}

// In chunks of whole samples per pixel, about a second each so that a stop
// is acted on soon, and ending at every noise check.
void RenderState::renderInChunks() {
    int s = resumeSample, chunk = hooks ? 1 : last;
    while (s < last) {
        if (checkpointAt(s)) {
            result.interrupted = true;
            break;
        }
        const auto c0 = std::chrono::steady_clock::now();
        const int e = std::min({last, s + chunk, adaptive ? nextNoiseCheck(s) : last});
        renderSamples(s, e);
        const double perSample = secondsSince(c0, std::chrono::steady_clock::now()) / double(e - s);
        if (hooks)
            chunk = int(std::clamp(std::min(1.0, hooks->everySeconds) / std::max(perSample, 1e-6), 1.0, 4096.0));
        s = e;
        progress.set(double(s - first) / double(last - first));
        if (checkNoise(s)) break;
    }
    spp = s - first;
}

void RenderState::renderTimed() {
    spp = resumeSample - first;
    TimedSweeps(*this).run();
}

}  // namespace vdbmarch
