// Per-thread state of every path loop: one medium query per medium (VDB
// accessors), scratch vectors reused across rays, and the render counters.
// The sampling strategies and the estimators above keep their scratch in
// `extensions`, made on first use, so this layer knows nothing of them.
// Tables made once per render live with the strategies, not here.
#pragma once

#include <memory>
#include <vector>

#include "core/sampling.h"
#include "core/stats.h"
#include "scene/scene.h"
#include "transport/majorant_segment.h"

namespace vdbmarch {

// Aligned to a cache line, and so padded to whole lines: the scratch of two
// threads' contexts, written at every vertex, never shares a line.
struct alignas(64) ThreadContextExtension {
    virtual ~ThreadContextExtension() = default;
};

struct ThreadContext {
    explicit ThreadContext(const Scene& s);
    const Scene& scene;
    std::vector<std::unique_ptr<MediumQuery>> queries;  // one per medium
    std::vector<Interval> intervals, shadowIntervals;
    std::vector<Interval> mediaIntervals;  // every medium's intervals before regionIntervals merges them
    std::vector<MajorantSegment> majorants;  // sigma_maj (tracking.h)
    // Shadow rays' unbiased ray marching (transmittance.cpp): the blocks
    // not sampled yet, and the optical-depth estimates.
    std::vector<DensityBound> shadowBounds;
    std::vector<double> marchDepths;
    // Per light, the last ray's part inside its reach (lightReach). Held
    // in place, not in a heap vector, since it is written on every ray (a
    // heap vector slowed renders measurably: docs/benchmarks/history.md,
    // "Beam directions weighted by the phase towards the vertex; the spot
    // reach").
    struct ReachMemo {
        Vec3 o, d;
        float t0 = 0, t1 = 0;
        bool reaches = false, valid = false;
    };
    static constexpr int ReachMemoLights = 4;  // the first lights only
    ReachMemo reachMemo[ReachMemoLights];
    RenderCounters counters;
    // Scratch of the layers above, one slot each, made on first use: slot 0
    // is the estimator's, the sampling strategies number theirs from 1
    // (strategies/strategy_set.h).
    std::vector<std::unique_ptr<ThreadContextExtension>> extensions;

    template <typename T>
    T& extensionAt(size_t slot) {
        if (extensions.size() <= slot) extensions.resize(slot + 1);
        if (!extensions[slot]) extensions[slot] = std::make_unique<T>();
        return static_cast<T&>(*extensions[slot]);
    }
    // The estimator's scratch (slot 0).
    template <typename T>
    T& extensionAs() { return extensionAt<T>(0); }

    // Light::reachInterval of scene light `light` for `ray`, remembered for
    // the last ray asked (bit-identical rays only): a beam direction's
    // density and the next segment's distance samplers ask for the same ray.
    bool lightReach(int light, const Ray& ray, float& t0, float& t1) {
        if (light >= ReachMemoLights) return scene.lights[size_t(light)].reachInterval(ray, t0, t1);
        ReachMemo& m = reachMemo[light];
        if (!(m.valid && m.o.x == ray.o.x && m.o.y == ray.o.y && m.o.z == ray.o.z && m.d.x == ray.d.x &&
              m.d.y == ray.d.y && m.d.z == ray.d.z)) {
            m.reaches = scene.lights[size_t(light)].reachInterval(ray, m.t0, m.t1);
            m.o = ray.o;
            m.d = ray.d;
            m.valid = true;
        }
        t0 = m.t0;
        t1 = m.t1;
        return m.reaches;
    }
};

}  // namespace vdbmarch
