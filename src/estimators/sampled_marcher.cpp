// Baseline (ii), transmittance sampling (eqs. 6-11), and the paper's guided
// marcher (eqs. 16-18). Both walk a camera-ray segment once in steps of the
// scene's step, as the uniform marcher does, but only to build the per-ray
// histogram: per step the media (one density lookup), the transmittance
// T(t0) and, for guided, the cached L_i of the cell holding it (Y_lm of the
// ray's direction evaluated once per ray, one tree lookup per cell crossed).
// L_i, the expensive part (shadow rays and photon lookups), is then
// estimated at only a few positions drawn from the pdf (ray_pdf.h):
//
//   transmittance:  P(t) ~ sigma_s T(t)            (eq. 9 with sigma_s)
//   guided:         P(t) ~ h(t) sigma_s T(t), mixed with the above  (eq. 16)
//
// and weighted by the estimator of eq. 18,
//
//   Delta L = (1/N) sum_j T(t_j) sigma_s(t_j) L_i(t_j) / P(t_j),
//
// where T and sigma_s are the step's (the medium is constant per step, as in
// eq. 5), so the pdf is only a pdf: for any histogram the expectation is
// the same integral the uniform marcher approximates, without its one-
// sample-per-step cost. VDB media are heterogeneous, so unlike the paper's
// homogeneous segment the true transmittance is accumulated step by step
// (the per-step exponential in between), which the pdf shares.
//
// Guided allots N per segment by eq. 17: proportional to the segment's
// expected in-scattering sum(h sigma_s T S) times the path throughput,
// relative to its mean over the segments through media (a probe of
// camera rays), between
// render.ray_samples / 4 and 8 render.ray_samples; transmittance always takes
// render.ray_samples. Emission is integrated on the steps, as uniform does.
#include <algorithm>
#include <cmath>

#include "estimators/segment_marcher.h"
#include "strategies/caustic_folds.h"
#include "strategies/light_distances.h"
#include "transport/roulette.h"

namespace vdbmarch {

namespace {

constexpr int MinSamplesDivisor = 4;  // guided: at least ray_samples / 4 per segment (and 1)
constexpr int MaxSamplesFactor = 8;   // guided: at most 8 ray_samples per segment
constexpr int ProbeWidth = 32, ProbeHeight = 24;

// Guided: the share of L_i positions drawn towards point, spot and sphere
// lights near the segment (equiangular sampling, Kulla & Fajardo 2012). Near
// a light the integrand grows as 1/r^2 over a span far below a cell of the
// cache, and a cache baked for other lights puts no samples there at all;
// with this share the weight of a position near a light stays below
// 1 / (share x equiangular density), whatever the cache says.
constexpr double LightDistanceShare = 0.25;

// Guided: the share of L_i positions drawn near the segment's crossings of
// the folds of point and parallel lights' caustics behind glass spheres
// (caustic_folds.h), where the light grows as 1 / sqrt(distance): with it a
// position's weight there stays below 1 / (share x the folds' density).
constexpr double FoldDistanceShare = 0.15;

class SampledMarcher final : public SegmentMarcher {
public:
    SampledMarcher(const EstimatorInputs& in, bool guided)
        : SegmentMarcher(in),
          mGuided(guided && mIllumination->cache),
          mLightShare(mGuided && in.scene.desc.experiments.volumeSampling != VolumeSampling::Distance
                          ? LightDistanceShare
                          : 0.0) {
        if (mGuided) mMeanGuided = measureMeanGuided();
    }

private:
    // Eq. 17's scale: the mean histogram integral of the camera-ray segments
    // through scattering media, over a grid of pixel-centre camera rays.
    // Deterministic (fixed ray seeds).
    double measureMeanGuided() const {
        ThreadContext ctx(mScene);
        MarcherScratch& m = scratch(ctx);
        m.measureOnly = true;
        const int w = mScene.camera->width(), h = mScene.camera->height();
        for (int j = 0; j < ProbeHeight; ++j)
            for (int i = 0; i < ProbeWidth; ++i) {
                Rng rng(hashValues(0x707265706173, uint64_t(j * ProbeWidth + i)));
                float x = (float(i) + 0.5f) * float(w) / ProbeWidth, y = (float(j) + 0.5f) * float(h) / ProbeHeight;
                radiance(mScene.camera->generateRay(x, y), rng, ctx);
            }
        // Per segment through a scattering medium, not per camera ray: rays
        // that miss the media take no samples, so the mean N over the
        // segments that do stays render.ray_samples, as for transmittance.
        return m.measuredSegments > 0 ? m.measuredGuided / double(m.measuredSegments) : 0.0;
    }

    int sampleCount(const RayPdf& pdf, const Color& beta) const {
        const int M = mScene.desc.render.raySamples;
        if (!mGuided || !(mMeanGuided > 0)) return M;
        double share = double(average(beta)) * pdf.guidedIntegral() / mMeanGuided;
        double n = std::round(double(M) * share);
        return int(std::clamp(n, double(std::max(1, M / MinSamplesDivisor)), double(MaxSamplesFactor * M)));
    }

    // Whether a segment gathers the photons at one of its L_i samples
    // rather than at each: with render.li = "path" where the map holds
    // caustics alone. Not the multiply scattered light of point and spot
    // lights (pointLightsByPhotons), which varies along a ray as 1 / d^2
    // near the light, so one gather weighted by n has far more variance
    // (measured: docs/benchmarks/history.md, "Photons gathered within their
    // medium region"). Nor the paper's "photons", which gathers at every
    // sample.
    bool gathersOncePerSegment() const {
        const Illumination& il = *mIllumination;
        return il.li == LiSource::Path && il.indirect && !il.pointLightsByPhotons;
    }

    bool marchSegment(ThreadContext& ctx, int region, const Ray& ray, float tEnd, Rng& rng, Color& L,
                      Color& beta) const override {
        const Scene& scene = mScene;
        bool infiniteTail;
        if (!activeIntervals(ctx, region, ray, tEnd, infiniteTail)) return true;
        MarcherScratch& m = scratch(ctx);
        const bool scatter = scatters(ctx);  // else emission and transmittance only
        auto& steps = m.pdfSteps;
        steps.clear();
        m.stepSigmaS.clear();
        m.stepKappa.clear();
        m.stepT.clear();
        m.stepH.clear();
        CacheLookup* cache = mGuided ? &cacheLookup(ctx) : nullptr;
        if (cache) cache->setDirection(-ray.d);

        // The walk: steps [k dx, (k + 1) dx) clipped to the active
        // intervals, the medium taken at one jittered point per step. The
        // media of WalkBatch steps are looked up first, in a loop of
        // independent lookups the core can overlap (a lookup's latency is
        // a few times its throughput), then the steps are taken in order.
        // Roulette may end the walk inside a batch: the rest were looked up
        // for nothing, never used (the pixels are those of a step-by-step
        // walk).
        const double dx = double(scene.step);
        const double u = double(rng.uniform());
        Color T(1);  // from the segment's start
        bool ended = false;
        MediumPoint* media = m.walkMedia;
        double stepA[WalkBatch], stepB[WalkBatch];
        Vec3 stepX[WalkBatch];
        for (const Interval& iv : ctx.intervals) {
            double k = std::floor(double(iv.t0) / dx);
            while (!ended) {
                int n = 0;
                for (; n < WalkBatch; k += 1) {
                    const double a = std::max(double(iv.t0), k * dx), b = std::min(double(iv.t1), (k + 1) * dx);
                    if (a >= double(iv.t1)) break;
                    if (!(b > a)) continue;
                    stepA[n] = a;
                    stepB[n] = b;
                    stepX[n] = ray.at(float(a + u * (b - a)));
                    ++n;
                }
                for (int i = 0; i < n; ++i) evalMedia(ctx, region, stepX[i], media[i]);
                for (int i = 0; i < n && !ended; ++i) {
                    const MediumPoint& mp = media[i];
                    const double a = stepA[i], b = stepB[i];
                    ++ctx.counters.marchSamples;
                    if (isBlack(mp.sigma_t)) continue;
                    const float len = float(b - a);
                    const StepTerms st = stepTerms(mp, len);
                    if (!isBlack(mp.emission)) {
                        L += beta * T * st.absorbedA * mp.emission;
                        tallyEmission(ctx, beta * T * st.absorbedA * mp.emission);
                    }
                    // sigma_s T(t0) S(kappa, len)
                    const float base = scatter && mp.scatters() ? average(T * st.absorbedS) : 0.f;
                    if (base > 0) {
                        steps.push_back({float(a), len, average(mp.sigma_t), base});
                        m.stepSigmaS.push_back(mp.sigma_s);
                        m.stepKappa.push_back(mp.sigma_t);
                        m.stepT.push_back(T);
                        if (cache) m.stepH.push_back(cache->at(stepX[i]));
                    }
                    T *= st.T;
                    // Russian roulette on the rest of the segment; the steps
                    // already taken keep their weights, later ones carry 1/q.
                    const float q = rouletteSurvival(beta * T);
                    if (q < 1) {
                        if (!(q > 0) || rng.uniform() >= q) {
                            T = Color(0);
                            ended = true;
                        } else {
                            T /= q;
                        }
                    }
                }
                if (n < WalkBatch) break;  // the interval is done
            }
            if (ended) break;
        }

        if (!steps.empty()) {
            RayPdf& pdf = m.rayPdf;
            pdf.build(steps, cache ? m.stepH.data() : nullptr);
            if (m.measureOnly) {
                if (pdf.valid()) ++m.measuredSegments;
                m.measuredGuided += double(average(beta)) * pdf.guidedIntegral();
            } else if (pdf.valid()) {
                // N stratified positions (one uniform per stratum of the CDF).
                const int n = sampleCount(pdf, beta);
                // Towards point, spot and sphere lights near the segment, the
                // mixture with their equiangular densities (RayPdf::
                // sampleWithLights). The samplers are copied: the L_i paths
                // prepare their own in the same ThreadContext.
                auto& lights = m.lightDistances;
                lights.clear();
                const StrategySet& strategies = mPaths.strategies();
                if (mLightShare > 0 &&
                    strategies.lightDistances().prepare(ctx, PathSegment{ray, region, HeroChannel{}, tEnd, false}))
                    lights = strategies.lightDistances().prepared(ctx);
                const double a = lights.empty() ? 0.0 : mLightShare;
                FoldSampler& folds = m.foldDistances;
                const bool crossesFolds =
                    mLightShare > 0 && strategies.causticFolds().crossings(region, ray, tEnd, folds);
                const RayPdf::Mixture mixture{a, &lights, crossesFolds ? FoldDistanceShare : 0.0, &folds};
                MediumPoint ms;
                // The caustic photons at one of the n samples, drawn uniformly
                // and weighted by n: each sample is gathered with probability
                // 1 / n, so the sum is unbiased. The gather is the dearest
                // part of an L_i sample, while the paths' noise wants every
                // sample. (-1: every sample gathers.)
                const int gatherAt =
                    gathersOncePerSegment() && n > 1 ? std::min(n - 1, int(rng.uniform() * float(n))) : -1;
                for (int j = 0; j < n; ++j) {
                    int k;
                    float offset, t;
                    double p;
                    if (!pdf.sampleMixture((double(j) + rng.uniformDouble()) / double(n), mixture, k, offset, p, t))
                        continue;
                    const Vec3 x = ray.at(t);
                    evalMedia(ctx, region, x, ms);  // the phase mixture at x
                    const float photonWeight = gatherAt < 0 ? 1.f : j == gatherAt ? float(n) : 0.f;
                    const Color Li = inScattered(ctx, region, x, ray.d, ms, rng, 1.f, photonWeight);
                    if (isBlack(Li)) continue;
                    Color Tt = m.stepT[size_t(k)];
                    for (int c = 0; c < 3; ++c) Tt[c] *= std::exp(-m.stepKappa[size_t(k)][c] * offset);
                    const Color weight = beta * Tt * m.stepSigmaS[size_t(k)];
                    L += weight * Li * float(1.0 / (double(n) * p));
                    if (mTallyDirect) tallyInScattered(ctx, weight * float(1.0 / (double(n) * p)));
                }
            }
        }
        beta *= T;
        if (ended) return false;
        if (infiniteTail) applyInfiniteTail(region, beta);
        return true;
    }

    const bool mGuided;
    // The mixture share of the equiangular density (0: the paper's pdf alone).
    const double mLightShare;
    double mMeanGuided = 0;
};

}  // namespace

std::unique_ptr<Estimator> makeTransmittanceMarcher(const EstimatorInputs& in) {
    return std::make_unique<SampledMarcher>(in, false);
}

std::unique_ptr<Estimator> makeGuidedMarcher(const EstimatorInputs& in) { return std::make_unique<SampledMarcher>(in, true); }

}  // namespace vdbmarch
