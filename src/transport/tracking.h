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

// The extinction a majorant bounds: the largest channel's, so that one
// majorant serves every channel (for grey media, any channel's).
inline float majorantSigmaT(const Color& sigmaT) { return maxComponent(sigmaT); }

// True when some medium's extinction differs between channels: paths then
// track with spectral MIS (HeroChannel).
bool hasChromaticExtinction(const Scene& scene);

// Spectral MIS for tracking in chromatic media (Miller, Georgiev and Jarosz
// 2019, section 5; hero sampling of Wilkie et al. 2014): a path picks its
// hero channel uniformly, decides each tentative collision (absorb,
// scatter, null) by the hero's coefficients against the one majorant of
// all channels, and every channel's throughput is weighed by the balance
// heuristic over the three channels' path densities: f_c / mean_k p_k.
// A collision event's f and p agree channel by channel (sigma_s or
// sigma_maj - sigma_t), so a channel's weight is p_c / mean_k p_k <= 3:
// no channel ever carries a firefly of its own, unlike one path per
// channel. Grey extinction (channel < 0) keeps the channel average.
struct HeroChannel {
    int channel = -1;  // < 0: grey extinction, no spectral MIS
    // Each channel's path density over their mean (averages 1).
    Color pdf{1, 1, 1};

    // Weighs beta by an event whose density in channel c is proportional
    // to p[c]: beta *= p / mean(pdf p), pdf *= p / mean(pdf p).
    void weigh(const Color& p, Color& beta) {
        const Color q = pdf * p;
        const float s = average(q);
        if (!(s > 0)) return;  // an event the hero cannot draw (rounding at the majorant)
        beta *= p / s;
        pdf = q / s;
        // A channel below 1e-20 of the mean carries nothing: flushed, so
        // that it dies instead of lingering among the denormals (clearIn).
        for (int c = 0; c < 3; ++c)
            if (pdf[c] < 1e-20f) pdf[c] = 0, beta[c] = 0;
    }
    // The path density of an event whose density in channel c is
    // proportional to p[c]: the channels' mixture mean(pdf p).
    float mixed(const Color& p) const { return average(pdf * p); }
    // True when no channel the path still carries (pdf > 0) has extinction
    // in a region of these coefficients (Region::coefficients): every later
    // null collision there would weigh by exactly 1, and tracking stops
    // (a hero with no extinction in unbounded fog would never collide).
    bool clearIn(const Color& coefficients) const {
        for (int c = 0; c < 3; ++c)
            if (pdf[c] > 0 && coefficients[c] > 0) return false;
        return true;
    }
    // A null collision (sigma_maj - sigma_t per channel) weighs beta;
    // false where tracking can stop (clearIn).
    bool null(const Color& sigmaT, float sigmaMaj, const Color& coefficients, Color& beta) {
        if (channel < 0) return true;
        weigh(max(Color(sigmaMaj) - sigmaT, Color(0)), beta);
        return !clearIn(coefficients);
    }
    // A scattering collision: grey extinction weighs each channel by its
    // albedo over the mean (the event was drawn by the mean), chromatic by
    // sigma_s (the collision and the scattering together).
    void scatter(const Color& sigmaS, Color& beta) {
        if (channel < 0)
            beta *= sigmaS / average(sigmaS);
        else
            weigh(sigmaS, beta);
    }
    // The hero's value of c, or for grey extinction the channel average.
    float of(const Color& c) const { return channel < 0 ? average(c) : c[channel]; }
};

// A medium's extinction majorant from its density bound and coefficient.
// evalMedia clamps each coefficient to MaxCoefficient, so the extinction
// never exceeds twice that: the bound keeps huge inputs (density 1e30 x
// sigma 1e30) finite, where an infinite majorant would stall tracking.
inline float mediumMajorant(float densityBound, float sigmaT) {
    return std::min(densityBound * sigmaT, 2 * MaxCoefficient);
}

// A path's (or photon's) starting spectral state: a hero channel drawn
// uniformly where some medium's extinction differs between channels, else grey.
inline HeroChannel startingHero(bool chromatic, Rng& rng) {
    HeroChannel h;
    if (chromatic) h.channel = std::min(2, int(rng.uniform() * 3));
    return h;
}

// Combined extinction majorant of the region's media along [0, tEnd).
void regionMajorants(ThreadContext& ctx, int region, const Ray& r, float tEnd, std::vector<MajorantSegment>& out);

// Delta tracking along [0, tEnd) of `ray` in `region`: tentative collisions
// are drawn at rate sigma_maj against the local majorants (walked lazily for
// a single medium, so blocks past the first real collision are never
// visited), and collide(x, sigmaMaj) is called at each until it returns false.
template <typename Collide>
void deltaTrack(ThreadContext& ctx, int region, const Ray ray, float tEnd, Rng& rng, Collide&& collide) {
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
        const float k = majorantSigmaT(m.sigma_a + m.sigma_s);
        ctx.queries[size_t(media[0])]->forEachDensityBound(ray, 0.f, tEnd, [&](const DensityBound& s) {
            return track({s.t0, s.t1, mediumMajorant(s.maxDensity, k)});
        });
    } else if (!media.empty()) {
        regionMajorants(ctx, region, ray, tEnd, ctx.majorants);
        for (const auto& seg : ctx.majorants)
            if (!track(seg)) break;
    }
}

}  // namespace vdbmarch
