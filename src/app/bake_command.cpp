#include "app/bake_command.h"

#include <cstdio>
#include <memory>

#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/threads.h"
#include "illumination/bake.h"
#include "parse/frames.h"
#include "scene/scene.h"

namespace vdbmarch {

const SceneOptionTable<BakeArgs>& bakeSceneOptions() {
    static const SceneOptionTable<BakeArgs> table = {
        {"--photons", "photons.count", "Photon paths to trace (scene key photons.count)", &BakeArgs::photons},
        {"--k", "photons.k", "Photons per estimate (photons.k)", &BakeArgs::k},
        {"--quality", "cache.quality", "Grid quality a of s = (aN/(k V))^(1/3) (cache.quality)", &BakeArgs::quality},
        {"--sh-order", "cache.sh_order", "Spherical-harmonics order K, 0-8 (cache.sh_order)", &BakeArgs::shOrder},
        {"--min-cell", "cache.min_cell", "Smallest adaptive cell in world units (cache.min_cell)", &BakeArgs::minCell},
        {"--seed", "render.seed", "Random seed", &BakeArgs::seed},
        {"--threads", "render.threads", "Worker threads (0 = all cores)", &BakeArgs::threads},
    };
    return table;
}

namespace {

// Timings, counts and memory of a finished bake (--stats).
std::string statsJson(const BakeResult& r, int threads) {
    const RadianceCache& c = r.cache;
    nlohmann::json s;
    s["seconds"] = {{"trace", r.traceSeconds}, {"kd_tree", r.treeSeconds}, {"topology", r.topologySeconds},
                    {"estimate", r.estimateSeconds}, {"total", r.totalSeconds}};
    s["threads"] = threads;
    s["photon_paths"] = r.paths;
    s["photons"] = c.info.photons;
    s["direct_photons"] = r.directPhotons;
    s["cells"] = c.cells.size();
    s["levels"] = c.levels;
    s["sh_order"] = c.info.shOrder;
    s["bytes"] = {{"photon_map", r.photonBytes}, {"cache", r.cacheBytes}};
    return s.dump(2) + "\n";
}

// One bake: the whole command for one frame (`frame` set by --frames, its
// paths already substituted in `a`) or without frames.
int bakeFrame(const BakeArgs& a, std::optional<int> frame) {
    if (!endsWith(a.output, ".vdb")) throw InputError(str("-o ", a.output, ": the cache must be a .vdb file"));
    if (!a.stats.empty() && !endsWith(a.stats, ".json"))
        throw InputError(str("--stats ", a.stats, ": the statistics file must be a .json file"));
    if (a.adaptive && a.uniform) throw InputError("--adaptive and --uniform both given");
    checkWritable(a.output);
    if (!a.stats.empty()) checkWritable(a.stats);
    // Options are overrides of the scene's "photons" and "cache" keys, so
    // the scene parser validates them like any other key.
    std::vector<std::string> overrides = a.sets;
    appendSceneOverrides(a, bakeSceneOptions(), overrides);
    if (a.adaptive) overrides.push_back("cache.adaptive=true");
    if (a.uniform) overrides.push_back("cache.adaptive=false");
    SceneDesc desc = loadSceneInput(a.input, overrides, frame);
    std::unique_ptr<Scene> scene = buildScene(desc);
    const int threads = resolveThreadCount(desc.render.threads);
    tbb::task_arena arena(threads);
    BakeResult r;
    arena.execute([&] { r = bakeRadianceCache(*scene, desc.photons, desc.cache); });
    r.cache.save(a.output);
    if (!a.stats.empty()) writeTextFileAtomic(a.stats, statsJson(r, threads));
    const RadianceCache& c = r.cache;
    if (!a.quiet)
        std::fprintf(stderr,
                     "vdbmarch: %zu photon paths -> %llu photons (%zu direct) in %.3f s; kd-tree %.3f s; %zu cells "
                     "(%d level(s), SH order %d) in %.3f s; total %.3f s -> %s\n",
                     r.paths, static_cast<unsigned long long>(c.info.photons), r.directPhotons, r.traceSeconds,
                     r.treeSeconds, c.cells.size(), c.levels, c.info.shOrder,
                     r.topologySeconds + r.estimateSeconds,
                     r.totalSeconds, a.output.c_str());
    return 0;
}

}  // namespace

// --frames: a cache per frame, each baked as if alone (docs/farm.md, "Frames").
int runBake(const BakeArgs& a) {
    const std::vector<std::pair<std::string, std::string>> outputs = {{"-o", a.output}, {"--stats", a.stats}};
    if (a.frames.empty()) {
        checkFrameOutputs(outputs, 0, "");
        return bakeFrame(a, std::nullopt);
    }
    const std::vector<int> frames = parseFrameRange(a.frames);
    checkFrameOutputs(outputs, frames.size(), a.frames);
    checkFrameInputs(a.input, a.sets, frames);
    for (int frame : frames)
        runFrame(frame, [&] {
            BakeArgs f = a;
            f.output = substituteFrame(a.output, frame);
            f.stats = substituteFrame(a.stats, frame);
            bakeFrame(f, frame);
        });
    return 0;
}

}  // namespace vdbmarch
