#include "image/metrics.h"

#include "core/error.h"
#include "image/png_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace vdbmarch {

namespace {

// Keeps relative errors bounded where the reference is near black. 1e-2 makes
// relMse the standard relMSE of the rendering literature (adaptive-sampling
// and denoising papers since Rousselle et al.), so numbers are comparable.
constexpr double RelEpsilon = 1e-2;

void checkSameSize(const Image& test, const Image& reference) {
    if (test.width != reference.width || test.height != reference.height)
        throw InputError(str("image sizes differ: test is ", test.width, "x", test.height,
                             ", reference is ", reference.width, "x", reference.height));
}

bool finiteRgb(const Image& img, size_t i) {
    const float* p = &img.rgba[i * 4];
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

}  // namespace

// matplotlib's viridis sampled at 10 even steps (as R viridisLite::viridis(10)).
constexpr uint8_t Viridis[10][3] = {
    {0x44, 0x01, 0x54}, {0x48, 0x28, 0x78}, {0x3E, 0x4A, 0x89}, {0x31, 0x68, 0x8E}, {0x26, 0x82, 0x8E},
    {0x1F, 0x9E, 0x89}, {0x35, 0xB7, 0x79}, {0x6D, 0xCD, 0x59}, {0xB4, 0xDE, 0x2C}, {0xFD, 0xE7, 0x25},
};

void viridisColor(double t, uint8_t out[3]) {
    t = clamp(t, 0.0, 1.0) * 9.0;
    int i = std::min(int(t), 8);
    double f = t - i;
    for (int c = 0; c < 3; ++c)
        out[c] = uint8_t(std::lround(Viridis[i][c] + f * (Viridis[i + 1][c] - Viridis[i][c])));
}

ImageErrorStats compareImages(const Image& test, const Image& reference) {
    checkSameSize(test, reference);
    ImageErrorStats s;
    double sumSq = 0, sumRel = 0, sumAbsRel = 0, sumA = 0, sumB = 0;
    for (size_t i = 0; i < test.pixelCount(); ++i) {
        bool okA = finiteRgb(test, i), okB = finiteRgb(reference, i);
        s.nonFiniteA += !okA;
        s.nonFiniteB += !okB;
        if (!okA || !okB) continue;
        ++s.pixels;
        for (int c = 0; c < 3; ++c) {
            double a = test.rgba[i * 4 + c], b = reference.rgba[i * 4 + c];
            double d = a - b;
            sumSq += d * d;
            sumRel += d * d / (b * b + RelEpsilon);
            sumAbsRel += std::abs(d) / (std::abs(b) + RelEpsilon);
            sumA += a;
            sumB += b;
        }
    }
    const double n = 3.0 * double(s.pixels);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.rmse = n > 0 ? std::sqrt(sumSq / n) : nan;
    s.relMse = n > 0 ? sumRel / n : nan;
    s.meanAbsRelError = n > 0 ? sumAbsRel / n : nan;
    s.meanA = n > 0 ? sumA / n : nan;
    s.meanB = n > 0 ? sumB / n : nan;
    return s;
}

RelErrorSpread relativeErrorSpread(const Image& test, const Image& reference, float minReferenceAlpha) {
    checkSameSize(test, reference);
    const size_t count = test.pixelCount();
    std::vector<size_t> use;
    use.reserve(count);
    for (int attempt = 0; attempt < 2 && use.empty(); ++attempt)
        for (size_t i = 0; i < count; ++i)
            if (finiteRgb(test, i) && finiteRgb(reference, i) &&
                (attempt == 1 || reference.rgba[i * 4 + 3] >= minReferenceAlpha))
                use.push_back(i);
    RelErrorSpread s;
    s.pixels = use.size();
    if (use.empty()) {
        s.p50 = s.p95 = s.ratio = s.eps = std::numeric_limits<double>::quiet_NaN();
        return s;
    }
    double mean = 0;
    for (size_t i : use)
        for (int c = 0; c < 3; ++c) mean += reference.rgba[i * 4 + c];
    mean /= 3.0 * double(use.size());
    // A fraction of the mean rather than an absolute constant, so the figure
    // does not depend on the scene's brightness or exposure.
    s.eps = mean > 0 ? RelSpreadEpsilonFraction * mean : RelEpsilon;
    std::vector<double> err;
    err.reserve(use.size());
    for (size_t i : use) {
        double e = 0;
        for (int c = 0; c < 3; ++c) {
            double a = test.rgba[i * 4 + c], b = reference.rgba[i * 4 + c];
            e += std::abs(a - b) / (std::abs(b) + s.eps);
        }
        err.push_back(e / 3.0);
    }
    auto percentile = [&](double p) {
        size_t rank = size_t(std::max(1.0, std::ceil(p * double(err.size())))) - 1;
        std::nth_element(err.begin(), err.begin() + rank, err.end());
        return err[rank];
    };
    s.p50 = percentile(0.50);
    s.p95 = percentile(0.95);
    s.ratio = s.p95 == 0 ? 0.0 : s.p50 == 0 ? std::numeric_limits<double>::infinity() : s.p95 / s.p50;
    return s;
}

PairedAgreement pairedAgreement(const Image& test, const Image& reference) {
    checkSameSize(test, reference);
    PairedAgreement out;
    const int W = reference.width, H = reference.height;
    for (int q = 0; q < PairedAgreement::Regions; ++q) {
        const int x0 = q == 0 ? 0 : ((q - 1) % 2) * (W / 2), y0 = q == 0 ? 0 : ((q - 1) / 2) * (H / 2);
        const int w = q == 0 ? W : (q - 1) % 2 ? W - W / 2 : W / 2, h = q == 0 ? H : (q - 1) / 2 ? H - H / 2 : H / 2;
        for (int c = 0; c < PairedAgreement::Channels; ++c) {
            double sum = 0, sum2 = 0;
            size_t n = 0;
            for (int y = y0; y < y0 + h; ++y)
                for (int x = x0; x < x0 + w; ++x) {
                    const size_t i = 4 * (size_t(y) * size_t(W) + size_t(x));
                    const double d = double(test.rgba[i + size_t(c)]) - double(reference.rgba[i + size_t(c)]);
                    if (!std::isfinite(d)) continue;
                    sum += d;
                    sum2 += d * d;
                    ++n;
                }
            if (n < 2) continue;
            const double mean = sum / double(n);
            const double var = std::max(0.0, (sum2 - sum * mean) / double(n - 1));
            const double se = std::sqrt(var / double(n));
            const double z = se > 0 ? mean / se : 0.0;
            out.z[q][c] = z;
            if (std::abs(z) > out.maxAbsZ) out.maxAbsZ = std::abs(z), out.region = q, out.channel = c;
        }
    }
    return out;
}

double lowFrequencyError(const Image& test, const Image& reference, int block) {
    checkSameSize(test, reference);
    double se = 0, refSum = 0;
    size_t blocks = 0, pixels = 0;
    for (int by = 0; by < reference.height; by += block)
        for (int bx = 0; bx < reference.width; bx += block) {
            double a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
            int n = 0;
            for (int y = by; y < std::min(by + block, reference.height); ++y)
                for (int x = bx; x < std::min(bx + block, reference.width); ++x) {
                    const Color ta = test.rgb(x, y), rb = reference.rgb(x, y);
                    if (!isFinite(ta) || !isFinite(rb)) continue;
                    for (int c = 0; c < 3; ++c) {
                        a[c] += ta[c];
                        b[c] += rb[c];
                    }
                    ++n;
                }
            if (n == 0) continue;
            for (int c = 0; c < 3; ++c) {
                const double d = (a[c] - b[c]) / n;
                se += d * d;
                refSum += b[c];
            }
            blocks += 3;
            pixels += size_t(n);
        }
    const double mean = pixels ? refSum / (3.0 * double(pixels)) : 0.0;
    if (!(mean > 0) || blocks == 0) return std::nan("");
    return std::sqrt(se / double(blocks)) / mean;
}

void writeFalseColorDiff(const std::string& path, const Image& test, const Image& reference) {
    checkSameSize(test, reference);
    const size_t count = test.pixelCount();
    // Negative marks a pixel that is non-finite in either image.
    std::vector<double> err(count, -1.0);
    std::vector<double> finiteErr;
    finiteErr.reserve(count);
    for (size_t i = 0; i < count; ++i) {
        if (!finiteRgb(test, i) || !finiteRgb(reference, i)) continue;
        double e = 0;
        for (int c = 0; c < 3; ++c) e += std::abs(double(test.rgba[i * 4 + c]) - reference.rgba[i * 4 + c]);
        err[i] = e / 3.0;
        finiteErr.push_back(err[i]);
    }

    double scale = 0;
    if (!finiteErr.empty()) {
        // Nearest-rank 99th percentile; fall back to the maximum when more than
        // 99% of pixels match exactly, so the few differing ones still show.
        size_t rank = size_t(std::ceil(0.99 * double(finiteErr.size()))) - 1;
        std::nth_element(finiteErr.begin(), finiteErr.begin() + rank, finiteErr.end());
        scale = finiteErr[rank];
        if (scale <= 0) scale = *std::max_element(finiteErr.begin(), finiteErr.end());
    }

    std::vector<uint8_t> rgb(count * 3);
    for (size_t i = 0; i < count; ++i) {
        uint8_t* p = &rgb[i * 3];
        if (err[i] < 0) {
            p[0] = 255; p[1] = 0; p[2] = 255;
        } else {
            viridisColor(scale > 0 ? err[i] / scale : 0.0, p);
        }
    }
    writePngRgb8(path, test.width, test.height, rgb);
}

}  // namespace vdbmarch
