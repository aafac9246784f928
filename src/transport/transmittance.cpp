#include "transport/transmittance.h"

#include <algorithm>

#include "core/power_series.h"
#include "transport/roulette.h"
#include "transport/tracking.h"

namespace vdbmarch {

namespace {

// Optical depth of the region's media over [0, tEnd) of ray r. Constant
// media integrate exactly; gridded media are marched with uniform steps at
// (k + u) * step, an unbiased estimate of the integral of sigma_t. Stops early
// once every channel's depth exceeds `depthCutoff`.
Color opticalDepth(ThreadContext& ctx, int region, const Ray& r, float tEnd, Rng& rng, float depthCutoff) {
    Color tau(0);
    const auto& media = ctx.scene.regions[size_t(region)].media;
    if (media.empty()) return tau;
    const float step = ctx.scene.shadowStep;
    const float u = rng.uniform();
    for (int mi : media) {
        MediumQuery& q = *ctx.queries[size_t(mi)];
        const Medium& m = *ctx.scene.media[size_t(mi)];
        const Color sigmaT = m.sigma_a + m.sigma_s;
        float integral;
        if (q.densityIntegral(r, 0.f, tEnd, integral)) {
            for (int c = 0; c < 3; ++c)  // unbounded fog: inf * 0 must not make NaN
                if (integral > 0 && sigmaT[c] > 0) tau[c] += sigmaT[c] * integral;
            if (minComponent(tau) > depthCutoff) return tau;
            continue;
        }
        ctx.shadowIntervals.clear();
        q.activeIntervals(r, 0.f, tEnd, ctx.shadowIntervals);
        float sum = 0;
        for (const Interval& iv : ctx.shadowIntervals) {
            // Lattice index in double: k + 1 must never round back to k.
            double k = std::ceil(double(iv.t0) / step - u);
            for (double t = (k + u) * step; t < iv.t1; k += 1, t = (k + u) * step) {
                sum += q.density(r.at(t));
                ++ctx.counters.shadowSamples;
                if (minComponent(tau + sigmaT * (sum * step)) > depthCutoff) return tau + sigmaT * (sum * step);
            }
        }
        tau += sigmaT * (sum * step);
    }
    return tau;
}

// Ratio tracking through the region's media over [0, tEnd): constant media
// exactly, gridded media against their local majorants (the maximum over
// channels, so the weights stay in [0, 1]), residual to each block's minimum.
Color ratioTracking(ThreadContext& ctx, int region, const Ray& r, float tEnd, Rng& rng) {
    Color T(1);
    for (int mi : ctx.scene.regions[size_t(region)].media) {
        const Medium& m = *ctx.scene.media[size_t(mi)];
        const Color k = m.sigma_a + m.sigma_s;
        MediumQuery& q = *ctx.queries[size_t(mi)];
        float integral;
        if (q.densityIntegral(r, 0.f, tEnd, integral)) {
            for (int c = 0; c < 3; ++c)
                if (integral > 0 && k[c] > 0) T[c] *= std::exp(-k[c] * integral);
            continue;
        }
        const float kMax = maxComponent(k);
        if (!(kMax > 0)) continue;
        // Block by block, lazily: a ray that roulette ends deep in a
        // cloud never visits the blocks behind.
        bool ended = false;
        ctx.queries[size_t(mi)]->forEachDensityBound(r, 0.f, tEnd, [&](const DensityBound& seg) {
            // Residual ratio tracking (Novak et al. 2014): the segment's
            // density lower bound is a control whose transmittance is exact,
            // exp(-k rho_min len); tentative collisions only track the
            // residual rho - rho_min, at rate k_max (rho_max - rho_min), with
            // weights 1 - k (rho - rho_min) / sigma_r in [0, 1]. Where the
            // block's density varies little, few collisions and little noise.
            const float lo = std::min(seg.minDensity, seg.maxDensity);
            if (lo > 0 && seg.t1 > seg.t0)
                for (int c = 0; c < 3; ++c)
                    if (k[c] > 0) T[c] *= std::exp(-double(k[c]) * lo * (double(seg.t1) - seg.t0));
            if (lo > 0 && isBlack(T)) {
                ended = true;
                return false;
            }
            const float sigmaMaj = mediumMajorant(seg.maxDensity - lo, kMax);
            if (!(sigmaMaj > 0)) return true;
            // The step floor of deltaTrack (tracking.h) for absurd majorants.
            const bool absurd = double(sigmaMaj) * double(ctx.scene.step) > 1e6;
            const double minStep = 1e-6 * double(ctx.scene.step);
            double t = seg.t0;
            while (true) {
                const double dt = -std::log(1 - double(rng.uniform())) / sigmaMaj;
                t += absurd ? std::max(dt, minStep) : dt;
                if (t >= seg.t1) return true;
                ++ctx.counters.shadowSamples;
                const float d = q.density(r.at(t));
                for (int c = 0; c < 3; ++c) T[c] *= std::max(0.f, 1 - k[c] * (d - lo) / sigmaMaj);
                if (!russianRoulette(T, rng)) {
                    ended = true;
                    return false;
                }
            }
        });
        if (ended) return Color(0);
    }
    return T;
}

// Unbiased ray marching (Kettunen et al. 2021) of one medium over [0, tEnd).
// The optical depth is estimated by stratified samples placed in proportion
// to each block's residual bound (max - min, importance sampling), residual to
// the block's minimum, whose share is exact. The blocks are walked lazily in
// pools of about MarchedPoolDepth of residual optical depth, each cut into
// strata of at most MarchedDepthPerStratum, so roulette ends a deep ray's
// walk early. The series of core/power_series.h turns order + 1 such
// estimates into an unbiased transmittance whose noise is close to stepped
// marching's exp(-tau); most shadow rays need one estimate (order 0 with
// probability SeriesPZero). The constants were tuned by measurement:
// docs/benchmarks/history.md, "Shadow rays: unbiased ray marching".
constexpr double MarchedDepthPerStratum = 1.0;
constexpr double MarchedPoolDepth = 4.0;
constexpr double SeriesPZero = 0.75;
// Deep shadow rays are ended by roulette once less than this share of the
// light is left, far above the camera paths' RouletteThreshold; tuned by
// measurement: docs/benchmarks/history.md, "The block walk and shadow-ray
// roulette; the default render against the yardstick".
constexpr double ShadowRouletteThreshold = 0.2;
constexpr int MaxStrataPerPool = 4096;  // absurd majorants: wider strata, still unbiased

Color marchedTransmittance(ThreadContext& ctx, int mi, const Ray& r, float tEnd, Rng& rng) {
    const Medium& m = *ctx.scene.media[size_t(mi)];
    const Color k = m.sigma_a + m.sigma_s;
    MediumQuery& q = *ctx.queries[size_t(mi)];
    float integral;
    if (q.densityIntegral(r, 0.f, tEnd, integral)) {
        Color T(1);
        for (int c = 0; c < 3; ++c)
            if (integral > 0 && k[c] > 0) T[c] = std::exp(-k[c] * integral);
        return T;
    }
    const float kMax = maxComponent(k), kMin = minComponent(k);
    if (!(kMax > 0)) return Color(1);
    const SeriesOrder dist(SeriesPZero);
    const int order = dist.sample(rng.uniformDouble());
    const int n = order + 1;
    auto& depth = ctx.marchDepths;  // per estimate: its residual depth so far
    depth.assign(size_t(2 * n), 0.0);
    auto& pool = ctx.shadowBounds;  // segments with residual, not yet sampled
    pool.clear();
    double poolMass = 0, control = 0;
    // Samples every estimate over the pool: M strata of equal residual mass,
    // one jittered sample each, mapped to t through the pool's segments.
    auto samplePool = [&]() {
        const int strata = int(std::min<double>(MaxStrataPerPool,
                                                std::ceil(double(kMax) * poolMass / MarchedDepthPerStratum)));
        const double width = poolMass / strata;
        for (int j = 0; j < n; ++j) {
            size_t seg = 0;
            double segStart = 0;  // residual mass before pool[seg]
            for (int i = 0; i < strata; ++i) {
                const double c = (i + rng.uniformDouble()) * width;
                while (seg + 1 < pool.size() &&
                       c >= segStart + (double(pool[seg].maxDensity) - pool[seg].minDensity) *
                                           (double(pool[seg].t1) - pool[seg].t0)) {
                    segStart += (double(pool[seg].maxDensity) - pool[seg].minDensity) * (double(pool[seg].t1) - pool[seg].t0);
                    ++seg;
                }
                const DensityBound& s = pool[seg];
                const double lo = s.minDensity, span = double(s.maxDensity) - lo;
                const double t = std::min(double(s.t1), s.t0 + (c - segStart) / span);
                ++ctx.counters.shadowSamples;
                depth[size_t(j)] += (double(q.density(r.at(float(t)))) - lo) / span * width;
            }
        }
        pool.clear();
        poolMass = 0;
    };
    // Roulette on the first estimate's depth in the least attenuated
    // channel: past ShadowRouletteThreshold of the light, the ray goes on
    // with probability exp(-(depth - paid)); the survivor's weight keeps it
    // unbiased.
    double paid = -std::log(double(ShadowRouletteThreshold)), weight = 1;
    auto roulette = [&]() {
        const double d = double(kMin) * (control + depth[0]);
        if (!(kMin > 0) || d <= paid) return true;
        const double survive = std::exp(-(d - paid));
        paid = d;
        if (rng.uniformDouble() >= survive) return false;
        weight /= survive;
        return true;
    };
    bool ended = false;
    ctx.queries[size_t(mi)]->forEachDensityBound(r, 0.f, tEnd, [&](const DensityBound& s) {
        if (!(s.t1 > s.t0)) return true;
        const double len = double(s.t1) - s.t0;
        const float lo = std::max(0.f, std::min(s.minDensity, s.maxDensity));
        control += double(lo) * len;
        if (s.maxDensity > lo) {
            pool.push_back({s.t0, s.t1, s.maxDensity, lo});
            poolMass += (double(s.maxDensity) - lo) * len;
            if (double(kMax) * poolMass < MarchedPoolDepth) return true;
            samplePool();
        }
        if (!roulette()) {
            ended = true;
            return false;
        }
        return true;
    });
    if (ended) return Color(0);
    if (!pool.empty()) samplePool();
    double* d = depth.data();
    for (int j = 0; j < n; ++j) d[j] += control;
    return powerSeriesTransmittance(d, order, k, dist, d + n) * float(weight);
}

}  // namespace

Color regionTransmittance(ThreadContext& ctx, int region, const Ray& r, float tEnd, Rng& rng,
                          TransmittanceEstimator estimator) {
    switch (estimator) {
    case TransmittanceEstimator::RatioTracking:
        return ratioTracking(ctx, region, r, tEnd, rng);
    case TransmittanceEstimator::UnbiasedMarching: {
        Color T(1);
        for (int mi : ctx.scene.regions[size_t(region)].media) {
            T *= marchedTransmittance(ctx, mi, r, tEnd, rng);  // independent per medium: the product is unbiased
            if (isBlack(T)) break;
        }
        return T;
    }
    case TransmittanceEstimator::Stepped:
        break;
    }
    return exp(-opticalDepth(ctx, region, r, tEnd, rng, Infinity));
}

Color shadowTransmittance(ThreadContext& ctx, int region, const Vec3& p, const Vec3& wi, float dist, Rng& rng,
                          TransmittanceEstimator estimator) {
    ++ctx.counters.shadowRays;
    if (estimator != TransmittanceEstimator::Stepped) {
        Color T(1);
        bool reached = walkShadowRay(ctx.scene, region, Ray{p, wi}, dist, [&](int reg, const Ray& r, float tEnd) {
            T *= regionTransmittance(ctx, reg, r, tEnd, rng, estimator);
            return !isBlack(T);
        });
        return reached ? T : Color(0);
    }
    Color tau(0);
    // exp(-30) ~ 1e-13: beyond that depth the light is numerically gone.
    const float cutoff = 30.f;
    bool reached = walkShadowRay(ctx.scene, region, Ray{p, wi}, dist, [&](int reg, const Ray& r, float tEnd) {
        tau += opticalDepth(ctx, reg, r, tEnd, rng, cutoff - minComponent(tau));
        return !(minComponent(tau) > cutoff);
    });
    return reached ? exp(-tau) : Color(0);
}

}  // namespace vdbmarch
