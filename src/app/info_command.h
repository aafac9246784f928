// `vdbmarch info`: the grids of a .vdb file and a summary of its density grid.
#pragma once

#include <string>
#include <vector>

namespace vdbmarch {

struct InfoArgs {
    std::string file;
};

int runInfo(const InfoArgs& args);

// `vdbmarch check FILE...`: reads every grid of each VDB file fully, in a
// separate process (app/vdb_check.h), and says which are damaged or cut
// short. --in-process reads in this process (what the separate one runs).
struct CheckArgs {
    std::vector<std::string> files;
    bool inProcess = false;
    bool quiet = false;
};

int runCheck(const CheckArgs& args);

}  // namespace vdbmarch
