#include "render/adaptive_sampling.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "core/rng.h"
#include "render/noise_estimate.h"

namespace vdbmarch {

namespace {

// Pixels stop in blocks of NoiseBlock x NoiseBlock of the window.
constexpr int NoiseBlock = 8;

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

}  // namespace

int nextNoiseCheck(int n) {
    int c = 16;
    while (c <= n) c = std::max(c + 4, (c * 5 + 3) / 4);
    return c;
}
bool isNoiseCheck(int n) { return n >= 16 && nextNoiseCheck(n - 1) == n; }

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

// Adaptive sampling of a timed render (experiments.adaptive, docs/noise.md):
// each block has s_b and t_b, its pixels' measured seconds per sample, and
// where the render is denoised K_b (`gains`, empty: 1), the factor by which
// the denoiser divides its variance. The allocation n_b = k s_b /
// sqrt(K_b t_b) minimises the image's MSE, sum_b s_b^2 / (K_b n_b), for the
// time sum_b t_b n_b; k is the water level at which the still-sampling
// blocks' targets take up the time left, and a block whose count has reached
// its target stops. The time left is taken a fifth larger than predicted,
// so that a wrong prediction leaves a block sampling rather than stopping
// it early.
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

}  // namespace vdbmarch
