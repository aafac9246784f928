// The media of a region at one point: summed coefficients, emission and the
// phase mixture; and the union of the region's active intervals along a ray
// (empty space skipping).
#pragma once

#include <vector>

#include "transport/phase.h"
#include "transport/thread_context.h"

namespace vdbmarch {

// Each medium's coefficients are clamped to MaxCoefficient so sums stay finite.
constexpr float MaxCoefficient = 1e30f;

struct MediumPoint {
    Color sigma_a, sigma_s, sigma_t;
    Color emission;  // L_e averaged with weights sigma_a,i (sigma_a L_e / sigma_a)
    PhaseMixture phase;
    bool scatters() const { return !phase.empty(); }
};

void evalMedia(ThreadContext& ctx, int region, const Vec3& p, MediumPoint& mp);

// Sorted, merged union of the active intervals of the region's media within
// [tMin, tMax].
void regionIntervals(ThreadContext& ctx, int region, const Ray& r, float tMin, float tMax,
                     std::vector<Interval>& out);

}  // namespace vdbmarch
