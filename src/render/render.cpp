#include "render/render.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/error.h"
#include "core/memory.h"
#include "core/rng.h"
#include "core/sobol.h"
#include "core/threads.h"
#include "estimators/estimator.h"
#include "transport/first_event.h"

namespace vdbmarch {

namespace {

// Threads take the image in work blocks of WorkBlockSize^2 pixels (not the
// farm's tiles, app/tiles.h, nor the noise target's blocks below).
constexpr int WorkBlockSize = 16;

class ProgressBar {
public:
    ProgressBar(bool enabled, int total) : mEnabled(enabled), mTotal(total) {}
    void tick() {
        if (!mEnabled) return;
        show(++mDone);
    }
    // Fraction in [0, 1] (time budgets).
    void set(double fraction) {
        if (!mEnabled) return;
        show(int(std::min(1.0, std::max(0.0, fraction)) * mTotal));
    }

private:
    void show(int done) {
        int percent = int(100LL * done / mTotal);
        std::lock_guard<std::mutex> lock(mMutex);
        if (percent == mShown) return;
        mShown = percent;
        int bars = percent / 4;
        std::fprintf(stderr, "\r[%-25.*s] %3d%%", bars, "=========================", percent);
        if (done == mTotal) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

    bool mEnabled;
    int mTotal;
    std::atomic<int> mDone{0};
    std::mutex mMutex;
    int mShown = -1;
};

}  // namespace

AovSums::AovSums(const AovSet& aovs, size_t pixels) {
    if (aovs.depth) {
        depth.assign(pixels, 0.0);
        depthSamples.assign(pixels, 0);
    }
    if (aovs.albedo) albedo.assign(pixels, Color(0));
    if (aovs.normal) normal.assign(pixels, Color(0));
    if (aovs.splitDirect()) direct.assign(pixels, Color(0));
}

uint64_t AovSums::bytesPerPixel(const AovSet& a) {
    return (a.depth ? sizeof(double) + sizeof(uint32_t) + sizeof(float) : 0) +
           (a.albedo ? sizeof(Color) + 3 * sizeof(float) : 0) + (a.normal ? sizeof(Color) + 3 * sizeof(float) : 0) +
           (a.splitDirect() ? sizeof(Color) : 0) + (a.direct ? 3 * sizeof(float) : 0) +
           (a.indirect ? 3 * sizeof(float) : 0);
}

namespace {

// Adaptive sampling: pixels stop in blocks of NoiseBlock x NoiseBlock of
// the window, decided at 16 samples and then every quarter more.
constexpr int NoiseBlock = 8;
int nextNoiseCheck(int n) {
    int c = 16;
    while (c <= n) c = std::max(c + 4, (c * 5 + 3) / 4);
    return c;
}
bool isNoiseCheck(int n) { return n >= 16 && nextNoiseCheck(n - 1) == n; }

// Random stream of the feature AOVs, apart from the beauty's.
constexpr uint64_t AovStream = 0x616f7673;
// The pixel positions' sequences (one per half render: PixelStream + 0, + 1).
constexpr uint64_t PixelStream = 0x70697870;

// The layers of the requested AOVs from their sums over `spp` samples. The
// indirect layer is the beauty minus the direct one, so they add up to the
// beauty exactly up to the rounding of that subtraction.
std::vector<ExrLayer> aovLayers(const AovSet& aovs, const AovSums& s, const PixelSums& sums) {
    std::vector<ExrLayer> layers;
    const std::vector<Color>& beauty = sums.L;
    const size_t pixels = beauty.size();
    auto inv = [&](size_t p) { return 1.f / float(sums.samplesOf(p)); };
    auto colorLayer = [&](const char* name, std::vector<std::string> channels, auto value) {
        ExrLayer l{name, std::move(channels), {}};
        l.pixels.reserve(3 * pixels);
        for (size_t p = 0; p < pixels; ++p) {
            const Color c = value(p);
            l.pixels.insert(l.pixels.end(), {c.x, c.y, c.z});
        }
        layers.push_back(std::move(l));
    };
    if (aovs.depth) {
        ExrLayer l{"depth", {"Z"}, std::vector<float>(pixels)};
        for (size_t p = 0; p < pixels; ++p)
            l.pixels[p] = s.depthSamples[p] > 0 ? float(s.depth[p] / double(s.depthSamples[p])) : NoDepth;
        layers.push_back(std::move(l));
    }
    if (aovs.albedo) colorLayer("albedo", {"R", "G", "B"}, [&](size_t p) { return s.albedo[p] * inv(p); });
    if (aovs.normal) colorLayer("normal", {"X", "Y", "Z"}, [&](size_t p) { return s.normal[p] * inv(p); });
    if (aovs.direct) colorLayer("direct", {"R", "G", "B"}, [&](size_t p) { return s.direct[p] * inv(p); });
    if (aovs.indirect)
        colorLayer("indirect", {"R", "G", "B"}, [&](size_t p) { return beauty[p] * inv(p) - s.direct[p] * inv(p); });
    return layers;
}

}  // namespace

void PixelSums::fold(const PhotonPassSums& pass) {
    for (size_t i = 0; i < L.size(); ++i) {
        L[i] += pass.L[i].rounded();
        T[i] += double(float(pass.T[i]));
        oddL[i] += pass.oddL[i].rounded();
        oddT[i] += double(float(pass.oddT[i]));
    }
    if (!pass.E.empty()) {
        if (E.empty()) E.assign(L.size(), Color(0)), oddE.assign(L.size(), Color(0));
        for (size_t i = 0; i < L.size(); ++i) {
            E[i] += pass.E[i].rounded();
            oddE[i] += pass.oddE[i].rounded();
        }
    }
    samples += pass.samples;
}

Image PixelSums::average(int width, int height) const {
    Image img(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t p = size_t(y) * size_t(width) + size_t(x);
            const float inv = 1.f / float(samplesOf(p));
            img.set(x, y, L[p] * inv, clamp(1.f - float(T[p]) * inv, 0.f, 1.f));
        }
    return img;
}

namespace {

// Samples of [first, first + n) with even and with odd index.
void halfCounts(int first, int n, int& even, int& odd) {
    odd = (first + n) / 2 - first / 2;
    even = n - odd;
}

// One half's mean image: per pixel `set(img, x, y, p, n)` with n > 0 the
// half's sample count (pixels of no sample in that half stay 0).
template <class SetPixel>
Image halfImage(const PixelSums& s, int width, int height, bool odd, SetPixel&& set) {
    Image img(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t p = size_t(y) * size_t(width) + size_t(x);
            int ne, no;
            halfCounts(0, s.samplesOf(p), ne, no);
            const int n = odd ? no : ne;
            if (n > 0) set(img, x, y, p, n);
        }
    return img;
}

// The beauty's half: the odd-index samples' sums, or the total minus them.
Image halfImage(const PixelSums& s, int width, int height, bool odd) {
    return halfImage(s, width, height, odd, [&](Image& img, int x, int y, size_t p, int n) {
        const Color l = odd ? s.oddL[p] : s.L[p] - s.oddL[p];
        const double t = odd ? s.oddT[p] : s.T[p] - s.oddT[p];
        img.set(x, y, l / float(n), clamp(1.f - float(t / double(n)), 0.f, 1.f));
    });
}

// Mean and variance of the mean of one pixel from its sums over n samples
// starting at sample `first` (the two halves' difference, NoiseEstimate).
bool pixelNoise(const Color& L, const Color& oddL, int first, int n, Color& mean, Color& variance) {
    int ne, no;
    halfCounts(first, n, ne, no);
    if (ne == 0 || no == 0) return false;
    mean = L / float(n);
    const Color d = (L - oddL) / float(ne) - oddL / float(no);
    variance = d * d * float(double(ne) * double(no) / (double(n) * double(n)));
    return true;
}

// The image's NoiseEstimate from its pixels' means and variances, RGB summed.
struct NoiseTotals {
    double variance = 0, mean = 0;
    size_t pixels = 0;
    void add(const Color& m, const Color& v) {
        variance += double(v.x) + double(v.y) + double(v.z);
        mean += double(m.x) + double(m.y) + double(m.z);
        ++pixels;
    }
    NoiseEstimate estimate() const {
        NoiseEstimate e;
        const double n = 3.0 * double(std::max<size_t>(1, pixels));
        e.valid = pixels > 0;
        e.rmse = std::sqrt(variance / n);
        e.mean = mean / n;
        return e;
    }
};

// The blocks of adaptive sampling at a check after n samples: each 8x8
// block's per-sample standard deviation s_b (its pixels' variances times
// their sample counts, RGB summed: docs/noise.md) and the image's noise.
// False where a pixel lacks one of its halves.
struct NoiseBlocks {
    int bx = 0, by = 0;
    std::vector<double> sigma;
    std::vector<int> count;  // pixels in the block
    NoiseEstimate image;
    NoiseBlocks() = default;
    // The blocks of a ww x wh window, zeroed.
    NoiseBlocks(int ww, int wh)
        : bx((ww + NoiseBlock - 1) / NoiseBlock), by((wh + NoiseBlock - 1) / NoiseBlock),
          sigma(size_t(bx) * size_t(by), 0.0), count(sigma.size(), 0) {}
    size_t size() const { return sigma.size(); }
    size_t of(int x, int y) const { return size_t(y / NoiseBlock) * size_t(bx) + size_t(x / NoiseBlock); }
};
bool measureNoiseBlocks(const PixelSums& sums, const PhotonPassSums& open, int ww, int wh, int n, NoiseBlocks& out) {
    out = NoiseBlocks(ww, wh);
    NoiseTotals totals;
    for (int y = 0; y < wh; ++y)
        for (int x = 0; x < ww; ++x) {
            const size_t p = size_t(y) * size_t(ww) + size_t(x);
            Color L = sums.L[p], odd = sums.oddL[p], mean, var;
            if (open.pass >= 0) {
                L += open.L[p].rounded();
                odd += open.oddL[p].rounded();
            }
            const int k = sums.convergedAt[p] > 0 ? sums.convergedAt[p] : n;
            if (!pixelNoise(L, odd, 0, k, mean, var)) return false;
            totals.add(mean, var);
            out.sigma[out.of(x, y)] += double(float((double(var.x) + double(var.y) + double(var.z)) * k));
            ++out.count[out.of(x, y)];
        }
    for (size_t b = 0; b < out.sigma.size(); ++b) out.sigma[b] = std::sqrt(out.sigma[b] / (3.0 * out.count[b]));
    out.image = totals.estimate();
    return true;
}

// Stops the pixels of the still-sampling blocks whose count n has reached
// their target k a_b (sums.convergedAt = n); true when no pixel samples on.
bool stopBlocksAt(PixelSums& sums, const NoiseBlocks& blocks, const std::vector<double>& target, int ww, int wh,
                  int n) {
    bool any = false;
    for (int y = 0; y < wh; ++y)
        for (int x = 0; x < ww; ++x) {
            int& c = sums.convergedAt[size_t(y) * size_t(ww) + size_t(x)];
            if (c == 0 && double(n) >= target[blocks.of(x, y)]) c = n;
            any = any || c == 0;
        }
    return !any;
}

// The noise target (render.noise, docs/noise.md) at a check after n samples:
// true once the window's estimated RMSE is below noise x its mean. Until
// then each 8x8 block gets samples in proportion to s_b, the allocation that
// minimises the image's MSE for a sample count (n_b = k s_b gives MSE =
// mean(s_b) / k), with k set so that this MSE meets the target: a block
// stops (sums.convergedAt) once n >= k s_b. The decisions depend only on the
// sums, so the image is the same for any thread count.
bool noiseTargetStep(PixelSums& sums, const PhotonPassSums& open, float noise, int ww, int wh, int n) {
    NoiseBlocks blocks;
    if (!measureNoiseBlocks(sums, open, ww, wh, n, blocks)) return false;
    const double target = double(noise) * blocks.image.mean;
    if (blocks.image.rmse <= target) return true;
    double weighted = 0;
    for (size_t b = 0; b < blocks.sigma.size(); ++b) weighted += blocks.sigma[b] * blocks.count[b];
    const double k = weighted / (double(ww) * double(wh)) / (target * target);
    std::vector<double> samples(blocks.sigma.size());
    for (size_t b = 0; b < samples.size(); ++b) samples[b] = k * blocks.sigma[b];
    stopBlocksAt(sums, blocks, samples, ww, wh, n);
    return false;
}

// Each pixel's camera time in a timed adaptive render: seconds summed over
// the samples this process rendered, and how many.
struct PixelTimes {
    std::vector<double> seconds;
    std::vector<int> samples;
};

// What the denoiser leaves of each block's noise, from a denoised frame's
// estimated variance per pixel (`denoised`): K_b = the block's summed pixel
// variance over its summed denoised variance, at least 1 and at most
// MaxDenoiserGain.
constexpr double MaxDenoiserGain = 1000;
std::vector<double> denoiserGains(const PixelSums& frame, const std::vector<float>& denoised, int ww, int wh) {
    const NoiseBlocks layout(ww, wh);
    std::vector<double> noise(layout.size(), 0.0), error(layout.size(), 0.0);
    for (int y = 0; y < wh; ++y)
        for (int x = 0; x < ww; ++x) {
            const size_t p = size_t(y) * size_t(ww) + size_t(x), b = layout.of(x, y);
            Color mean, var;
            if (pixelNoise(frame.L[p], frame.oddL[p], 0, frame.samplesOf(p), mean, var))
                noise[b] += double(var.x) + double(var.y) + double(var.z);
            if (std::isfinite(denoised[p])) error[b] += std::max(0.0, double(denoised[p]));
        }
    std::vector<double> gain(noise.size(), 1.0);
    for (size_t b = 0; b < gain.size(); ++b)
        gain[b] = noise[b] >= error[b] * MaxDenoiserGain ? MaxDenoiserGain : std::max(1.0, noise[b] / error[b]);
    return gain;
}

// Adaptive sampling of a timed render (experiments.adaptive, docs/noise.md) at a
// check after n samples, with `secondsLeft` of camera time left (summed over
// the threads). Each block has s_b and t_b, its pixels' measured seconds
// per sample, and where the render is denoised K_b (`gains`, empty: 1), the
// factor by which the denoiser divides its variance. The allocation n_b = k s_b /
// sqrt(K_b t_b) minimises the image's MSE, sum_b s_b^2 / (K_b n_b), for the
// time sum_b t_b n_b; k is the water level
// at which the still-sampling blocks' targets take up the time left, and a
// block whose count has reached its target stops. The time left is taken a
// fifth larger than predicted, so that a wrong prediction leaves a block
// sampling rather than stopping it early. True when every pixel stopped.
bool timedAdaptiveStep(PixelSums& sums, const PhotonPassSums& open, const PixelTimes& times,
                       const std::vector<double>& gains, int ww, int wh, int n, double secondsLeft) {
    NoiseBlocks blocks;
    if (!measureNoiseBlocks(sums, open, ww, wh, n, blocks)) return false;
    const size_t nb = blocks.size();
    std::vector<double> seconds(nb, 0.0), timed(nb, 0.0);
    std::vector<char> active(nb, 0);
    for (int y = 0; y < wh; ++y)
        for (int x = 0; x < ww; ++x) {
            const size_t p = size_t(y) * size_t(ww) + size_t(x), b = blocks.of(x, y);
            seconds[b] += times.seconds[p];
            timed[b] += times.samples[p];
            if (sums.convergedAt[p] == 0) active[b] = 1;
        }
    // Blocks without a measured time (a resumed render's pixels that have
    // not sampled since) keep sampling, outside the allocation; a block's
    // time is floored at a hundredth of the mean. A block of no noise at all
    // (the background) has target 0: it stops, as it does towards a noise
    // target.
    double meanTime = 0, pixelsIn = 0;
    for (size_t b = 0; b < nb; ++b) {
        active[b] = active[b] && timed[b] > 0;
        if (!active[b]) continue;
        meanTime += seconds[b] / timed[b] * blocks.count[b];
        pixelsIn += blocks.count[b];
    }
    if (pixelsIn == 0 || !(meanTime > 0)) return false;
    meanTime /= pixelsIn;
    std::vector<double> a(nb, 0.0), t(nb, 0.0);
    for (size_t b = 0; b < nb; ++b) {
        if (!active[b]) continue;
        t[b] = std::max(seconds[b] / timed[b], 0.01 * meanTime);
        a[b] = blocks.sigma[b] / std::sqrt(t[b] * (gains.empty() ? 1.0 : gains[b]));
    }
    // The water level: the time the active blocks' targets take beyond n,
    // sum_b count_b t_b max(0, k a_b - n), equals the time left.
    const double budget = 1.2 * std::max(secondsLeft, 0.0);
    auto timeAt = [&](double k) {
        double sum = 0;
        for (size_t b = 0; b < nb; ++b)
            if (active[b]) sum += blocks.count[b] * t[b] * std::max(0.0, k * a[b] - n);
        return sum;
    };
    double lo = 0, hi = 1;
    for (int i = 0; i < 200 && timeAt(hi) < budget; ++i) hi *= 2;
    for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (timeAt(mid) < budget ? lo : hi) = mid;
    }
    std::vector<double> target(nb, std::numeric_limits<double>::infinity());
    for (size_t b = 0; b < nb; ++b)
        if (active[b]) target[b] = hi * a[b];
    return stopBlocksAt(sums, blocks, target, ww, wh, n);
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
void addCameraSample(const Scene& scene, const Estimator& marcher, ThreadContext& ctx, int x, int y, uint64_t pixel,
                     int s, size_t local, PhotonPassSums& open, AovSums& aovSums) {
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
    if (aovs.firstEvent()) {
        Rng aovRng(hashValues(rs.seed, pixel, AovStream), uint64_t(s));
        const FirstEvent fe = traceFirstEvent(ctx, ray, aovRng);
        if (aovs.depth && fe.hasDepth) {
            aovSums.depth[local] += double(scene.camera->viewDepth(fe.depthPoint));
            ++aovSums.depthSamples[local];
        }
        if (aovs.albedo) aovSums.albedo[local] += fe.albedo;
        if (aovs.normal) aovSums.normal[local] += fe.normal;
    }
}

}  // namespace

Image PixelSums::evenHalf(int width, int height) const { return halfImage(*this, width, height, false); }
Image PixelSums::oddHalf(int width, int height) const { return halfImage(*this, width, height, true); }

Image PixelSums::emittedHalf(int width, int height, bool odd) const {
    if (E.empty()) return Image();
    return halfImage(*this, width, height, odd, [&](Image& img, int x, int y, size_t p, int n) {
        img.set(x, y, (odd ? oddE[p] : E[p] - oddE[p]) / float(n), 1.f);
    });
}

NoiseEstimate estimateNoise(const PixelSums& sums, int firstSample) {
    NoiseTotals totals;
    for (size_t p = 0; p < sums.L.size(); ++p) {
        Color mean, var;
        if (!pixelNoise(sums.L[p], sums.oddL[p], firstSample, sums.samplesOf(p), mean, var)) return {};
        totals.add(mean, var);
    }
    return totals.estimate();
}

PixelRect tileOfFrame(int index, int count, int width, int height) {
    if (count < 1 || count > height)
        throw InputError(str("--tile ", index, "/", count, ": the frame is split into horizontal bands of rows, so the "
                             "tile count must be 1 to the image height (", height, ")"));
    if (index < 0 || index >= count)
        throw InputError(str("--tile ", index, "/", count, ": the tile index must be 0 to ", count - 1));
    auto row = [&](int i) { return int(int64_t(i) * height / count); };
    return {0, row(index), width, row(index + 1)};
}

uint64_t imageMemoryBytes(int width, int height, const AovSet& aovs, bool emitted) {
    // The totals, the open pass's sums, the RGBA result and the AOVs.
    // Each twice: all samples and the odd-index half. The emitted part: its
    // totals and open sums, twice, and its two RGB layers.
    const uint64_t perPixel = 2 * (sizeof(Color) + sizeof(ColorSum) + 2 * sizeof(double)) + 4 * sizeof(float) +
                              sizeof(int) + sizeof(double) + sizeof(int) + AovSums::bytesPerPixel(aovs) +
                              (emitted ? 2 * (sizeof(Color) + sizeof(ColorSum)) + 6 * sizeof(float) : 0);
    return uint64_t(width) * uint64_t(height) * perPixel;
}

bool sceneEmitsLight(const SceneDesc& desc) {
    for (const MediumDesc& m : desc.media)
        if (m.hasEmission) return true;
    for (const LightDesc& l : desc.lights)
        if (l.type == LightDesc::Type::Sphere) return true;
    return false;
}

void checkImageMemory(int width, int height, const AovSet& aovs, bool emitted) {
    checkMemory(imageMemoryBytes(width, height, aovs, emitted),
                str("camera.resolution = [", width, ", ", height, "]: the image"));
}

bool keepShareOfBlocks(std::vector<int>& convergedAt, int width, int height, int blockSize, double share, int n) {
    const int bx = (width + blockSize - 1) / blockSize, blocks = bx * ((height + blockSize - 1) / blockSize);
    auto pixelsOf = [&](int b, auto&& f) {
        const int x0 = (b % bx) * blockSize, y0 = (b / bx) * blockSize;
        for (int y = y0; y < std::min(y0 + blockSize, height); ++y)
            for (int x = x0; x < std::min(x0 + blockSize, width); ++x) f(size_t(y) * size_t(width) + size_t(x));
    };
    std::vector<std::pair<uint64_t, int>> order;  // the blocks still sampling, in a fixed scattered order
    for (int b = 0; b < blocks; ++b) {
        bool active = false;
        pixelsOf(b, [&](size_t p) { active = active || convergedAt[p] == 0; });
        if (active) order.push_back({mixBits(uint64_t(b) + 1), b});
    }
    std::sort(order.begin(), order.end());
    const size_t keep = size_t(std::lround(std::clamp(share, 0.0, 1.0) * double(order.size())));
    if (keep == 0) return false;
    for (size_t i = keep; i < order.size(); ++i)
        pixelsOf(order[i].second, [&](size_t p) {
            if (convergedAt[p] == 0) convergedAt[p] = n;
        });
    return true;
}

RenderResult renderImage(const Scene& scene, const RenderOptions& options) {
    const RenderSettings& rs = scene.desc.render;
    const int w = scene.camera->width(), h = scene.camera->height();
    const PixelRect frame{0, 0, w, h};
    const PixelRect window = options.crop ? *options.crop : frame;
    if (window.empty() || !frame.contains(window))
        throw InputError(str("crop [", window.x0, ", ", window.x1, ") x [", window.y0, ", ", window.y1,
                             ") is empty or not inside the ", w, "x", h, " frame"));
    // Buffers hold the window's pixels; random streams are keyed by the
    // pixel's index in the whole frame.
    const int ww = window.width(), wh = window.height();
    checkImageMemory(ww, wh, rs.aovs, options.keepEmitted);
    const size_t pixels = size_t(ww) * size_t(wh);
    const bool timed = options.timeBudget > 0;
    const AovSet& aovs = rs.aovs;
    // What the photon passes are (nothing is traced yet), and which samples
    // this render takes: refused before any buffer is allocated.
    const IlluminationRequest request = illuminationRequest(scene, rs.method, options.illumination);
    const PhotonPasses photonPasses(scene, request, w * h);
    // The passes of the whole render, and the samples of the passes asked for.
    const int totalPasses = photonPasses.passOf(std::max(0, rs.spp - 1)) + 1;
    const int totalPhotonPasses = timed ? 0 : totalPasses;
    int first = 0, last = rs.spp;
    if (options.photonPassRange)
        std::tie(first, last) = samplesOfPasses(scene, photonPasses, *options.photonPassRange, timed, totalPasses, ww, wh);

    const int workBlocksX = (ww + WorkBlockSize - 1) / WorkBlockSize, workBlocksY = (wh + WorkBlockSize - 1) / WorkBlockSize;
    const int workBlocks = workBlocksX * workBlocksY;
    RenderResult result;
    result.window = window;
    result.totalPhotonPasses = totalPhotonPasses;
    result.firstSample = first;
    PixelSums sums(pixels);
    PhotonPassSums open;  // the sums of the pass being rendered
    open.pass = -1;
    AovSums aovSums(aovs, pixels);
    // Adaptive sampling: towards the noise target (render.noise), or in a
    // timed render by each block's noise and measured time (experiments.adaptive).
    const bool timedAdaptive = timed && scene.desc.experiments.adaptive && rs.noise <= 0;
    const bool adaptive = rs.noise > 0 || timedAdaptive;
    if (adaptive) sums.convergedAt.assign(pixels, 0);
    PixelTimes times;
    if (timedAdaptive) {
        times.seconds.assign(pixels, 0.0);
        times.samples.assign(pixels, 0);
    }
    std::vector<RenderCounters> workBlockCounters(static_cast<size_t>(workBlocks));
    ProgressBar progress(options.progress, timed || options.checkpoint || rs.noise > 0 ? 1000 : workBlocks);
    const int threads = resolveThreadCount(rs.threads);
    result.threads = threads;
    auto start = std::chrono::steady_clock::now();
    auto runStart = options.runStart ? *options.runStart : start;
    tbb::task_arena arena(threads);

    // Photons and the cache count in the time budget: an equal-time
    // comparison charges the guided marcher for its cache.
    std::shared_ptr<Illumination> illumination;
    std::unique_ptr<Estimator> marcher;
    // The sampling strategies and their tables, once per render.
    const std::shared_ptr<const StrategySet> strategies =
        options.strategies ? options.strategies : StrategySet::build(scene);
    arena.execute([&] {
        illumination = std::make_shared<Illumination>(buildIllumination(scene, request));
        marcher = makeEstimator(rs.method, scene, illumination, strategies);
    });
    const double firstIlluminationSeconds = illumination->stats.seconds;
    result.cacheCells = illumination->cache ? illumination->cache->cells.size() : 0;
    result.photonBytes = illumination->stats.photonBytes;
    result.cacheBytes = illumination->stats.cacheBytes;

    // A resumed render takes the checkpoint's sums, counters and time; the
    // photon passes are replayed from their seeds when the next sample needs
    // them (PhotonPasses::advance), so the illumination is the same too.
    const CheckpointHooks* hooks = options.checkpoint ? &*options.checkpoint : nullptr;
    int resumeSample = first;
    RenderCounters resumedCounters;
    double resumedSeconds = 0;
    if (hooks && hooks->resume) {
        const RenderCheckpoint& c = *hooks->resume;
        if (c.sums.L.size() != pixels || c.nextSample < first || (!timed && c.nextSample > last))
            throw std::logic_error("renderImage: the checkpoint does not belong to this render");
        sums = c.sums;
        if (adaptive && sums.convergedAt.size() != pixels) sums.convergedAt.assign(pixels, 0);
        open = c.open;
        result.passSums = c.passSums;
        aovSums = c.aovs;
        resumedCounters = c.counters;
        resumeSample = c.nextSample;
        resumedSeconds = c.seconds;
        runStart -= std::chrono::duration_cast<std::chrono::steady_clock::duration>(
            std::chrono::duration<double>(resumedSeconds));
    }

    // One sweep renders samples [s0, s1) of every pixel. Each pixel sums its
    // samples in index order, so the image depends only on the final sample
    // count, never on how samples were split into sweeps or threads.
    auto renderSweep = [&](int s0, int s1) {
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<int>(0, workBlocks, 1), [&](const tbb::blocked_range<int>& range) {
                for (int workBlock = range.begin(); workBlock != range.end(); ++workBlock) {
                    ThreadContext ctx(scene);
                    const int x0 = window.x0 + (workBlock % workBlocksX) * WorkBlockSize, y0 = window.y0 + (workBlock / workBlocksX) * WorkBlockSize;
                    for (int y = y0; y < std::min(y0 + WorkBlockSize, window.y1); ++y)
                        for (int x = x0; x < std::min(x0 + WorkBlockSize, window.x1); ++x) {
                            const uint64_t pixel = uint64_t(y) * uint64_t(w) + uint64_t(x);  // in the frame
                            const size_t local = size_t(y - window.y0) * size_t(ww) + size_t(x - window.x0);
                            if (adaptive && sums.convergedAt[local] > 0) continue;  // stopped sampling
                            const auto t0 = timedAdaptive ? std::chrono::steady_clock::now()
                                                          : std::chrono::steady_clock::time_point();
                            for (int s = s0; s < s1; ++s)
                                addCameraSample(scene, *marcher, ctx, x, y, pixel, s, local, open, aovSums);
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
    };

    // A photon pass's sums are folded into the totals when the next pass
    // starts and at the end (and kept apart with options.photonPassRange).
    auto closePhotonPass = [&] {
        if (open.pass < 0) return;
        sums.fold(open);
        if (options.photonPassRange) result.passSums.push_back(std::move(open));
        open = PhotonPassSums();
        open.pass = -1;
    };
    auto openPhotonPass = [&](int pass, int samples) {
        if (open.pass != pass) {
            closePhotonPass();
            open.pass = pass;
            open.L.assign(pixels, ColorSum());
            open.T.assign(pixels, 0.0);
            open.oddL.assign(pixels, ColorSum());
            open.oddT.assign(pixels, 0.0);
            if (options.keepEmitted) {
                open.E.assign(pixels, ColorSum());
                open.oddE.assign(pixels, ColorSum());
            }
        }
        open.samples += samples;
    };

    // Samples [s0, s1), pass by pass of photons: the marcher reads the pass's
    // map and radius through `illumination`, and is made again only when the
    // cache was refined (eq. 17's scale is measured from the cache).
    auto renderSamples = [&](int s0, int s1) {
        for (int s = s0; s < s1;) {
            const int pass = photonPasses.passOf(s);
            if (pass != illumination->photonPass) {
                arena.execute([&] {
                    if (photonPasses.advance(scene, pass, *illumination))
                        marcher = makeEstimator(rs.method, scene, illumination, strategies);
                });
            }
            const int end = std::min(s1, photonPasses.progressive() ? photonPasses.firstSampleOf(pass + 1) : s1);
            openPhotonPass(pass, end - s);
            renderSweep(s, end);
            s = end;
        }
    };


    // The counters so far, those of a resumed render's first runs included.
    auto counters = [&] {
        RenderCounters total = resumedCounters;
        for (const auto& t : workBlockCounters) total += t;
        return total;
    };

    // At a sample boundary (`next` samples done): hands the state to the
    // checkpoint hook when one is due or a stop was asked for; true: stop.
    auto lastCheckpoint = std::chrono::steady_clock::now();
    auto checkpointAt = [&](int next) {
        if (!hooks) return false;
        const bool stop = hooks->stopRequested && hooks->stopRequested();
        const auto now = std::chrono::steady_clock::now();
        if (!stop && std::chrono::duration<double>(now - lastCheckpoint).count() < hooks->everySeconds) return false;
        RenderCheckpoint c;
        c.nextSample = next;
        c.seconds = std::chrono::duration<double>(now - runStart).count();
        c.counters = counters();
        // The sums are lent to the checkpoint, not copied (a large frame's
        // are hundreds of megabytes), and taken back even if saving throws.
        c.sums = std::move(sums);
        c.open = std::move(open);
        c.passSums = std::move(result.passSums);
        c.aovs = std::move(aovSums);
        struct GiveBack {
            RenderCheckpoint& c;
            PixelSums& sums;
            PhotonPassSums& open;
            std::vector<PhotonPassSums>& passSums;
            AovSums& aovs;
            ~GiveBack() {
                sums = std::move(c.sums);
                open = std::move(c.open);
                passSums = std::move(c.passSums);
                aovs = std::move(c.aovs);
            }
        } giveBack{c, sums, open, result.passSums, aovSums};
        hooks->save(c);
        lastCheckpoint = std::chrono::steady_clock::now();
        return stop;
    };

    // The noise target (render.noise): checked at fixed sample counts.
    bool reachedTarget = false;
    auto checkNoise = [&](int n) {
        if (rs.noise <= 0 || !isNoiseCheck(n)) return false;
        return reachedTarget = noiseTargetStep(sums, open, rs.noise, ww, wh, n);
    };

    int spp = resumeSample - first;
    if (!timed && !hooks && !adaptive) {
        renderSamples(first, last);
        spp = last - first;
    } else if (!timed) {
        // In chunks of whole samples per pixel, about a second each, so a
        // stop is acted on soon, and ending at every noise check; the sums
        // do not depend on the chunks.
        int s = resumeSample, chunk = hooks ? 1 : last;
        while (s < last) {
            if (checkpointAt(s)) {
                result.interrupted = true;
                break;
            }
            const auto c0 = std::chrono::steady_clock::now();
            const int e = std::min({last, s + chunk, adaptive ? nextNoiseCheck(s) : last});
            renderSamples(s, e);
            const double perSample =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count() / double(e - s);
            if (hooks)
                chunk = int(std::clamp(std::min(1.0, hooks->everySeconds) / std::max(perSample, 1e-6), 1.0, 4096.0));
            s = e;
            progress.set(double(s - first) / double(last - first));
            if (checkNoise(s)) break;
        }
        spp = s - first;
    } else {
        // Sweeps of whole samples per pixel while the next sample is expected
        // to finish within the budget (which also covers loading, measured
        // from runStart, less what is kept back for the denoiser); always at
        // least one sweep, and two samples where the halves are kept (the
        // denoiser needs both). The first sweep is one
        // sample; later ones as many as fill about TimedSweepSeconds and fit
        // in the time left (a sweep makes a thread context per block of
        // pixels, whose set-up one sample per sweep paid for every sample:
        // 12 % of cloud_sun's time at 160x120), ending at noise checks and
        // photon passes. The sums do not depend on the sweeps. A sample that
        // starts a photon pass is expected to take as long as the first
        // photons did.
        constexpr double TimedSweepSeconds = 0.1;
        constexpr int MaxTimedSweep = 64;
        const double budget = options.timeBudget - std::max(options.reserveSeconds, 0.0);
        double perSample = 0;  // the camera part of one sample per pixel, last measured
        double cameraSeconds = 0;  // the sweeps' camera time so far (wall)
        std::vector<double> gains;      // the denoiser's per block, last measured
        double lastDenoiseSeconds = -1;
        auto photonsBeforeSample = [&](int sample) {
            const int pass = photonPasses.passOf(sample);
            return pass != illumination->photonPass && photonPasses.needsWork(pass) ? firstIlluminationSeconds : 0.0;
        };
        do {
            if (checkpointAt(first + spp)) {
                result.interrupted = true;
                break;
            }
            auto p0 = std::chrono::steady_clock::now();
            int n = 1;
            if (perSample > 0) {
                const double room = budget * 0.98 - std::chrono::duration<double>(p0 - runStart).count() -
                                    photonsBeforeSample(spp);
                // A checkpoint is due at a sweep's end every hooks->everySeconds.
                const double sweep = std::min(TimedSweepSeconds, hooks ? hooks->everySeconds : TimedSweepSeconds);
                n = int(std::clamp(std::min(sweep, room / 1.05) / perSample, 1.0, double(MaxTimedSweep)));
                if (adaptive) n = std::min(n, nextNoiseCheck(spp) - spp);
                if (photonPasses.progressive())
                    n = std::min(n, photonPasses.firstSampleOf(photonPasses.passOf(spp) + 1) - spp);
                n = std::max(n, 1);
            }
            const double photonsBefore = illumination->stats.seconds;
            renderSamples(spp, spp + n);
            spp += n;
            auto now = std::chrono::steady_clock::now();
            // The camera part of the sweep (photons are predicted apart).
            const double camera =
                std::chrono::duration<double>(now - p0).count() - (illumination->stats.seconds - photonsBefore);
            perSample = camera / double(n);
            cameraSeconds += camera;
            double elapsed = std::chrono::duration<double>(now - runStart).count();
            progress.set(elapsed / budget);
            if (checkNoise(spp)) break;
            if (timedAdaptive && isNoiseCheck(spp)) {
                // The time left in the pixels' seconds: wall time times the
                // threads' measured pixel seconds per wall second.
                double pixelSeconds = 0;
                for (double t : times.seconds) pixelSeconds += t;
                // Where the frame is denoised, the denoiser's gain per block,
                // measured again at a check while a denoise costs at most
                // DenoiseCheckShare of the time left (the first expected to
                // take what the render keeps back for the final one).
                constexpr double DenoiseCheckShare = 0.02;
                const double expected = lastDenoiseSeconds >= 0 ? lastDenoiseSeconds : options.reserveSeconds;
                if (options.denoisedVariance && expected <= DenoiseCheckShare * (budget * 0.98 - elapsed)) {
                    const auto d0 = std::chrono::steady_clock::now();
                    PixelSums frame = sums;
                    if (open.pass >= 0) frame.fold(open);
                    FrameHalves halves{frame.evenHalf(ww, wh), frame.oddHalf(ww, wh), frame.emittedHalf(ww, wh, false),
                                       frame.emittedHalf(ww, wh, true), aovLayers(aovs, aovSums, frame)};
                    const std::vector<float> denoised = options.denoisedVariance(halves);
                    if (denoised.size() == pixels) gains = denoiserGains(frame, denoised, ww, wh);
                    lastDenoiseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - d0).count();
                    elapsed += lastDenoiseSeconds;
                }
                const double left = (budget * 0.98 - elapsed) * (cameraSeconds > 0 ? pixelSeconds / cameraSeconds : 0.0);
                if (timedAdaptiveStep(sums, open, times, gains, ww, wh, spp, left)) break;
            }
            // At least two samples where the halves are kept: the denoiser
            // needs both (a one-sample render is written noisy).
            const int fewest = options.keepHalves ? 2 : 1;
            const double photonsNext = photonsBeforeSample(spp);
            if (first + spp >= fewest && elapsed + 1.05 * perSample + photonsNext > budget * 0.98) {
                // The time left buys part of one more sample (after its photon
                // pass, where it starts one): the pixels of a share of the
                // still-sampling work blocks take it (spread over the frame in
                // a fixed order), the others stop where they are. Where a
                // sample costs seconds (guided marching at 640x480) up to half
                // of a 12 s budget was left unused (docs/noise.md).
                if (timedAdaptive && !options.photonPassRange) {
                    const double share = (budget * 0.98 - elapsed - photonsNext) / (1.05 * perSample);
                    if (share > 0.05 && keepShareOfBlocks(sums.convergedAt, ww, wh, WorkBlockSize, share, spp)) {
                        renderSamples(spp, spp + 1);
                        ++spp;
                    }
                }
                break;
            }
        } while (spp < (1 << 24));
        progress.set(1.0);
    }
    result.spp = spp;
    if (result.interrupted) {
        result.counters = counters();
        return result;
    }
    result.illuminationSeconds = illumination->stats.seconds;
    result.photons = illumination->stats.photons;
    result.photonPasses = illumination->photonPass + 1;
    closePhotonPass();
    result.image = sums.average(ww, wh);
    result.layers = aovLayers(aovs, aovSums, sums);
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
    return result;
}

}  // namespace vdbmarch
