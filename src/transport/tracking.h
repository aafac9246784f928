// Majorants and delta tracking: the free-flight sampler of the path loop and
// the photon tracer. The medium bounds its density per 8^3 block of its VDB
// tree (volume/medium.h, DensityBound); times sigma_t that gives the
// (t0, t1, sigma_maj) segments tracked here; the caller's callback handles
// each tentative collision.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "core/rng.h"
#include "transport/media_point.h"
#include "transport/thread_context.h"

namespace vdbmarch {

// Extinction used for tracking: channel c, or (grey media, channel < 0) channel 0.
inline float trackedSigmaT(const Color& sigmaT, int channel) { return sigmaT[channel < 0 ? 0 : channel]; }

// Tracking probabilities of the channel, or for grey extinction the channel
// average (sigma_a + sigma_s sums to sigma_t either way).
inline float trackedOrAverage(const Color& c, int channel) { return channel < 0 ? average(c) : c[channel]; }

// True when some medium's extinction differs between channels: paths then
// track one channel each, which keeps every estimator unbiased.
bool hasChromaticExtinction(const Scene& scene);

// A medium's extinction majorant from its density bound and coefficient.
// evalMedia clamps each coefficient to MaxCoefficient, so the extinction
// never exceeds twice that: the bound keeps huge inputs (density 1e30 x
// sigma 1e30) finite, where an infinite majorant would stall tracking.
inline float mediumMajorant(float densityBound, float sigmaT) {
    return std::min(densityBound * sigmaT, 2 * MaxCoefficient);
}

// Combined extinction majorant of the region's media along [0, tEnd) for the
// tracked `channel`.
void regionMajorants(ThreadContext& ctx, int region, const Ray& r, float tEnd, int channel,
                     std::vector<MajorantSegment>& out);

// Delta tracking along [0, tEnd) of `ray` in `region`: tentative collisions
// are drawn at rate sigma_maj against the local majorants (walked lazily for
// a single medium, so blocks past the first real collision are never
// visited), and collide(x, sigmaMaj) is called at each until it returns false.
template <typename Collide>
void deltaTrack(ThreadContext& ctx, int region, const Ray ray, float tEnd, int channel, Rng& rng, Collide&& collide) {
    // `ray` is a copy: collide() may replace the caller's ray when it scatters.
    // A majorant of over a million collisions per march step (coefficients
    // near float's limits) would take steps below the resolution of t and
    // never leave a region of tiny density (the stress suite's 1e30 media
    // hung photon tracing): there, steps shorter than 1e-6 of a march step
    // are lengthened to it. Positions are floats, so such a medium is opaque
    // at that scale whatever the step; ordinary media never reach the rule.
    const double minStep = 1e-6 * double(ctx.scene.step);
    auto track = [&](const MajorantSegment& seg) {
        const float sigmaMaj = seg.sigmaMaj;
        if (!(sigmaMaj > 0)) return true;
        const bool absurd = double(sigmaMaj) * double(ctx.scene.step) > 1e6;
        double t = seg.t0;
        while (true) {
            const double dt = -std::log(1 - double(rng.uniform())) / sigmaMaj;
            t += absurd ? std::max(dt, minStep) : dt;
            if (t >= seg.t1) return true;
            if (!collide(ray.at(t), sigmaMaj)) return false;
        }
    };
    const auto& media = ctx.scene.regions[size_t(region)].media;
    if (media.size() == 1) {
        const Medium& m = *ctx.scene.media[size_t(media[0])];
        const float k = trackedSigmaT(m.sigma_a + m.sigma_s, channel);
        ctx.queries[size_t(media[0])]->forEachDensityBound(ray, 0.f, tEnd, [&](const DensityBound& s) {
            return track({s.t0, s.t1, mediumMajorant(s.maxDensity, k)});
        });
    } else if (!media.empty()) {
        regionMajorants(ctx, region, ray, tEnd, channel, ctx.majorants);
        for (const auto& seg : ctx.majorants)
            if (!track(seg)) break;
    }
}

}  // namespace vdbmarch
