// Light estimators against closed forms: a sphere light's irradiance by cone
// sampling, a spot light's smooth falloff, a collimated quad's beam.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"
#include "scene/lights.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

// A sphere light of radiance L seen from distance d gives irradiance
// E = pi L (r/d)^2 on a surface facing it; the cone sampler's L/pdf averaged
// with the cosine must match, within 4 standard errors.
TEST(SphereLight, ConeSamplingEstimatesTheIrradianceOfASphere) {
    const LightDesc d = sphereLight(Vec3(0, 0, 3), 1, Color(10));
    const auto light = makeLight(d);
    const double L = light->emittedRadiance().x, r = 1, dist = 3;
    const double expected = M_PI * L * (r / dist) * (r / dist);
    Rng rng(9);
    const int n = 200000;
    double s = 0, s2 = 0;
    for (int i = 0; i < n; ++i) {
        LightSample ls;
        ASSERT_TRUE(light->sample(Vec3(0), rng.uniform(), rng.uniform(), ls));
        double v = ls.L.x * std::max(0.f, ls.wi.z);
        s += v;
        s2 += v * v;
        EXPECT_NEAR(length(ls.wi * ls.dist - d.position), r, 1e-4);  // lands on the sphere
    }
    double mean = s / n, se = std::sqrt((s2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, expected, 4 * se + 1e-9);
}

TEST(SpotLight, SmoothFalloffBetweenConeAndFalloffStart) {
    const auto light = makeLight(spotLight(Vec3(0, 0, 0), Vec3(0, 0, -1), 30, 10, Color(4)));
    auto at = [&](float deg) {
        LightSample ls;
        Vec3 x(std::sin(radians(deg)) * 2, 0, -std::cos(radians(deg)) * 2);
        return light->sample(x, 0, 0, ls) ? ls.L.x : 0.f;
    };
    EXPECT_NEAR(at(0), 1.0, 1e-6);    // I / d^2 = 4 / 4
    EXPECT_NEAR(at(19), 1.0, 1e-6);   // inside the full-intensity core
    EXPECT_GT(at(25), 0.0);
    EXPECT_LT(at(25), 1.0);
    EXPECT_EQ(at(31), 0.0);           // outside the cone
}

TEST(CollimatedQuad, LightsOnlyItsBeam) {
    const auto light = makeLight(quadLight(Vec3(0, 5, 0), Vec3(2, 0, 0), Vec3(0, 0, 1), Vec3(0, -1, 0), Color(3)));
    LightSample ls;
    ASSERT_TRUE(light->sample(Vec3(0.9f, 0, 0.4f), 0, 0, ls));
    EXPECT_NEAR(ls.dist, 5, 1e-5);
    EXPECT_EQ(ls.L.x, 3);
    EXPECT_FALSE(light->sample(Vec3(1.1f, 0, 0), 0, 0, ls));  // beside the quad
    EXPECT_FALSE(light->sample(Vec3(0, 6, 0), 0, 0, ls));     // above the emitter
}

// A spot's reach along a ray (the interval distance sampling draws from)
// against a brute-force walk of the ray, for narrow, wide and
// wider-than-a-hemisphere cones, rays that start inside, outside and at the
// apex. The interval must hold every lit point (it may be a hull).
TEST(SpotLight, ReachIntervalHoldsEveryLitPointOfTheRay) {
    Rng rng(3, 4);
    int withLight = 0;
    for (float cone : {7.f, 30.f, 89.f, 120.f, 180.f}) {
        const auto light = makeLight(spotLight(Vec3(0.2f, 1, -0.5f), normalize(Vec3(0.3f, -1, 0.2f)), cone, 0, Color(1)));
        for (int i = 0; i < 400; ++i) {
            Vec3 o = i % 50 == 0 ? light->desc().position
                                 : Vec3(rng.uniform() * 4 - 2, rng.uniform() * 4 - 2, rng.uniform() * 4 - 2);
            const Vec3 d = sampleUniformSphere(rng.uniform(), rng.uniform());
            const Ray r{o, d};
            float t0 = -1, t1 = -1;
            const bool any = light->reachInterval(r, t0, t1);
            // Lit points on a fine walk of [0, 20].
            float lo = Infinity, hi = -1;
            for (int k = 0; k <= 20000; ++k) {
                const float t = 20.f * float(k) / 20000;
                LightSample ls;
                if (light->sample(r.at(t), 0, 0, ls) && ls.L.x > 0) {
                    lo = std::min(lo, t);
                    hi = std::max(hi, t);
                }
            }
            if (hi < 0) continue;  // nothing lit on the walk (the interval may still be beyond it)
            ++withLight;
            ASSERT_TRUE(any) << "cone " << cone << " ray " << i;
            EXPECT_LE(t0, lo + 2e-3f) << "cone " << cone << " ray " << i;
            EXPECT_GE(t1, hi - 2e-3f) << "cone " << cone << " ray " << i;
            // Tight: the hull's ends are lit (or the ray's start, or beyond the walk).
            if (t0 > 0) {
                EXPECT_NEAR(t0, lo, 2e-3f) << "cone " << cone << " ray " << i;
            }
            if (t1 < 19.99f) {
                EXPECT_NEAR(t1, hi, 2e-3f) << "cone " << cone << " ray " << i;
            }
        }
    }
    EXPECT_GT(withLight, 300);
    // Other lights reach all of the ray.
    const auto point = makeLight(pointLight(Vec3(0), Color(1)));
    float t0, t1;
    ASSERT_TRUE(point->reachInterval(Ray{Vec3(1, 0, 0), Vec3(0, 1, 0)}, t0, t1));
    EXPECT_EQ(t0, 0.f);
    EXPECT_TRUE(std::isinf(t1));
}

// What each kind of light answers to the questions scene set-up and the
// strategies ask instead of testing its type.
TEST(Lights, EachKindAnswersTheInterfacesQueries) {
    Vec3 c;
    float r;
    const auto point = makeLight(pointLight(Vec3(1, 2, 3), Color(1)));
    EXPECT_TRUE(point->isDelta() && point->isPointLike() && !point->atInfinity());
    ASSERT_TRUE(point->emittingBall(c, r));
    EXPECT_EQ(c, Vec3(1, 2, 3));
    EXPECT_EQ(r, 0.f);
    EXPECT_FALSE(point->spotCone() || point->sphere() || point->collimatedQuad());

    const auto spot = makeLight(spotLight(Vec3(0, 1, 0), Vec3(0, -1, 0), 30, 10, Color(1)));
    EXPECT_TRUE(spot->isDelta() && spot->isPointLike());
    ASSERT_TRUE(spot->spotCone());
    EXPECT_EQ(spot->spotCone()->apex, Vec3(0, 1, 0));
    EXPECT_FLOAT_EQ(spot->spotCone()->cosCone, std::cos(radians(30.f)));
    EXPECT_FLOAT_EQ(spot->spotCone()->omcFalloffStart, 1 - std::cos(radians(20.f)));

    const auto sun = makeLight(directionalLight(Vec3(0, -1, 0), Color(1)));
    EXPECT_TRUE(sun->isDelta() && !sun->isPointLike() && sun->atInfinity());
    EXPECT_FALSE(sun->emittingBall(c, r));

    const auto quad = makeLight(quadLight(Vec3(0, 5, 0), Vec3(2, 0, 0), Vec3(0, 0, 1), Vec3(0, -1, 0), Color(3)));
    EXPECT_TRUE(quad->isDelta() && !quad->isPointLike() && !quad->atInfinity());
    EXPECT_FALSE(quad->emittingBall(c, r));  // may be anywhere: shadow reach stays conservative
    ASSERT_TRUE(quad->collimatedQuad());
    EXPECT_EQ(quad->collimatedQuad()->u, Vec3(2, 0, 0));

    const auto sphere = makeLight(sphereLight(Vec3(0, 0, 3), 0.5f, Color(10)));
    EXPECT_TRUE(!sphere->isDelta() && !sphere->isPointLike());
    ASSERT_TRUE(sphere->emittingBall(c, r) && sphere->sphere());
    EXPECT_EQ(r, 0.5f);
    EXPECT_EQ(sphere->sphere()->center, Vec3(0, 0, 3));
    float t;
    EXPECT_TRUE(sphere->intersect(Ray{Vec3(0), Vec3(0, 0, 1)}, 0, Infinity, t));
    EXPECT_NEAR(t, 2.5f, 1e-6f);
    EXPECT_FALSE(point->intersect(Ray{Vec3(0), Vec3(1, 0, 0)}, 0, Infinity, t));
    EXPECT_GT(sphere->directionPdf(Vec3(0)), 0.f);
    EXPECT_EQ(point->directionPdf(Vec3(0)), 0.f);
}

}  // namespace
}  // namespace vdbmarch
