// The camera-path loop the three ray marchers share: surfaces (glass refracts
// the camera ray into the medium it holds, interfaces switch regions, diffuse
// surfaces end the path with direct light), sphere lights and the background,
// with a marcher-specific march of each segment between surfaces; and the one
// L_i estimate all of them use at their samples, so that comparisons are fair.
#pragma once

#include <memory>

#include "marchers/illumination.h"
#include "marchers/marcher.h"

namespace vdbmarch {

class SegmentMarcher : public Marcher {
public:
    SegmentMarcher(const Scene& scene, std::shared_ptr<const Illumination> illumination);
    PathResult radiance(const Ray& cameraRay, Rng& rng, ThreadContext& ctx) const override;

protected:
    // Marches [0, tEnd) of the ray in `region`, adding to L and attenuating
    // beta. Returns false when Russian roulette ended the path.
    virtual bool marchSegment(ThreadContext& ctx, int region, const Ray& ray, float tEnd, Rng& rng, Color& L,
                              Color& beta) const = 0;

    // L_i at x towards -rayDir: shadow rays to every light (direct light)
    // plus the non-direct photons of eq. 4 (everything shadow rays cannot
    // reach: multiple scattering, caustics); or, with render.li = "cache",
    // the cached L_i alone. mp: the media at x (phase mixture).
    Color inScattered(ThreadContext& ctx, int region, const Vec3& x, const Vec3& rayDir, const MediumPoint& mp,
                      Rng& rng) const;

    // The active intervals of [0, tEnd) (empty space skipped) into
    // ctx.intervals; false when the region holds no media. A ray into
    // unbounded fog stops where its transmittance falls below e^-20
    // (infiniteTail; applyInfiniteTail then sets T(infinity) = 0 in every
    // channel that the fog extinguishes).
    bool activeIntervals(ThreadContext& ctx, int region, const Ray& ray, float tEnd, bool& infiniteTail) const;
    void applyInfiniteTail(int region, Color& beta) const;

    CacheLookup& cacheLookup(ThreadContext& ctx) const;

    const Scene& mScene;
    std::shared_ptr<const Illumination> mIllumination;
};

// Throughput below which Russian roulette decides whether a ray goes on.
constexpr float RouletteThreshold = 1e-3f;

// One step of length dx in a medium with extinction kappa: its transmittance,
// and the fraction absorbed and scattered, (1 - e^{-kappa dx}) sigma_x / kappa,
// i.e. S sigma_x of eq. 7, bounded for any kappa.
struct StepTerms {
    Color T, absorbedA, absorbedS;
};
StepTerms stepTerms(const MediumPoint& mp, float dx);

}  // namespace vdbmarch
