// `vdbmarch bench`: the command-line side of the benchmark harness
// (app/bench.h): checks the options and prints where the results went.
#pragma once

#include <string>
#include <vector>

#include "app/bench.h"

namespace vdbmarch {

struct BenchArgs {
    std::string scene, res;
    // Comma-separated lists, parsed into options.methods, budgets and vdbRenderSteps.
    std::string methods = "uniform,reference", budgets = "1,2,4,8", vdbSteps = "4,2,1,0.5";
    bool stripNoReference = false;
    std::vector<std::string> sets;  // --set key.path=value
    // -o, --seconds, --reference, --reference-spp, --repeats, --strip and
    // --strip-width set these directly.
    BenchOptions options;
};

int runBenchCommand(const BenchArgs& args);

}  // namespace vdbmarch
