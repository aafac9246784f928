// The denoiser's entry point: the input checked, the emitted part split off
// where it needs it, and each image denoised by the steps of docs/denoise.md
// (denoise_filters, denoise_features and denoise_selection).
#include "denoise/denoise.h"

#include "core/error.h"
#include "core/threads.h"
#include "denoise/denoise_features.h"
#include "denoise/denoise_filters.h"
#include "denoise/denoise_planes.h"
#include "denoise/denoise_selection.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace vdbmarch {

namespace {

using namespace denoising;

// An emitted part (DenoiseInput::emittedA/B) whose halves differ by at most
// this share of the image's half-difference variance is added unfiltered.
constexpr double EmittedNoiseShare = 0.05;

void checkSize(size_t size, size_t pixels, const char* name, bool optional) {
    if (size == pixels || (optional && size == 0)) return;
    throw std::invalid_argument(str("denoise: ", name, " has ", size, " entries, expected ", pixels,
                                    optional ? " (or none)" : ""));
}

void checkOptions(const DenoiseOptions& o) {
    auto radius = [](int r, const char* name) {
        if (r < 0 || r > 32) throw std::invalid_argument(str("denoise: ", name, " ", r, " is outside [0, 32]"));
    };
    auto positive = [](float v, const char* name) {
        if (!(v > 0) || !finite(v)) throw std::invalid_argument(str("denoise: ", name, " ", v, " must be positive"));
    };
    if (o.threads < 0) throw std::invalid_argument(str("denoise: threads ", o.threads, " is negative"));
    radius(o.searchRadius, "searchRadius");
    radius(o.patchRadius, "patchRadius");
    radius(o.varianceRadius, "varianceRadius");
    radius(o.featureSearchRadius, "featureSearchRadius");
    radius(o.featurePatchRadius, "featurePatchRadius");
    positive(o.colorStrength, "colorStrength");
    if (o.candidates < 1 || o.candidates > 4)
        throw std::invalid_argument(str("denoise: candidates ", o.candidates, " is outside [1, 4]"));
    radius(o.selectionRadius, "selectionRadius");
    if (!(o.regressionRidge >= 0) || !finite(o.regressionRidge))
        throw std::invalid_argument(str("denoise: regressionRidge ", o.regressionRidge, " must be >= 0"));
    if (!(o.regressionNoiseRidge >= 0) || !finite(o.regressionNoiseRidge))
        throw std::invalid_argument(str("denoise: regressionNoiseRidge ", o.regressionNoiseRidge, " must be >= 0"));
    positive(o.featureStrength, "featureStrength");
    positive(o.featureThreshold, "featureThreshold");
    positive(o.featurePrefilterStrength, "featurePrefilterStrength");
    auto sigma = [](float v, const char* name) {
        if (!(v >= 0 && v <= 64)) throw std::invalid_argument(str("denoise: ", name, " ", v, " is outside [0, 64]"));
    };
    sigma(o.restoreSigma, "restoreSigma");
    sigma(o.fireflySigma, "fireflySigma");
}

// Throws std::invalid_argument on a bad size or option (denoise()'s contract).
void checkInput(const DenoiseInput& in, const DenoiseOptions& options) {
    if (in.width < 0 || in.height < 0)
        throw std::invalid_argument(str("denoise: invalid frame size ", in.width, "x", in.height));
    checkOptions(options);
    const size_t pixels = size_t(in.width) * size_t(in.height);
    checkSize(in.halfA.size(), pixels, "halfA", false);
    checkSize(in.halfB.size(), pixels, "halfB", false);
    auto pair = [&](size_t a, size_t b, const char* nameA, const char* nameB) {
        checkSize(a, pixels, nameA, true);
        checkSize(b, pixels, nameB, true);
        if ((a == 0) != (b == 0))
            throw std::invalid_argument(str("denoise: ", nameA, " and ", nameB, " must both be given or both be empty"));
    };
    pair(in.alphaA.size(), in.alphaB.size(), "alphaA", "alphaB");
    pair(in.emittedA.size(), in.emittedB.size(), "emittedA", "emittedB");
    checkSize(in.albedo.size(), pixels, "albedo", true);
    checkSize(in.normal.size(), pixels, "normal", true);
    checkSize(in.depth.size(), pixels, "depth", true);
}


// The selected planes as an RGBA image (opaque without alpha).
void writeImage(const std::vector<Plane>& selected, int channels, Image& out) {
    forEachRow(out.height, [&](int y) {
        for (int x = 0; x < out.width; ++x) {
            float value[4] = {0, 0, 0, 1};
            for (int c = 0; c < channels; ++c) value[c] = selected[size_t(c)].at(x, y);
            out.set(x, y, Color(value[0], value[1], value[2]), value[3]);
        }
    });
}

// The whole algorithm on one image (its emitted part, if any, ignored);
// `in` already checked.
Image denoiseWhole(const DenoiseInput& in, const DenoiseOptions& options, std::vector<float>* variances) {
    const int w = in.width, h = in.height;
    const size_t pixels = size_t(w) * size_t(h);
    Image out(w, h);
    if (pixels == 0) return out;

    const int pad = std::max({options.patchRadius, options.featurePatchRadius, 1});
    tbb::task_arena arena(resolveThreadCount(options.threads));
    arena.execute([&] {
        const ColourHalves halves = loadColourHalves(in, options, pad);        // steps 1, 2 and 8
        const std::vector<Feature> features = loadFeatures(in, options, pad);  // step 3
        Candidates candidates = filterCandidates(halves, features, options);   // steps 4 to 7
        // The variance estimate alone takes the selection's path, with one candidate too.
        Plane ownWeight;
        std::vector<Plane> selected =
            candidates.filtered.size() == 1 && !variances
                ? std::move(candidates.filtered[0])
                : selectCandidates(candidates.filtered, candidates.inverse, halves.clamped, halves.variance,
                                   options.selectionRadius, variances ? &ownWeight : nullptr);
        if (variances) estimateOutputVariance(halves.variance, ownWeight, options.restoreSigma, *variances);
        restoreLocalMeans(selected, halves.clamped, halves.clampedLight, options);
        writeImage(selected, halves.channels, out);
    });
    return out;
}

}  // namespace

Image denoise(const DenoiseInput& in, const DenoiseOptions& options, std::vector<float>* variances) {
    checkInput(in, options);
    const size_t pixels = size_t(in.width) * size_t(in.height);
    // Nothing emitted anywhere (or no emitted part): the whole image as one,
    // bit for bit what no emitted part gives.
    auto zero = [](const Color& c) { return c.x == 0 && c.y == 0 && c.z == 0; };
    if (std::all_of(in.emittedA.begin(), in.emittedA.end(), zero) &&
        std::all_of(in.emittedB.begin(), in.emittedB.end(), zero))
        return denoiseWhole(in, options, variances);
    // The scattered light (each half minus its emitted part) and the emitted
    // part, each denoised on its own with the same alpha and features; the
    // image is their sum, its alpha the scattered part's.
    DenoiseInput scattered = in, emitted = in;
    for (size_t p = 0; p < pixels; ++p) {
        scattered.halfA[p] = in.halfA[p] - in.emittedA[p];
        scattered.halfB[p] = in.halfB[p] - in.emittedB[p];
    }
    emitted.halfA = in.emittedA;
    emitted.halfB = in.emittedB;
    // The scattered part alone is a smooth glow, over which NL-means moves
    // light at scales the restoring Gaussian of step 9 leaves: restored at
    // half its sigma (docs/denoise.md, "Emission apart").
    DenoiseOptions scatteredOptions = options;
    scatteredOptions.restoreSigma = 0.5f * options.restoreSigma;
    Image out = denoiseWhole(scattered, scatteredOptions, variances);
    // The emitted part is filtered only where its noise counts: the
    // marchers integrate emission along the camera ray nearly noise-free,
    // and NL-means leaves such a part as it is, at the cost of a second
    // denoise (BENCHMARKS.md). Then its halves' mean is added as it is.
    // Non-finite values always go through the filter, which cleans them.
    double emittedNoise = 0, imageNoise = 0;
    for (size_t p = 0; p < pixels; ++p) {
        emittedNoise += double(lengthSquared(in.emittedA[p] - in.emittedB[p]));
        imageNoise += double(lengthSquared(in.halfA[p] - in.halfB[p]));
    }
    if (std::isfinite(emittedNoise) && std::isfinite(imageNoise) && emittedNoise <= EmittedNoiseShare * imageNoise) {
        for (size_t p = 0; p < pixels; ++p) {
            const Color e = 0.5f * (in.emittedA[p] + in.emittedB[p]);
            for (int c = 0; c < 3; ++c) out.rgba[4 * p + size_t(c)] += e[c];
            // The emitted mean's own variance, (A - B)^2 / 4 per channel.
            if (variances) (*variances)[p] += 0.25f * lengthSquared(in.emittedA[p] - in.emittedB[p]);
        }
        return out;
    }
    std::vector<float> emittedVariances;
    const Image e = denoiseWhole(emitted, options, variances ? &emittedVariances : nullptr);
    for (size_t p = 0; p < out.pixelCount(); ++p) {
        for (int c = 0; c < 3; ++c) out.rgba[4 * p + size_t(c)] += e.rgba[4 * p + size_t(c)];
        if (variances) (*variances)[p] += emittedVariances[p];
    }
    return out;
}

}  // namespace vdbmarch
