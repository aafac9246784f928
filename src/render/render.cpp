#include "render/render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/memory.h"
#include "core/rng.h"
#include "core/sobol.h"
#include "core/threads.h"
#include "render/render_state.h"

namespace vdbmarch {

namespace {

// Random stream of the feature AOVs, apart from the beauty's.
constexpr uint64_t AovStream = 0x616f7673;
// The pixel positions' sequences (one per half render: PixelStream + 0, + 1).
constexpr uint64_t PixelStream = 0x70697870;

// The pixels to render: the crop, else the frame. InputError when the crop
// is empty or not inside the frame, or the window's buffers do not fit in
// memory (checkImageMemory).
PixelRect renderWindow(const Scene& scene, const RenderOptions& options) {
    const int w = scene.camera->width(), h = scene.camera->height();
    const PixelRect frame{0, 0, w, h};
    const PixelRect window = options.crop ? *options.crop : frame;
    if (window.empty() || !frame.contains(window))
        throw InputError(str("crop [", window.x0, ", ", window.x1, ") x [", window.y0, ", ", window.y1,
                             ") is empty or not inside the ", w, "x", h, " frame"));
    checkImageMemory(window.width(), window.height(), scene.desc.render.aovs, options.keepEmitted);
    return window;
}

// The samples [first, last) of the photon passes `passes` = [a, b) asked for
// (render --passes), refused where a render cannot be split by passes.
std::pair<int, int> samplesOfPasses(const Scene& scene, const PhotonPasses& photonPasses, std::pair<int, int> passes,
                                    bool timed, int totalPasses, int ww, int wh) {
    const RenderSettings& rs = scene.desc.render;
    const AovSet& aovs = rs.aovs;
    const size_t pixels = size_t(ww) * size_t(wh);
    const auto [a, b] = passes;
    if (timed) throw InputError("--passes and --time: a part of a render by passes renders fixed samples");
    if (rs.noise > 0)
        throw InputError(str("--passes and render.noise = ", rs.noise, ": a part of a render by passes renders "
                             "fixed samples; split a render to a noise target by tiles instead"));
    if (aovs.any())
        throw InputError(str("--passes ", a, "-", b, " and render.aovs: AOVs are not split by passes; split the "
                             "render by tiles instead"));
    if (!photonPasses.progressive())
        throw InputError(str("--passes ", a, "-", b, ": this render has no progressive photon passes (method ",
                             methodName(rs.method), "): split it by tiles instead"));
    if (a < 0 || b <= a || b > totalPasses)
        throw InputError(str("--passes ", a, "-", b, ": this render has passes 0 to ", totalPasses - 1, " (",
                             rs.spp, " spp, ", photonPasses.samplesPerPass(), " per pass); the range is FIRST-END "
                             "with END excluded, at most ", totalPasses));
    // Each pass's sums are kept until written (one EXR layer per pass).
    checkMemory(uint64_t(b - a) * uint64_t(pixels) * (sizeof(ColorSum) + sizeof(double) + 4 * sizeof(float)),
                str("--passes ", a, "-", b, ": the sums of ", b - a, " passes of ", ww, "x", wh, " pixels"));
    return {photonPasses.firstSampleOf(a), std::min(rs.spp, photonPasses.firstSampleOf(b))};
}

// Camera sample s of pixel (x, y) (`pixel` its index in the frame, `local`
// in the window's buffers): its radiance into the open pass's sums and its
// odd half, and with AOVs the direct part and the first event's features. A
// non-finite sample is dropped and counted, never written.
void addCameraSample(const Scene& scene, const Estimator& marcher, const FirstEventTracer* firstEvents,
                     ThreadContext& ctx, int x, int y, uint64_t pixel, int s, size_t local, PhotonPassSums& open,
                     AovSums& aovSums) {
    const RenderSettings& rs = scene.desc.render;
    const AovSet& aovs = rs.aovs;
    Rng rng(hashValues(rs.seed, pixel), uint64_t(s));
    float jx = 0.5f, jy = 0.5f;
    // Each half render (even and odd samples) takes its pixel positions from
    // its own scrambled Sobol sequence: stratified within the half, and the
    // halves independent, as the noise estimate and the denoiser need.
    if (rs.pixelJitter) sobolPoint2D(uint32_t(s >> 1), hashValues(rs.seed, pixel, PixelStream + uint64_t(s & 1)), jx, jy);
    const Ray ray = scene.camera->generateRay(float(x) + jx, float(y) + jy);
    const PathRadiance pr = marcher.radiance(ray, rng, ctx);
    if (!isFinite(pr.L) || !std::isfinite(pr.transmittance)) {
        ++ctx.counters.nonFiniteSamples;
        return;
    }
    open.L[local].add(pr.L);
    open.T[local] += pr.transmittance;
    if (s & 1) {
        open.oddL[local].add(pr.L);
        open.oddT[local] += pr.transmittance;
    }
    if (!open.E.empty()) {
        open.E[local].add(pr.emitted);
        if (s & 1) open.oddE[local].add(pr.emitted);
    }
    if (!aovs.any()) return;
    if (aovs.splitDirect()) aovSums.direct[local] += pr.direct;
    if (firstEvents) {
        Rng aovRng(hashValues(rs.seed, pixel, AovStream), uint64_t(s));
        const FirstEvent fe = firstEvents->trace(ctx, ray, aovRng);
        if (aovs.depth && fe.hasDepth) {
            aovSums.depth[local] += double(scene.camera->viewDepth(fe.depthPoint));
            ++aovSums.depthSamples[local];
        }
        if (aovs.albedo) aovSums.albedo[local] += fe.albedo;
        if (aovs.normal) aovSums.normal[local] += fe.normal;
    }
}

}  // namespace

PixelRect tileOfFrame(int index, int count, int width, int height) {
    if (count < 1 || count > height)
        throw InputError(str("--tile ", index, "/", count, ": the frame is split into horizontal bands of rows, so the "
                             "tile count must be 1 to the image height (", height, ")"));
    if (index < 0 || index >= count)
        throw InputError(str("--tile ", index, "/", count, ": the tile index must be 0 to ", count - 1));
    auto row = [&](int i) { return int(int64_t(i) * height / count); };
    return {0, row(index), width, row(index + 1)};
}

bool sceneEmitsLight(const SceneDesc& desc) {
    for (const MediumDesc& m : desc.media)
        if (m.hasEmission) return true;
    for (const LightDesc& l : desc.lights)
        if (!makeLight(l)->isDelta()) return true;  // an area light
    return false;
}

RenderPlan::RenderPlan(const Scene& scene, const RenderOptions& options)
    : scene(scene), options(options), rs(scene.desc.render), aovs(rs.aovs), w(scene.camera->width()),
      h(scene.camera->height()), window(renderWindow(scene, options)), ww(window.width()), wh(window.height()),
      pixels(size_t(ww) * size_t(wh)), timed(options.timeBudget > 0),
      timedAdaptive(timed && scene.desc.experiments.adaptive && rs.noise <= 0), adaptive(rs.noise > 0 || timedAdaptive),
      hooks(options.checkpoint ? &*options.checkpoint : nullptr),
      request(illuminationRequest(scene, rs.method, options.illumination)), photonPasses(scene, request, w * h),
      totalPasses(photonPasses.passOf(std::max(0, rs.spp - 1)) + 1), last(rs.spp) {
    if (options.photonPassRange)
        std::tie(first, last) = samplesOfPasses(scene, photonPasses, *options.photonPassRange, timed, totalPasses, ww, wh);
}

RenderState::RenderState(const Scene& scene, const RenderOptions& options)
    : RenderPlan(scene, options), workBlocksX((ww + WorkBlockSize - 1) / WorkBlockSize),
      workBlocks(workBlocksX * ((wh + WorkBlockSize - 1) / WorkBlockSize)),
      film(pixels, aovs, options.keepEmitted, bool(options.photonPassRange)),
      workBlockCounters(static_cast<size_t>(workBlocks)),
      progress(options.progress, timed || options.checkpoint || rs.noise > 0 ? 1000 : workBlocks),
      threads(resolveThreadCount(rs.threads)), start(std::chrono::steady_clock::now()),
      runStart(options.runStart ? *options.runStart : start), arena(threads) {
    result.window = window;
    result.totalPhotonPasses = timed ? 0 : totalPasses;
    result.firstSample = first;
    result.threads = threads;
    if (adaptive) film.sums.convergedAt.assign(pixels, 0);
    if (timedAdaptive) {
        times.seconds.assign(pixels, 0.0);
        times.samples.assign(pixels, 0);
    }
    resumeSample = first;
}

void RenderState::buildMarcher() {
    strategies = options.strategies ? options.strategies : StrategySet::build(scene);
    if (aovs.firstEvent()) firstEvents = std::make_unique<FirstEventTracer>(scene);
    // A resume in this process takes over the photons and cache it stopped
    // with, if they are still at the pass of its last sample.
    const RenderCheckpoint* from = hooks ? hooks->resume : nullptr;
    const bool carried = from && from->illumination && from->nextSample > first &&
                         from->illumination->photonPass == photonPasses.passOf(from->nextSample - 1);
    arena.execute([&] {
        illumination = carried ? from->illumination
                               : std::make_shared<Illumination>(buildIllumination(scene, request));
        marcher = makeEstimator(rs.method, scene, illumination, strategies);
    });
    firstIlluminationSeconds = carried ? from->setupSeconds : illumination->stats.seconds;
    result.cacheCells = illumination->cache ? illumination->cache->cells.size() : 0;
    result.photonBytes = illumination->stats.photonBytes;
    result.cacheBytes = illumination->stats.cacheBytes;
}

// A resumed render takes the checkpoint's sums, counters and time; the
// photon passes are replayed from their seeds when the next sample needs
// them (PhotonPasses::advance), so the illumination is the same too.
void RenderState::resume(const RenderCheckpoint& c) {
    if (c.sums.L.size() != pixels || c.nextSample < first || (!timed && c.nextSample > last))
        throw std::logic_error("renderImage: the checkpoint does not belong to this render");
    resumeFilm(c, film);
    if (adaptive && film.sums.convergedAt.size() != pixels) film.sums.convergedAt.assign(pixels, 0);
    resumedCounters = c.counters;
    resumeSample = c.nextSample;
    resumedSeconds = c.seconds;
    runStart -= std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(resumedSeconds));
}

// One sweep renders samples [s0, s1) of every pixel. Each pixel sums its
// samples in index order, so the image depends only on the final sample
// count, never on how samples were split into sweeps or threads.
void RenderState::renderSweep(int s0, int s1) {
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, workBlocks, 1), [&](const tbb::blocked_range<int>& range) {
            for (int workBlock = range.begin(); workBlock != range.end(); ++workBlock) {
                ThreadContext ctx(scene);
                const int x0 = window.x0 + (workBlock % workBlocksX) * WorkBlockSize;
                const int y0 = window.y0 + (workBlock / workBlocksX) * WorkBlockSize;
                for (int y = y0; y < std::min(y0 + WorkBlockSize, window.y1); ++y)
                    for (int x = x0; x < std::min(x0 + WorkBlockSize, window.x1); ++x) {
                        const uint64_t pixel = uint64_t(y) * uint64_t(w) + uint64_t(x);  // in the frame
                        const size_t local = size_t(y - window.y0) * size_t(ww) + size_t(x - window.x0);
                        if (adaptive && film.sums.convergedAt[local] > 0) continue;  // stopped sampling
                        const auto t0 = timedAdaptive ? std::chrono::steady_clock::now()
                                                      : std::chrono::steady_clock::time_point();
                        for (int s = s0; s < s1; ++s)
                            addCameraSample(scene, *marcher, firstEvents.get(), ctx, x, y, pixel, s, local, film.open,
                                            film.aovs);
                        if (timedAdaptive) {
                            times.seconds[local] +=
                                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                            times.samples[local] += s1 - s0;
                        }
                    }
                workBlockCounters[size_t(workBlock)] += ctx.counters;
                if (!timed && !hooks && !adaptive) progress.tick();
            }
        }, tbb::simple_partitioner());
    });
}

// Pass by pass of photons: the marcher reads the pass's map and radius
// through `illumination`, and is made again only when the cache was refined
// (eq. 17's scale is measured from the cache).
void RenderState::renderSamples(int s0, int s1) {
    for (int s = s0; s < s1;) {
        const int pass = photonPasses.passOf(s);
        if (pass != illumination->photonPass) {
            arena.execute([&] {
                if (photonPasses.advance(scene, pass, *illumination))
                    marcher = makeEstimator(rs.method, scene, illumination, strategies);
            });
        }
        const int end = std::min(s1, photonPasses.progressive() ? photonPasses.firstSampleOf(pass + 1) : s1);
        film.openPhotonPass(pass, end - s);
        renderSweep(s, end);
        s = end;
    }
}

RenderCounters RenderState::counters() const {
    RenderCounters total = resumedCounters;
    for (const auto& t : workBlockCounters) total += t;
    return total;
}

bool RenderState::checkpointAt(int next) {
    if (!hooks) return false;
    const bool stop = hooks->stopRequested && hooks->stopRequested();
    const auto now = std::chrono::steady_clock::now();
    if (!stop && std::chrono::duration<double>(now - lastCheckpoint).count() < hooks->everySeconds) return false;
    RenderCheckpoint c;
    c.nextSample = next;
    c.seconds = std::chrono::duration<double>(now - runStart).count();
    c.counters = counters();
    c.setupSeconds = firstIlluminationSeconds;
    if (stop) c.illumination = illumination;  // the render ends here
    saveCheckpoint(*hooks, c, film);
    lastCheckpoint = std::chrono::steady_clock::now();
    return stop;
}

bool RenderState::checkNoise(int n) {
    if (rs.noise <= 0 || !isNoiseCheck(n)) return false;
    return reachedTarget = noiseTargetStep(film.sums, film.open, rs.noise, ww, wh, n);
}

RenderResult RenderState::finish() {
    result.spp = spp;
    if (result.interrupted) {
        result.counters = counters();
        result.passSums = std::move(film.passSums);
        return std::move(result);
    }
    result.illuminationSeconds = illumination->stats.seconds;
    result.photons = illumination->stats.photons;
    result.photonPasses = illumination->photonPass + 1;
    film.closePhotonPass();
    result.passSums = std::move(film.passSums);
    const PixelSums& sums = film.sums;
    result.image = sums.average(ww, wh);
    result.layers = aovLayers(aovs, film.aovs, sums);
    result.noise = estimateNoise(sums, first);
    result.reachedNoiseTarget = reachedTarget;
    double sampled = 0;
    for (size_t p = 0; p < pixels; ++p) sampled += sums.samplesOf(p);
    result.meanSpp = sampled / double(pixels);
    if (adaptive) {
        // How the samples were spent (docs/noise.md).
        ExrLayer count{"samples", {"N"}, std::vector<float>(pixels)};
        for (size_t p = 0; p < pixels; ++p) count.pixels[p] = float(sums.samplesOf(p));
        result.layers.push_back(std::move(count));
    }
    if (options.keepHalves) {
        result.evenHalf = sums.evenHalf(ww, wh);
        result.oddHalf = sums.oddHalf(ww, wh);
        result.emittedEven = sums.emittedHalf(ww, wh, false);
        result.emittedOdd = sums.emittedHalf(ww, wh, true);
    }
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() + resumedSeconds;
    result.counters = counters();
    return std::move(result);
}

RenderResult renderImage(const Scene& scene, const RenderOptions& options) {
    // What cannot be rendered is refused before any buffer is allocated.
    RenderState render(scene, options);
    // Photons and the cache count in the time budget: an equal-time
    // comparison charges the guided marcher for its cache.
    render.buildMarcher();
    if (render.hooks && render.hooks->resume) render.resume(*render.hooks->resume);
    // The first checkpoint is due CheckpointHooks::everySeconds from here.
    render.lastCheckpoint = std::chrono::steady_clock::now();
    if (!render.timed && !render.hooks && !render.adaptive)
        render.renderAllSamples();
    else if (!render.timed)
        render.renderInChunks();
    else
        render.renderTimed();
    return render.finish();
}

}  // namespace vdbmarch
