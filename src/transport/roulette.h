// Russian roulette, the one rule every path loop uses: a path whose
// throughput (relative to where it started) fell below `threshold` goes on
// with probability maxComponent(beta) / threshold and is reweighted by its
// inverse, so the estimate stays unbiased while dim paths end early.
#pragma once

#include <algorithm>

#include "core/math.h"
#include "core/rng.h"

namespace vdbmarch {

// Camera paths and shadow-ray ratio tracking: end paths whose weight is
// negligible (1e-3 of the light they started with).
constexpr float RouletteThreshold = 1e-3f;
// Scattering paths past RouletteMinDepth events (the reference tracer and
// photons): survive with probability equal to the throughput, so a path's
// weight stays near its start (photon powers stay even).
constexpr float ScatterRouletteThreshold = 1.f;
constexpr int RouletteMinDepth = 3;

// Probability that a path of throughput beta goes on (1 at or above the
// threshold, 0 for a black or non-finite throughput).
inline float rouletteSurvival(const Color& beta, float threshold = RouletteThreshold) {
    const float m = maxComponent(beta);
    if (!(m > 0)) return 0.f;
    return m >= threshold ? 1.f : m / threshold;
}

// Draws a uniform only when the throughput is below the threshold; divides
// beta by the survival probability. Returns false when the path ends. The
// path is judged by beta x judgedScale (PathState::rouletteScale: the
// throughput f's own sampling would have left it); any survival
// probability keeps the estimate unbiased.
inline bool russianRoulette(Color& beta, Rng& rng, float threshold = RouletteThreshold, float judgedScale = 1) {
    const float q = rouletteSurvival(beta * judgedScale, threshold);
    if (q >= 1) return true;
    if (!(q > 0) || rng.uniform() >= q) return false;
    beta /= q;
    return true;
}

// The same rule for a scalar weight: a light sample whose MIS weight is
// below MisWeightRouletteThreshold casts its shadow ray with probability
// w / threshold and then counts the threshold (light_distances.h).
constexpr float MisWeightRouletteThreshold = 0.25f;
inline bool russianRoulette(float& w, Rng& rng, float threshold) {
    Color c(w);
    const bool on = russianRoulette(c, rng, threshold);
    w = c.x;
    return on;
}

}  // namespace vdbmarch
