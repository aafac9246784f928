// Named counters, accumulated per thread and summed after a render (integer
// sums, so totals do not depend on the thread count).
#pragma once

#include <cstdint>

namespace vdbmarch {

struct RenderCounters {
    uint64_t cameraRays = 0;        // camera paths started (pixels x spp)
    uint64_t surfaceHits = 0;       // surface interactions along camera paths
    uint64_t marchSamples = 0;      // medium samples along camera rays
    uint64_t liSamples = 0;         // points where L_i was estimated
    uint64_t shadowRays = 0;        // shadow rays traced
    uint64_t shadowSamples = 0;     // medium samples along shadow rays
    uint64_t nonFiniteSamples = 0;  // NaN/Inf path results dropped
    double marchedLength = 0;       // camera-ray length inside active intervals
    double skippedLength = 0;       // camera-ray length skipped as empty space

    RenderCounters& operator+=(const RenderCounters& o) {
        cameraRays += o.cameraRays;
        surfaceHits += o.surfaceHits;
        marchSamples += o.marchSamples;
        liSamples += o.liSamples;
        shadowRays += o.shadowRays;
        shadowSamples += o.shadowSamples;
        nonFiniteSamples += o.nonFiniteSamples;
        marchedLength += o.marchedLength;
        skippedLength += o.skippedLength;
        return *this;
    }
};

}  // namespace vdbmarch
