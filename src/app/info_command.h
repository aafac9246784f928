// `vdbmarch info`: the grids of a .vdb file and a summary of its density grid.
#pragma once

#include <string>

namespace vdbmarch {

struct InfoArgs {
    std::string file;
};

int runInfo(const InfoArgs& args);

}  // namespace vdbmarch
