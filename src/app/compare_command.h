// `vdbmarch compare`: error metrics of a test image against a reference.
#pragma once

#include <string>

namespace vdbmarch {

struct CompareArgs {
    std::string test, reference;
    std::string diff;  // false-colour difference PNG; empty: none
    // Exit 0 when both files hold bit-identical pixels in every channel and
    // the same windows, 1 otherwise (tiled renders against one process).
    bool identical = false;
};

int runCompare(const CompareArgs& args);

}  // namespace vdbmarch
