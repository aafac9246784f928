// Run time against error: renders methods at a series of budgets and measures
// each image against a reference (vdbmarch bench).
#pragma once

#include <string>
#include <vector>

#include "scene/scene_desc.h"

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
};

struct BenchRow {
    std::string method;
    double budget = 0, seconds = 0, rmse = 0, relMse = 0;
    int spp = 0;
};

struct BenchResult {
    std::vector<BenchRow> rows;
    std::string referenceImage;     // which image served as reference
    double referenceNoiseRmse = 0;  // its own estimated noise (0 when given)
    std::string csvPath, tablePath, plotPath;
};

// Renders, measures and writes bench.csv, bench.md and (with gnuplot) bench.png
// in options.outDir. Progress lines go to stderr.
BenchResult runBench(const SceneDesc& scene, const BenchOptions& options);

}  // namespace vdbmarch
