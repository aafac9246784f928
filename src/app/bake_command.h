// `vdbmarch bake`: trace photons and write the radiance cache to a .vdb.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "app/command_line.h"

namespace vdbmarch {

struct BakeArgs {
    std::string input, output, stats;
    bool adaptive = false, uniform = false, quiet = false;
    std::vector<std::string> sets;  // --set key.path=value
    std::string frames;             // --frames A-B[:STEP] or N (parse/frames.h); empty: no frames
    // Scene overrides (bakeSceneOptions); unset ones keep the scene's values.
    std::optional<long long> photons, seed;
    std::optional<int> k, shOrder, threads;
    std::optional<double> quality, minCell;
};

// The options of `bake` that override scene keys (--photons -> photons.count, ...).
const SceneOptionTable<BakeArgs>& bakeSceneOptions();

// Bakes once, or a cache per frame of --frames.
int runBake(const BakeArgs& args);

}  // namespace vdbmarch
