// The factory table: every Method has a marcher (so suites that run over
// estimatorMethods() cover every method a scene can ask for), and each one
// makes a marcher that answers a camera ray.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/rng.h"
#include "estimators/estimator.h"
#include "parse/method.h"
#include "support/support.h"
#include "transport/thread_context.h"

namespace vdbmarch {
namespace {

using namespace test;

TEST(EstimatorFactory, HasAnEntryForEveryMethod) {
    const std::vector<Method> factory = estimatorMethods();
    const std::set<Method> fromFactory(factory.begin(), factory.end());
    const std::set<Method> all(allMethods().begin(), allMethods().end());
    EXPECT_EQ(fromFactory.size(), factory.size()) << "a method is listed twice in the factory table";
    EXPECT_EQ(fromFactory, all) << "estimatorMethods() and allMethods() differ";
}

class EstimatorFactoryMethods : public ::testing::TestWithParam<Method> {};

// An absorbing box in front of the camera: every marcher returns finite
// radiance and a transmittance in [0, 1] per ray, and sees the box: the
// transmittance through 2 units of sigma_a = 1 is exp(-2) in expectation,
// and so is the white background's radiance behind it (nothing scatters).
// Within 4 standard errors, or 1e-4 where the estimate is deterministic.
TEST_P(EstimatorFactoryMethods, MakesAMarcherThatAnswersARay) {
    auto scene = sceneFromJson(R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [4, 4]},
        "media": [{"type": "homogeneous", "sigma_a": 1, "sigma_s": 0,
                   "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
        "background": [1, 1, 1], "render": {"step": 0.01}})");
    auto marcher = makeEstimator(GetParam(), *scene);
    ASSERT_NE(marcher, nullptr);
    ThreadContext ctx(*scene);
    Rng rng(1);
    SampleStats transmittance, radiance;
    for (int i = 0; i < 256; ++i) {
        PathRadiance r = marcher->radiance(Ray{Vec3(0, 0, 3), Vec3(0, 0, -1)}, rng, ctx);
        ASSERT_TRUE(isFinite(r.L));
        ASSERT_GE(r.transmittance, 0.f);
        ASSERT_LE(r.transmittance, 1.f);
        transmittance.add(r.transmittance);
        radiance.add(average(r.L));
    }
    const double expected = std::exp(-2.0);
    EXPECT_NEAR(transmittance.mean(), expected, std::max(4 * transmittance.stdError(), 1e-4));
    EXPECT_NEAR(radiance.mean(), expected, std::max(4 * radiance.stdError(), 1e-4));
}

INSTANTIATE_TEST_SUITE_P(Methods, EstimatorFactoryMethods, ::testing::ValuesIn(estimatorMethods()), methodParamName);

}  // namespace
}  // namespace vdbmarch
