// Baseline (i) of the paper: ray marching with a uniform step and one random
// offset per ray segment (eq. 5), with L_i estimated at every step.
//
// Per step of length dx at x_k the source term is integrated exactly under the
// constant-medium assumption of eq. 5: the step contributes
//   T_k * S(x_k, dx) * (sigma_a L_e + sigma_s L_i),  S = (1 - e^{-kappa dx}) / kappa  (eq. 7)
// and T_{k+1} = T_k e^{-kappa dx}. S replaces eq. 5's dx so optically thick
// steps cannot over-count (S -> dx as kappa dx -> 0). S sigma_x is evaluated as
// (1 - e^{-kappa dx}) (sigma_x / kappa) so that no product can overflow.
#include <algorithm>
#include <cmath>

#include "estimators/segment_marcher.h"
#include "transport/roulette.h"

namespace vdbmarch {

namespace {

class UniformMarcher final : public SegmentMarcher {
public:
    using SegmentMarcher::SegmentMarcher;

private:
    bool marchSegment(ThreadContext& ctx, int region, const Ray& ray, float tEnd, Rng& rng, Color& L,
                      Color& beta) const override {
        const Scene& scene = mScene;
        bool infiniteTail;
        if (!activeIntervals(ctx, region, ray, tEnd, infiniteTail)) return true;
        const float dx = scene.step;
        const float u = rng.uniform();  // one random offset per segment (eq. 5 with jitter)
        // L_i at every step, but continuation paths (render.li = "path") at
        // render.ray_samples of the segment's steps on average, as the
        // sampled marchers take: each step traces one with probability q.
        double activeLength = 0;
        for (const Interval& iv : ctx.intervals) activeLength += double(std::min(iv.t1, 1e30f) - iv.t0);
        const float q = activeLength > 0 ? float(std::min(1.0, double(scene.desc.render.raySamples) * dx / activeLength))
                                         : 1.f;
        MediumPoint mp;
        for (const Interval& iv : ctx.intervals) {
            // Lattice index in double: k + 1 must never round back to k.
            double k = std::ceil(double(iv.t0) / dx - u);
            for (double t = (k + u) * dx; t < iv.t1; k += 1, t = (k + u) * dx) {
                Vec3 x = ray.at(float(t));
                evalMedia(ctx, region, x, mp);
                ++ctx.counters.marchSamples;
                if (isBlack(mp.sigma_t)) continue;
                Color Li = inScattered(ctx, region, x, ray.d, mp, rng, q);
                StepTerms st = stepTerms(mp, dx);
                L += beta * (st.absorbedA * mp.emission + st.absorbedS * Li);
                if (!isBlack(mp.emission)) tallyEmission(ctx, beta * st.absorbedA * mp.emission);
                if (mTallyDirect) tallyInScattered(ctx, beta * st.absorbedS);
                beta *= st.T;
                if (!russianRoulette(beta, rng)) {
                    beta = Color(0);
                    return false;
                }
            }
        }
        if (infiniteTail) applyInfiniteTail(region, beta);
        return true;
    }
};

}  // namespace

std::unique_ptr<Estimator> makeUniformMarcher(const EstimatorInputs& in) { return std::make_unique<UniformMarcher>(in); }

}  // namespace vdbmarch
