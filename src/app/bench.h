// Run time against error: renders methods at a series of budgets and measures
// each image against a reference (vdbmarch bench).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "image/image.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

struct BenchOptions {
    std::vector<std::string> methods;  // marchers, or "vdb_render" (OpenVDB's renderer)
    std::vector<double> budgets;  // spp, or seconds when budgetSeconds
    std::vector<double> vdbRenderSteps{4, 2, 1, 0.5};  // the budgets of vdb_render: its step in voxels
    bool budgetSeconds = false;
    std::string outDir;
    std::string referencePath;  // given reference EXR; empty: render and cache one
    int referenceSpp = 256;     // for a rendered reference
    int repeats = 1;            // runs per point (median time)
    // Image strip (the paper's figure 5): one row per method, one column per
    // budget (the i-th budget of each method's list), the image of the
    // median-time run tone mapped as the PNG preview (render.exposure).
    std::string stripPath;       // .png; empty: no strip
    bool stripReference = true;  // leftmost column: the reference
    int stripMaxWidth = 2000;    // tiles are box-downscaled so the strip fits
};

// Strip layout: StripSeparator pixels of StripSeparatorValue between tiles,
// StripReferenceGap after the reference column; a method with fewer budgets
// than columns leaves its last tiles in the separator colour.
constexpr int StripSeparator = 2;
constexpr int StripReferenceGap = 6;
constexpr uint8_t StripSeparatorValue = 255;

// The error spread is measured where the reference sees the medium or a
// surface (alpha = 1 - transmittance), not over the background, which every
// method renders exactly and would pull the median to 0.
constexpr float BenchSpreadMinAlpha = 0.01f;

struct BenchRow {
    std::string method;
    double budget = 0, seconds = 0, rmse = 0, relMse = 0;
    int spp = 0;
    // Per-pixel relative error percentiles (relativeErrorSpread in image/metrics.h).
    double relP50 = 0, relP95 = 0, relSpread = 0;  // relSpread = relP95 / relP50
    // RMSE of 8x8 block means over the reference mean (lowFrequencyError):
    // bias and blotches, not pixel noise.
    double lowFreq = 0;
};

struct BenchResult {
    std::vector<BenchRow> rows;
    std::string referenceImage;     // which image served as reference
    double referenceNoiseRmse = 0;  // its own estimated noise (0 when given)
    double referenceNoiseLowFreq = 0;  // ... as low-frequency error
    double spreadEps = 0;           // epsilon of the relative error
    size_t spreadPixels = 0;        // pixels the spread is measured over
    std::string csvPath, tablePath, plotPath;
    std::string stripPath;          // empty when not asked for
    int stripRows = 0, stripColumns = 0, tileWidth = 0, tileHeight = 0;
};

// Renders, measures and writes bench.csv, bench.md and (with gnuplot) bench.png
// in options.outDir, and the strip when asked for. Progress lines go to stderr.
BenchResult runBench(const SceneDesc& scene, const BenchOptions& options);

// Area-weighted box filter to width x height (each output pixel averages the
// input pixels it covers, in linear RGBA); non-finite values count as 0, as in
// the PNG preview.
Image downscaleBox(const Image& img, int width, int height);

}  // namespace vdbmarch
