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
    // Measure this layer of the test image (R, G, B, and A where it has
    // one) instead of its RGBA: `noisy`, the raw beauty of a denoised render.
    std::string layer;
    // Report pairedAgreement (image/metrics.h) and exit 1 when some region
    // and channel differ by more than 4 standard errors.
    bool paired = false;
};

int runCompare(const CompareArgs& args);

}  // namespace vdbmarch
