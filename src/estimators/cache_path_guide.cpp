#include "estimators/cache_path_guide.h"

#include <algorithm>
#include <cmath>

#include "estimators/segment_marcher.h"
#include "transport/path_tracer.h"
#include "transport/tracking.h"
#include "transport/transmittance.h"

namespace vdbmarch {

namespace {

// Share of the transmittance pdf in the guided mixture: with a useless cache
// the variance is at most 1 / eps times that of transmittance sampling.
constexpr float FlightDefensive = 0.25f;
// Bins per segment at most (a long segment takes longer bins).
constexpr int MaxFlightBins = 256;
// Least probability of passing a segment: T~ may underestimate T where
// gridded density varies inside a bin.
constexpr double MinPassThrough = 0.01;
// Every bin keeps at least this share of the mean scattering weight per
// unit length, so no bin of an active interval has probability 0.
constexpr double BinFloor = 1e-3;

class CachePathGuide final : public PathGuide {
public:
    CachePathGuide(const Scene& scene, const RadianceCache& cache)
        : mScene(scene), mCache(cache), mBin(cache.cellSize(cache.levels - 1)),
          mDirections(scene.desc.render.productSampling && cache.directionLobes && !cache.cells.empty()),
          mRoulette(scene.desc.render.guidedRoulette && !cache.cells.empty()) {
        mRegionEmits.assign(scene.regions.size(), 0);
        mRegionConstant.assign(scene.regions.size(), 0);
        for (size_t r = 0; r < scene.regions.size(); ++r) {
            const std::vector<int>& media = scene.regions[r].media;
            for (int mi : media) mRegionEmits[r] |= scene.media[size_t(mi)]->hasEmission;
            // One homogeneous medium: the same coefficients in every active interval.
            mRegionConstant[r] =
                media.size() == 1 && scene.desc.media[size_t(media[0])].type == MediumDesc::Type::Homogeneous;
        }
    }

    bool prepareFlight(ThreadContext& ctx, int region, const Ray& ray, float tEnd, int channel) const override {
        // Emission is collected at tracking collisions.
        if (mScene.regions[size_t(region)].media.empty() || mRegionEmits[size_t(region)]) return false;
        MarcherScratch& m = scratch(ctx);
        regionIntervals(ctx, region, ray, 0.f, tEnd, ctx.intervals);
        double active = 0;
        for (const Interval& iv : ctx.intervals) active += double(iv.t1) - double(iv.t0);
        // A segment to infinity (no surface behind the medium) is guided
        // through its finite active part; unbounded fog has no end.
        if (!(active > 0) || !std::isfinite(active)) return false;
        const double dx = std::max(double(mBin), active / MaxFlightBins);

        std::vector<PdfStep>& steps = m.pdfSteps;
        std::vector<float>& h = m.stepH;
        steps.clear();
        h.clear();
        CacheLookup& cache = m.lookup(mCache);
        cache.setDirection(-ray.d);
        MediumPoint mp;
        const bool constant = mRegionConstant[size_t(region)];
        bool haveMedia = false;
        double tau = 0, T = 1, sum = 0;
        // The last bin's kappa and length, its transmittance and S (full
        // bins of a constant medium repeat them: no exp per bin).
        double lastKappa = -1, lastLen = -1, lastT = 1, lastS = 0;
        for (const Interval& iv : ctx.intervals) {
            for (double k = std::floor(double(iv.t0) / dx);; k += 1) {
                const double a = std::max(double(iv.t0), k * dx), b = std::min(double(iv.t1), (k + 1) * dx);
                if (a >= double(iv.t1)) break;
                if (!(b > a)) continue;
                const Vec3 x = ray.at(float(0.5 * (a + b)));
                if (!(constant && haveMedia)) {
                    evalMedia(ctx, region, x, mp);
                    ++ctx.counters.marchSamples;
                    haveMedia = true;
                }
                const float len = float(b - a);
                const double kappa = trackedSigmaT(mp.sigma_t, channel);
                const double ss = trackedOrAverage(mp.sigma_s, channel);
                const double ktau = kappa * len;
                if (kappa != lastKappa || double(len) != lastLen) {
                    const double oneMinusT = -std::expm1(-ktau);
                    lastKappa = kappa;
                    lastLen = len;
                    lastT = 1 - oneMinusT;
                    lastS = ktau > 1e-6 ? oneMinusT / kappa : double(len);
                }
                const double base = ss * T * lastS;  // sigma_s T~(a) S(kappa, len)
                steps.push_back({float(a), len, float(kappa), float(base)});
                h.push_back(mp.scatters() ? cache.at(x) : 0.f);
                sum += base;
                tau += ktau;
                T *= lastT;
            }
        }
        if (!(sum > 0)) return false;
        const double floor = BinFloor * sum / active;
        for (PdfStep& s : steps) s.base = float(double(s.base) + floor * s.len);
        m.rayPdf.build(steps, h.data(), FlightDefensive);
        if (!m.rayPdf.valid()) return false;
        MarcherScratch::FlightState& f = m.flight;
        f.ray = ray;
        f.region = region;
        f.tEnd = tEnd;
        f.scatter = std::min(-std::expm1(-tau), 1 - MinPassThrough);
        f.inScattered = m.rayPdf.guidedIntegral();
        f.transmittance = std::exp(-tau);
        return f.scatter > 0;
    }

    float flightDensity(ThreadContext& ctx, float t) const override {
        MarcherScratch& m = scratch(ctx);
        const std::vector<PdfStep>& steps = m.pdfSteps;
        auto it = std::upper_bound(steps.begin(), steps.end(), t, [](float v, const PdfStep& s) { return v < s.t0; });
        if (it == steps.begin()) return 0.f;
        const PdfStep& s = *(it - 1);
        const float offset = t - s.t0;
        if (!(offset < s.len)) return 0.f;  // empty space between intervals
        return float(m.flight.scatter * m.rayPdf.pdf(int(it - 1 - steps.begin()), offset));
    }

    GuidedFlight sampleFlight(ThreadContext& ctx, Rng& rng, MediumPoint& mp) const override {
        MarcherScratch& m = scratch(ctx);
        const MarcherScratch::FlightState& f = m.flight;
        GuidedFlight out;
        if (rng.uniform() < f.scatter) {
            int k;
            float offset;
            double p;
            m.rayPdf.sample(rng.uniformDouble(), k, offset, p);
            out.scattered = true;
            out.t = m.pdfSteps[size_t(k)].t0 + offset;
            evalMedia(ctx, f.region, f.ray.at(out.t), mp);
            if (!mp.scatters() || !(p > 0)) return out;  // weight 0: nothing scatters here
            const Color T = regionTransmittance(ctx, f.region, f.ray, out.t, rng);
            out.weight = T * mp.sigma_s * float(1.0 / (f.scatter * p));
            return out;
        }
        out.t = f.tEnd;
        out.weight = regionTransmittance(ctx, f.region, f.ray, f.tEnd, rng) * float(1.0 / (1.0 - f.scatter));
        return out;
    }

    FlightEstimate flightEstimate(ThreadContext& ctx) const override {
        const MarcherScratch::FlightState& f = scratch(ctx).flight;
        return {f.inScattered, f.transmittance};
    }

    bool guidesRoulette() const override { return mRoulette; }
    bool guidesFlights(int region) const override { return mRegionConstant[size_t(region)]; }

    float expectedRadiance(ThreadContext& ctx, const Vec3& x, const Vec3& wo) const override {
        CacheLookup& cache = scratch(ctx).lookup(mCache);
        cache.setDirection(wo);
        return cache.at(x);
    }

    bool prepareDirection(ThreadContext& ctx, const Vec3& x, const Vec3& rayDir, const MediumPoint& mp,
                          ScatterVertex& vertex) const override {
        if (!mDirections) return false;
        return scratch(ctx).buildProductSampler(mCache, x, rayDir, mp, vertex);
    }

    Vec3 sampleDirection(ThreadContext& ctx, float u0, float u1, float u2, Color& weight, float& pdf) const override {
        const ProductSample s = scratch(ctx).productSampler.sample(u0, u1, u2);
        weight = s.weight;
        pdf = s.pdf;
        return s.wi;
    }

private:
    static MarcherScratch& scratch(ThreadContext& ctx) { return ctx.extensionAs<MarcherScratch>(); }

    const Scene& mScene;
    const RadianceCache& mCache;
    const float mBin;  // the cache's finest cell
    const bool mDirections;
    const bool mRoulette;
    std::vector<char> mRegionEmits, mRegionConstant;
};

}  // namespace

std::unique_ptr<PathGuide> makeCachePathGuide(const Scene& scene, const RadianceCache& cache) {
    return std::make_unique<CachePathGuide>(scene, cache);
}

}  // namespace vdbmarch
