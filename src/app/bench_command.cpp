#include "app/bench_command.h"

#include <cstdio>

#include "app/command_line.h"
#include "parse/method.h"

namespace vdbmarch {

int runBenchCommand(const BenchArgs& a) {
    std::vector<std::string> overrides = a.sets;
    if (!a.res.empty()) overrides.push_back(resolutionOverride(a.res));
    SceneDesc desc = loadSceneInput(a.scene, overrides);
    BenchOptions o = a.options;
    o.methods = splitList(a.methods);
    for (const auto& m : o.methods) {
        Method known;
        if (m != "vdb_render" && m != "auto" && !parseMethod(m, known))
            throw InputError(str("--methods: unknown method \"", m, "\""));
    }
    o.budgets = parseNumberList(a.budgets, "--budgets");
    o.vdbRenderSteps = parseNumberList(a.vdbSteps, "--vdb-render-steps");
    if (o.referenceSpp < 2) throw InputError(str("--reference-spp ", o.referenceSpp, ": must be at least 2"));
    if (o.repeats < 1) throw InputError(str("--repeats ", o.repeats, ": must be at least 1"));
    if (!o.stripPath.empty() && !endsWith(o.stripPath, ".png"))
        throw InputError(str("--strip ", o.stripPath, ": the strip must be a .png file"));
    if (o.stripMaxWidth < 1)
        throw InputError(str("--strip-width ", o.stripMaxWidth, ": must be a positive number of pixels"));
    o.stripReference = !a.stripNoReference;
    BenchResult r = runBench(desc, o);
    std::printf("reference: %s", r.referenceImage.c_str());
    if (r.referenceNoiseRmse > 0) std::printf(" (estimated noise RMSE %.5g)", r.referenceNoiseRmse);
    std::printf("\nwrote %s, %s%s%s%s%s\n", r.csvPath.c_str(), r.tablePath.c_str(), r.plotPath.empty() ? "" : ", ",
                r.plotPath.c_str(), r.stripPath.empty() ? "" : ", ", r.stripPath.c_str());
    return 0;
}

}  // namespace vdbmarch
