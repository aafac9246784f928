// Shadow-ray transmittance against quadrature: along rays through the sample
// cloud (a heterogeneous VDB grid, vdb_samples/cloud.vdb), the mean of each
// unbiased estimator (residual ratio tracking against each block's density
// bounds; unbiased ray marching) must equal exp(-k integral of the density),
// the integral taken by a fine midpoint rule over the trilinear density
// itself; unbiased ray marching must be the quieter of the two; and the
// majorant segments must bound the density from above and below.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/rng.h"
#include "core/sampling.h"
#include "transport/thread_context.h"
#include "transport/transmittance.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

struct CloudRays {
    std::unique_ptr<Scene> scene;
    std::vector<Ray> rays;
    std::vector<float> lengths;
};

// Rays from points around the cloud towards points near its centre, through
// thin edges and the dense core.
CloudRays cloudRays() {
    CloudRays c;
    c.scene = buildScene(loadSceneFile(samplePath("cloud.json")));
    const BBox b = c.scene->media[0]->worldBounds();
    const Vec3 centre = b.center(), ext = b.extent();
    Rng rng(17, 3);
    for (int i = 0; i < 12; ++i) {
        const Vec3 target = centre + Vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f) * ext * 0.6f;
        const Vec3 from = centre + sampleUniformSphere(rng.uniform(), rng.uniform()) * (length(ext) * 0.75f);
        c.rays.push_back(Ray{from, normalize(target - from)});
        c.lengths.push_back(length(target - from) * (1 + rng.uniform()));  // ends inside or beyond the cloud
    }
    return c;
}

// Mean and variance of an estimator along each ray against quadrature.
void checkAgainstQuadrature(TransmittanceEstimator estimator, std::vector<double>& variances) {
    CloudRays c = cloudRays();
    ThreadContext ctx(*c.scene);
    MediumQuery& q = *ctx.queries[0];
    const Medium& m = *c.scene->media[0];
    const Color k = m.sigma_a + m.sigma_s;
    int dense = 0;
    for (size_t i = 0; i < c.rays.size(); ++i) {
        const Ray& r = c.rays[i];
        const float len = c.lengths[i];
        const int n = 20000;
        double integral = 0;
        for (int j = 0; j < n; ++j) integral += double(q.density(r.at((j + 0.5) * double(len) / n))) * len / n;
        const double expected = std::exp(-double(k.x) * integral);
        if (expected < 0.5) ++dense;
        Rng rng(5, uint64_t(i));
        SampleStats st;
        for (int s = 0; s < 20000; ++s) st.add(regionTransmittance(ctx, 0, r, len, rng, estimator).x);
        EXPECT_NEAR(st.mean(), expected, 4 * st.stdError() + 1e-4) << "ray " << i << " optical depth " << k.x * integral;
        variances.push_back(st.variance());
    }
    EXPECT_GE(dense, 3);  // the rays do cross the cloud
}

TEST(Transmittance, RatioTrackingMatchesQuadratureThroughAVdbCloud) {
    std::vector<double> v;
    checkAgainstQuadrature(TransmittanceEstimator::RatioTracking, v);
}

TEST(Transmittance, UnbiasedMarchingMatchesQuadratureAndIsQuieterThanRatioTracking) {
    std::vector<double> marching, tracking;
    checkAgainstQuadrature(TransmittanceEstimator::UnbiasedMarching, marching);
    checkAgainstQuadrature(TransmittanceEstimator::RatioTracking, tracking);
    double sumMarching = 0, sumTracking = 0;
    for (size_t i = 0; i < marching.size(); ++i) {
        sumMarching += marching[i];
        sumTracking += tracking[i];
        std::printf("ray %zu: variance %.3g (marching), %.3g (ratio tracking)\n", i, marching[i], tracking[i]);
    }
    // The point of the estimator: the noise of next-event estimation's shadow rays.
    EXPECT_LT(sumMarching, 0.5 * sumTracking);
}

TEST(Transmittance, DensityBoundsBoundTheDensityFromBothSides) {
    CloudRays c = cloudRays();
    ThreadContext ctx(*c.scene);
    MediumQuery& q = *ctx.queries[0];
    int checked = 0, withControl = 0;
    for (size_t i = 0; i < c.rays.size(); ++i) {
        const Ray& r = c.rays[i];
        q.forEachDensityBound(r, 0.f, c.lengths[i], [&](const DensityBound& s) {
            EXPECT_LE(s.minDensity, s.maxDensity);
            withControl += s.minDensity > 0;
            for (int j = 0; j < 64; ++j) {
                const float d = q.density(r.at(s.t0 + (j + 0.5f) / 64 * (s.t1 - s.t0)));
                EXPECT_LE(d, s.maxDensity * (1 + 1e-5f));
                EXPECT_GE(d, s.minDensity * (1 - 1e-5f));
                ++checked;
            }
            return true;
        });
    }
    EXPECT_GT(checked, 1000);
    EXPECT_GT(withControl, 0);  // some blocks give the residual tracker a control
}

}  // namespace
}  // namespace vdbmarch
