#include "render.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "marchers/marcher.h"

namespace vdbmarch {

namespace {

constexpr int TileSize = 16;

class ProgressBar {
public:
    ProgressBar(bool enabled, int total) : mEnabled(enabled), mTotal(total) {}
    void tick() {
        if (!mEnabled) return;
        int done = ++mDone;
        int percent = int(100LL * done / mTotal);
        std::lock_guard<std::mutex> lock(mMutex);
        if (percent == mShown) return;
        mShown = percent;
        int bars = percent / 4;
        std::fprintf(stderr, "\r[%-25.*s] %3d%%", bars, "=========================", percent);
        if (done == mTotal) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

private:
    bool mEnabled;
    int mTotal;
    std::atomic<int> mDone{0};
    std::mutex mMutex;
    int mShown = -1;
};

}  // namespace

RenderResult renderImage(const Scene& scene, const RenderOptions& options) {
    const RenderSettings& rs = scene.desc.render;
    std::unique_ptr<Marcher> marcher = makeMarcher(rs.method, scene);
    const int w = scene.camera->width(), h = scene.camera->height();
    const int tilesX = (w + TileSize - 1) / TileSize, tilesY = (h + TileSize - 1) / TileSize;
    const int tiles = tilesX * tilesY;
    RenderResult result;
    result.image = Image(w, h);
    std::vector<RenderCounters> tileCounters(static_cast<size_t>(tiles));
    ProgressBar progress(options.progress, tiles);
    const int threads = rs.threads > 0 ? rs.threads : tbb::info::default_concurrency();
    result.threads = threads;
    auto start = std::chrono::steady_clock::now();
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& range) {
            for (int tile = range.begin(); tile != range.end(); ++tile) {
                ThreadContext ctx(scene);
                const int x0 = (tile % tilesX) * TileSize, y0 = (tile / tilesX) * TileSize;
                for (int y = y0; y < std::min(y0 + TileSize, h); ++y)
                    for (int x = x0; x < std::min(x0 + TileSize, w); ++x) {
                        const uint64_t pixel = uint64_t(y) * uint64_t(w) + uint64_t(x);
                        Color sum(0);
                        double transmittance = 0;
                        for (int s = 0; s < rs.spp; ++s) {
                            Rng rng(hashValues(rs.seed, pixel), uint64_t(s));
                            float jx = 0.5f, jy = 0.5f;
                            if (rs.pixelJitter) {
                                jx = rng.uniform();
                                jy = rng.uniform();
                            }
                            Ray ray = scene.camera->generateRay(float(x) + jx, float(y) + jy);
                            PathResult pr = marcher->radiance(ray, rng, ctx);
                            if (!isFinite(pr.L) || !std::isfinite(pr.transmittance)) {
                                ++ctx.counters.nonFiniteSamples;  // dropped, never written
                                continue;
                            }
                            sum += pr.L;
                            transmittance += pr.transmittance;
                        }
                        float inv = 1.f / float(rs.spp);
                        result.image.set(x, y, sum * inv, clamp(1.f - float(transmittance) * inv, 0.f, 1.f));
                    }
                tileCounters[size_t(tile)] += ctx.counters;
                progress.tick();
            }
        }, tbb::simple_partitioner());
    });
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (const auto& c : tileCounters) result.counters += c;
    return result;
}

}  // namespace vdbmarch
