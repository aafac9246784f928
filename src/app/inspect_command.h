// `vdbmarch inspect`: summarise a baked cache, or write L_i for a direction
// (.vdb) or a false-colour slice (.png).
#pragma once

#include <string>

namespace vdbmarch {

struct InspectArgs {
    std::string input, direction, slice, output;
};

int runInspect(const InspectArgs& args);

}  // namespace vdbmarch
