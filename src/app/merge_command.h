// `vdbmarch merge`: tiles of one render (render --tile / --crop) into the
// whole frame, checked to belong together (app/tiles.h).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace vdbmarch {

struct MergeArgs {
    std::vector<std::string> tiles;
    std::string output, png;
    std::optional<double> exposure;  // PNG exposure in stops (default: the scene's render.exposure)
    bool quiet = false;
};

int runMerge(const MergeArgs& args);

}  // namespace vdbmarch
