#include "app/method_pilot.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>

#include "core/error.h"

namespace vdbmarch {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

Clock::time_point plusSeconds(Clock::time_point t, double s) {
    return t + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// A render from `from` (null: the start) that stops at the first sample
// boundary where `stop` says so, keeping its state; or the whole render,
// where it ends first (or `stop` is empty).
struct Stage {
    RenderResult result;
    std::optional<RenderCheckpoint> state;  // where it stopped
};

Stage renderStage(const Scene& scene, RenderOptions o, const RenderCheckpoint* from, std::function<bool()> stop) {
    std::optional<RenderCheckpoint> saved;
    CheckpointHooks hooks;
    hooks.everySeconds = Infinity;
    hooks.resume = from;
    if (stop) {
        hooks.stopRequested = std::move(stop);
        hooks.save = [&saved](const RenderCheckpoint& c) { saved = c; };
    }
    o.checkpoint = std::move(hooks);
    Stage s{renderImage(scene, o), std::nullopt};
    if (s.result.interrupted) s.state = std::move(saved);
    return s;
}

// The noise estimate of a stopped render's sums; the photon pass being
// rendered is summed apart until it closes.
NoiseEstimate noiseOf(const RenderCheckpoint& c, double& meanSamples) {
    if (c.nextSample < 2) return {};
    const PixelSums all = c.sums.withOpen(c.open);
    double n = 0;
    for (size_t p = 0; p < all.L.size(); ++p) n += all.samplesOf(p);
    meanSamples = n / double(std::max<size_t>(1, all.L.size()));
    return estimateNoise(all);
}

// The noise at the end of the budget, `left` seconds away, of a method
// measured at m.rmse after m.seconds: it resumes with the photons and cache
// it stopped with, renders samples at the rate it did after its first ones
// (later photon passes included), and its noise falls as samples^-m.fall.
double predictedRmse(const PilotMeasurement& m, double left) {
    const double camera = std::max(m.seconds - m.setupSeconds, 1e-3);
    return m.rmse * std::pow(1 + std::max(left, 0.0) / camera, -m.fall);
}

bool clearlyBetter(double challenger, double incumbent) {
    return challenger * challenger < PilotMargin * incumbent * incumbent;
}

}  // namespace

RenderResult renderByPilots(Scene& scene, const RenderOptions& options, MethodPilot& out) {
    const Method rule = scene.desc.render.method;
    const Method other = rule == Method::Reference ? Method::Guided : Method::Reference;
    const Clock::time_point t0 = *options.runStart;
    const double end = options.timeBudget - std::max(options.reserveSeconds, 0.0);
    auto left = [&] { return end - secondsSince(t0); };
    // A stopped render's state resumed within the whole run's budget (its
    // seconds count back from runStart).
    auto resumedOptions = [&](const RenderCheckpoint& c) {
        RenderOptions o = options;
        o.runStart = plusSeconds(t0, c.seconds);
        return o;
    };
    auto renderRule = [&](const std::string& why) {
        scene.desc.render.method = out.method = rule;
        out.reason = why;
        return renderImage(scene, options);
    };

    std::vector<RenderCheckpoint> pilots;
    for (Method m : {rule, other}) {
        scene.desc.render.method = m;
        RenderOptions o = options;
        o.progress = false;
        o.denoisedVariance = nullptr;  // no denoiser runs in a pilot
        const Clock::time_point start = Clock::now();
        o.runStart = start;
        int boundaries = 0;  // every sweep renders at least one sample: past two after the third
        Stage s = renderStage(scene, o, nullptr, [&] {
            return ++boundaries >= 3 && secondsSince(start) >= PilotShare * options.timeBudget;
        });
        double meanSamples = 0;
        const NoiseEstimate noise = s.state ? noiseOf(*s.state, meanSamples) : NoiseEstimate{};
        if (!noise.valid) return renderRule("rule: a pilot gave no noise estimate");
        out.measured.push_back(
            {m, s.state->nextSample, meanSamples, s.state->seconds, s.state->setupSeconds, noise.rmse, 0.5, 0});
        pilots.push_back(std::move(*s.state));
    }
    for (PilotMeasurement& m : out.measured) m.predictedRmse = predictedRmse(m, left());
    size_t pick = clearlyBetter(out.measured[1].predictedRmse, out.measured[0].predictedRmse) ? 1 : 0;

    // The pick goes on from its pilot to the check.
    scene.desc.render.method = out.measured[pick].method;
    const Clock::time_point checkStart = Clock::now();
    Stage check = renderStage(scene, resumedOptions(pilots[pick]), &pilots[pick],
                              [&] { return secondsSince(t0) >= PilotCheckShare * options.timeBudget; });
    double meanSamples = 0;
    const NoiseEstimate noise = check.state ? noiseOf(*check.state, meanSamples) : NoiseEstimate{};
    if (!noise.valid) {  // it ended before the check (a noise target met)
        out.method = out.measured[pick].method;
        out.reason = str("measured: pilots predicted noise ", out.measured[pick].predictedRmse, " against ",
                         out.measured[1 - pick].predictedRmse);
        return std::move(check.result);
    }
    const PilotMeasurement& first = out.measured[pick];
    PilotMeasurement again = first;
    again.samples = check.state->nextSample;
    again.meanSamples = meanSamples;
    again.seconds += secondsSince(checkStart);
    again.rmse = noise.rmse;
    // How fast its noise fell between the two measurements, over the mean
    // samples per pixel (adaptive sampling spreads them unevenly): heavy
    // tails (rare, bright paths that the pilot missed) fall slower than
    // 1/sqrt(n).
    if (again.meanSamples > first.meanSamples && first.rmse > 0 && again.rmse > 0)
        again.fall = std::clamp(std::log(first.rmse / again.rmse) / std::log(again.meanSamples / first.meanSamples),
                                0.0, 0.5);
    again.predictedRmse = predictedRmse(again, left());
    out.measured.push_back(again);
    const double otherNow = predictedRmse(out.measured[1 - pick], left());
    const bool back = clearlyBetter(otherNow, again.predictedRmse);
    const RenderCheckpoint& from = back ? pilots[1 - pick] : *check.state;
    if (back) pick = 1 - pick;
    out.method = out.measured[pick].method;
    out.reason = str(back ? "measured again at the check" : "measured", ": predicted noise ",
                     back ? otherNow : again.predictedRmse, " against ",
                     methodName(out.measured[1 - pick].method), "'s ", back ? again.predictedRmse : otherNow);
    scene.desc.render.method = out.method;
    return renderStage(scene, resumedOptions(from), &from, nullptr).result;
}

std::string describePilot(const MethodPilot& p) {
    std::string s = "auto: ";
    for (size_t i = 0; i < p.measured.size(); ++i) {
        const PilotMeasurement& m = p.measured[i];
        s += str(i == 0 ? "pilots of " : i == 2 ? "; at the check " : "; ", methodName(m.method), " ", m.samples,
                 " spp in ", std::round(m.seconds * 100) / 100, " s",
                 m.setupSeconds > 0.005 ? str(" (first photons and cache ", std::round(m.setupSeconds * 100) / 100, " s)")
                                        : std::string(),
                 ", noise ", m.rmse, m.fall < 0.5 ? str(" falling as n^-", std::round(m.fall * 100) / 100) : std::string(),
                 " -> ", m.predictedRmse, " predicted at the end");
    }
    return s + str(": ", methodName(p.method));
}

}  // namespace vdbmarch
