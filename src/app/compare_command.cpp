#include "app/compare_command.h"

#include <cstdio>

#include "core/atomic_file.h"
#include "image/exr_io.h"
#include "image/metrics.h"

namespace vdbmarch {

int runCompare(const CompareArgs& a) {
    if (!a.diff.empty()) checkWritable(a.diff);
    Image ia = readExr(a.test), ib = readExr(a.reference);
    ImageErrorStats s = compareImages(ia, ib);
    std::printf("rmse %.6g\nrelmse %.6g\nmean_abs_rel_error %.6g\nmean_test %.6g\nmean_reference %.6g\n"
                "rmse_over_mean %.6g\nlow_frequency_error %.6g\nnonfinite_test %zu\nnonfinite_reference %zu\npixels %zu\n",
                s.rmse, s.relMse, s.meanAbsRelError, s.meanA, s.meanB, s.meanB != 0 ? s.rmse / s.meanB : 0.0,
                lowFrequencyError(ia, ib), s.nonFiniteA, s.nonFiniteB, s.pixels);
    if (!a.diff.empty()) writeFalseColorDiff(a.diff, ia, ib);
    return 0;
}

}  // namespace vdbmarch
