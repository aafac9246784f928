// What the three ray marchers share: their camera paths run the one path
// loop (paths/path_tracer.h) with media crossed by a march of each segment
// (SegmentMarch, the marcher's own), and the one L_i estimate all of them
// use at their samples, so that comparisons are fair.
#pragma once

#include <memory>
#include <vector>

#include "cache/cache_lookup.h"
#include "illumination/illumination.h"
#include "estimators/estimator.h"
#include "estimators/ray_pdf.h"
#include "transport/direct_light.h"
#include "transport/media_point.h"

namespace vdbmarch {

// Steps whose media the sampled marchers' walk looks up together.
constexpr int WalkBatch = 8;

// Per-thread scratch of the marchers (ThreadContext::extension).
struct MarcherScratch final : ThreadContextExtension {
    // The sampled marchers' per-ray histogram: steps, their media, the cache.
    std::vector<PdfStep> pdfSteps;
    std::vector<Color> stepSigmaS, stepKappa, stepT;
    std::vector<float> stepH;
    MediumPoint walkMedia[WalkBatch];  // the media of the walk's next steps
    RayPdf rayPdf;
    std::vector<LightDistance> lightDistances;  // guided: the segment's equiangular samplers
    FoldSampler foldDistances;  // guided: the segment's crossings of caustic folds
    std::unique_ptr<CacheLookup> cacheLookup;  // made on first use
    // The guided marcher's probe of eq. 17's scale: march without sampling
    // and sum each segment's throughput times its histogram integral.
    bool measureOnly = false;
    double measuredGuided = 0;
    size_t measuredSegments = 0;  // segments through scattering media
    // Scattering events of the camera path so far (diffuse bounces): a march
    // sample is one more, and a continuation path starts from there.
    int pathDepth = 0;
    // The direct / indirect AOVs (render.aovs): the camera path's direct
    // part so far, and that of the last inScattered() result.
    Color direct{0}, liDirect{0};
    // PathRadiance::emitted of the camera path so far.
    Color emitted{0};

    // The cache lookup along rays, made on first use.
    CacheLookup& lookup(const RadianceCache& cache);
};

class SegmentMarcher : public Estimator, public SegmentMarch {
public:
    explicit SegmentMarcher(const EstimatorInputs& in);
    PathRadiance radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const override;
    bool march(ThreadContext& ctx, int region, const Ray& ray, float tEnd, int depth, Rng& rng, Color& L,
               Color& beta) const override;

protected:
    // Marches [0, tEnd) of the ray in `region`, adding to L and attenuating
    // beta. Returns false when Russian roulette ended the path. With
    // mTallyDirect it also adds L's direct part by tallyEmission and
    // tallyInScattered. Past max_depth (!scatters(ctx)) emission only.
    virtual bool marchSegment(ThreadContext& ctx, int region, const Ray& ray, float tEnd, Rng& rng, Color& L,
                              Color& beta) const = 0;

    // L_i at x towards -rayDir (eq. 3), by render.li: shadow rays to every
    // light plus a continuation path and the caustic photons ("path"); or
    // shadow rays plus the non-direct photons of eq. 4 ("photons"); or the
    // cached L_i alone ("cache"). mp: the media at x (phase mixture).
    // `pathProbability`: with "path", the continuation path is traced with
    // this probability and weighted by its inverse (Russian roulette), so a
    // marcher that estimates L_i at every step bounds its paths per ray.
    // `photonWeight` scales the photons' part (0: not gathered here; see
    // SampledMarcher::gathersOncePerSegment).
    Color inScattered(ThreadContext& ctx, int region, const Vec3& x, const Vec3& rayDir, const MediumPoint& mp,
                      Rng& rng, float pathProbability = 1, float photonWeight = 1) const;

    // The active intervals of [0, tEnd) (empty space skipped) into
    // ctx.intervals; false when the region holds no media. A ray into
    // unbounded fog stops where its transmittance falls below e^-20
    // (infiniteTail; applyInfiniteTail then sets T(infinity) = 0 in every
    // channel that the fog extinguishes).
    bool activeIntervals(ThreadContext& ctx, int region, const Ray& ray, float tEnd, bool& infiniteTail) const;

    // The direct AOV's share of a segment's contributions: emission `Le`
    // (as added to L) is direct up to the first diffuse bounce; light in-
    // scattered with `weight` (L += weight * L_i) brings the direct part of
    // the last inScattered() result.
    // Emission before the first bounce is also PathRadiance::emitted.
    void tallyEmission(ThreadContext& ctx, const Color& Le) const {
        MarcherScratch& m = scratch(ctx);
        if (mTallyDirect && m.pathDepth <= 1) m.direct += Le;
        if (m.pathDepth == 0) m.emitted += Le;
    }
    void tallyInScattered(ThreadContext& ctx, const Color& weight) const { scratch(ctx).direct += weight * scratch(ctx).liDirect; }
    void applyInfiniteTail(int region, Color& beta) const;
    // Whether march samples of the current segment are scattering events
    // max_depth allows (MarcherScratch::pathDepth).
    bool scatters(ThreadContext& ctx) const { return scratch(ctx).pathDepth < mScene.desc.render.maxDepth; }

    static MarcherScratch& scratch(ThreadContext& ctx) { return ctx.extensionAs<MarcherScratch>(); }
    CacheLookup& cacheLookup(ThreadContext& ctx) const { return scratch(ctx).lookup(*mIllumination->cache); }

    const Scene& mScene;
    std::shared_ptr<const Illumination> mIllumination;
    const bool mChromatic;  // continuation paths track with spectral MIS (HeroChannel)
    const bool mTallyDirect;  // render.aovs asks for direct or indirect
    bool mLastEventByNextEvent = true;  // see the constructor
    PathTracer mPaths;  // continuation paths, with the render's strategies
    PathTracer mCameraPaths;  // camera paths, marched by this
};

// One step of length dx in a medium with extinction kappa: its transmittance,
// and the fraction absorbed and scattered, (1 - e^{-kappa dx}) sigma_x / kappa,
// i.e. S sigma_x of eq. 7, bounded for any kappa.
struct StepTerms {
    Color T, absorbedA, absorbedS;
};
StepTerms stepTerms(const MediumPoint& mp, float dx);

}  // namespace vdbmarch
