// Sampler hooks of the path loop (path_tracer.h): an estimator above this
// layer (the radiance cache, marchers/cache_path_guide.h) can take over a
// path segment's free flight and a medium vertex's scattering direction.
// Without a guide the loop delta-tracks and samples the phase function.
//
// A guided free flight on [0, tEnd) either scatters at t, drawn with density
// P_s p(t), and multiplies the throughput by T(t) sigma_s(t) / (P_s p(t)),
// or passes to tEnd with probability 1 - P_s and weight T(tEnd) / (1 - P_s),
// T estimated without bias (ratio tracking). Its expectation is that of
// delta tracking for any p whose support holds every point where sigma_s > 0,
// so heterogeneous media stay unbiased; absorption is in T, never a kill.
// The state of a prepared segment lives in the ThreadContext.
#pragma once

#include "core/rng.h"
#include "transport/direct_light.h"
#include "transport/media_point.h"
#include "transport/thread_context.h"

namespace vdbmarch {

// The guide's estimate of the prepared segment's radiance (from its cache):
// what scatters towards the ray's origin along it, int sigma_s T L_i dt,
// and the approximate transmittance to its end.
struct FlightEstimate {
    double inScattered = 0;
    double transmittance = 1;
};

struct GuidedFlight {
    bool scattered = false;  // false: passed to tEnd
    float t = 0;             // the collision (scattered)
    Color weight{0};         // factor on the throughput
};

class PathGuide {
public:
    virtual ~PathGuide() = default;

    // True when the guide samples the free flights of segments in `region`
    // (else it prepares them only for flightEstimate).
    virtual bool guidesFlights(int region) const = 0;
    // Prepares segment [0, tEnd) of `ray` in `region` for the tracked
    // `channel` (< 0: grey). False: leave this segment to delta tracking.
    virtual bool prepareFlight(ThreadContext& ctx, int region, const Ray& ray, float tEnd, int channel) const = 0;
    // Density of a scattering collision at t on the prepared segment,
    // P_s p(t): the weights of distance sampling towards lights use it.
    virtual float flightDensity(ThreadContext& ctx, float t) const = 0;
    // Draws the prepared segment's free flight; on a collision, mp holds the
    // media there.
    virtual GuidedFlight sampleFlight(ThreadContext& ctx, Rng& rng, MediumPoint& mp) const = 0;

    // The prepared segment's estimate (guided roulette's pixel estimate).
    virtual FlightEstimate flightEstimate(ThreadContext& ctx) const = 0;

    // True when the guide's radiance may steer Russian roulette and
    // splitting (render.guided_roulette).
    virtual bool guidesRoulette() const = 0;
    // The guide's estimate of the radiance a path at medium point x brings
    // back along wo (the in-scattered L_i(x, wo), grey); 0 where it has none.
    virtual float expectedRadiance(ThreadContext& ctx, const Vec3& x, const Vec3& wo) const = 0;

    // Prepares the direction sampler at a medium vertex (x, the path arriving
    // along rayDir, media mp there) and points `vertex`'s pathPdf at it, so
    // next-event estimation weighs its light samples by MIS against it.
    // False: sample the phase function.
    virtual bool prepareDirection(ThreadContext& ctx, const Vec3& x, const Vec3& rayDir, const MediumPoint& mp,
                                  ScatterVertex& vertex) const = 0;
    // Draws from the prepared direction sampler: wi, phase / pdf per channel, pdf.
    virtual Vec3 sampleDirection(ThreadContext& ctx, float u0, float u1, float u2, Color& weight, float& pdf) const = 0;
};

}  // namespace vdbmarch
