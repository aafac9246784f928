// `vdbmarch compare`: error metrics of a test image against a reference.
#pragma once

#include <string>

namespace vdbmarch {

struct CompareArgs {
    std::string test, reference;
    std::string diff;  // false-colour difference PNG; empty: none
};

int runCompare(const CompareArgs& args);

}  // namespace vdbmarch
