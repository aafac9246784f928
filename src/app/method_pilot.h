// render.method "auto" in a timed render: the method chosen by measurement
// (docs/method.md, "The automatic method"). Each candidate (the rule's pick
// of parse/auto_method.h, then the other of the path tracer and the guided
// marcher) renders a short pilot of the frame; the one whose noise at the
// end of the budget, predicted from its pilot's half-buffer variance, is
// lowest goes on from its pilot's samples. At a check a third of the way
// through, the pick's noise is measured again over its many more samples,
// which also says how fast it falls (a pilot can miss rare, bright paths),
// and the other resumes from its own pilot instead if it now predicts less. The rule stays the prior: the
// other candidate must predict less than PilotMargin of the pick's noise
// variance to take over.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "render/render.h"

namespace vdbmarch {

// The share of the time budget each candidate's pilot takes.
constexpr double PilotShare = 0.05;
// When the pick's noise is measured again, as a share of the budget.
constexpr double PilotCheckShare = 0.35;
// The other candidate takes over only below this share of the pick's
// predicted noise variance.
constexpr double PilotMargin = 0.7;

struct PilotMeasurement {
    Method method;
    int samples = 0;             // per pixel, when measured (the most any pixel had)
    double meanSamples = 0;      // per pixel, on average
    double seconds = 0;          // spent rendering it (its photons and cache included)
    double setupSeconds = 0;     // its first photons and cache (RenderCheckpoint::setupSeconds)
    double rmse = 0;             // its noise estimate then (NoiseEstimate::rmse)
    // Its noise falls as samples^-fall: 0.5 (finite variance) until a
    // second measurement tells (heavy tails fall slower).
    double fall = 0.5;
    double predictedRmse = 0;    // at the end of the budget
};

struct MethodPilot {
    std::vector<PilotMeasurement> measured;  // the pilots, then the pick's check
    Method method;                           // what rendered the image
    std::string reason;                      // for render.methodReason
};

// Renders `scene` with the method pilots pick (its desc.render.method is
// left at it), with the render's own options (a whole-frame timed render
// without checkpoints; the budget counts from options.runStart). Without a
// noise estimate from either pilot, the rule's pick renders the rest.
RenderResult renderByPilots(Scene& scene, const RenderOptions& options, MethodPilot& out);

// "reference 31 spp in 0.8 s, noise 0.012 -> 0.0031 predicted; ..." for the log.
std::string describePilot(const MethodPilot& p);

}  // namespace vdbmarch
