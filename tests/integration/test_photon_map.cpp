// The photon map's in-scattered radiance (eq. 4, with photons stored at
// every real collision with weight Phi / sigma_t) against independent
// truths: the closed form of single scattering from a point light, and the
// unbiased reference path tracer for the multiply scattered light, for an
// isotropic and a strongly forward-scattering medium.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include <tbb/task_arena.h>

#include "core/sampling.h"
#include "estimators/estimator.h"
#include "illumination/illumination.h"
#include "photons/photon_map.h"
#include "photons/photon_tracer.h"
#include "strategies/sphere_caustics.h"
#include "support/support.h"
#include "transport/phase.h"

namespace vdbmarch {
namespace {

using test::sceneFromJson;

constexpr float SigmaA = 0.25f, SigmaS = 1.f, Intensity = 10.f;
const Vec3 LightPos(0, 3, 0);

// Unit-radius-ish box of homogeneous medium under a point light.
std::string boxScene(float g, int maxDepth) {
    return str(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
        "lights": [{"type": "point", "position": [0, 3, 0], "intensity": [10, 10, 10]}],
        "media": [{"name": "m", "type": "homogeneous", "sigma_a": [0.25, 0.25, 0.25], "sigma_s": [1, 1, 1],
                   "g": )", g, R"(, "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
        "render": {"max_depth": )", maxDepth, R"(, "seed": 3}})");
}

// Light that reaches x straight from the point light: p I T / d^2.
float directLi(const Vec3& x, const Vec3& wo, float g) {
    Vec3 travel = x - LightPos;
    float d = length(travel);
    travel = travel / d;
    // The segment inside the box ends at its top face y = 1 (probes lie under the light).
    float inside = (1 - x.y) / -travel.y;
    return hgPhase(dot(travel, wo), g) * Intensity / (d * d) * std::exp(-(SigmaA + SigmaS) * inside);
}

// The uniform-kernel estimate sees L_i averaged over its gathering sphere:
// the same average of the closed form (deterministic quadrature points), so
// the comparison tests the normalisation, not the kernel's blur.
float directLiOverBall(const Vec3& x, const Vec3& wo, float g, float radius) {
    double sum = 0;
    int n = 0;
    Rng rng(4242);
    while (n < 20000) {
        Vec3 u(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
        if (lengthSquared(u) > 1) continue;
        sum += directLi(x + u * radius, wo, g);
        ++n;
    }
    return float(sum / n);
}

struct PhotonEstimate {
    double mean = 0, stdError = 0;
};

PhotonEstimate meanAndError(const std::vector<double>& v) {
    double m = 0, s = 0;
    for (double x : v) m += x;
    m /= double(v.size());
    for (double x : v) s += (x - m) * (x - m);
    return {m, std::sqrt(s / double(v.size() - 1) / double(v.size()))};
}

// L_i scattered at least once before x (up to depth - 1 events), by the
// reference tracer: phase-sample the light's travel direction t' around wo
// and take the radiance arriving along it.
PhotonEstimate referenceIndirect(const Scene& scene, const Vec3& x, const Vec3& wo, float g, int samples) {
    auto tracer = makeEstimator(Method::Reference, scene);
    ThreadContext ctx(scene);
    std::vector<double> v;
    v.reserve(size_t(samples));
    for (int i = 0; i < samples; ++i) {
        Rng rng(hashValues(77, uint64_t(i)));
        Vec3 travel = directionAround(wo, sampleHgCosTheta(rng.uniform(), g), rng.uniform());
        v.push_back(average(tracer->radiance(Ray{x, -travel}, rng, ctx).L));
    }
    return meanAndError(v);
}

void checkAgainstTruth(float g) {
    const int depth = 3;
    auto scene = sceneFromJson(boxScene(g, depth));
    auto shorter = sceneFromJson(boxScene(g, depth - 1));  // paths that end one event before x
    const Vec3 probes[] = {{0.2f, 0.1f, -0.3f}, {-0.4f, -0.5f, 0.3f}};
    const Vec3 dirs[] = {{0, -1, 0}, {1, 0, 0}, normalize(Vec3(0, 1, 1))};
    const int seeds = 8;
    const size_t k = 100;
    // Independent photon maps give the estimate's standard error.
    std::vector<std::vector<double>> direct(6), indirect(6), smoothedTruth(6);
    for (int s = 0; s < seeds; ++s) {
        PhotonSet set = tracePhotons(*scene, 100000, uint64_t(100 + s));
        std::vector<Photon> d, n;
        for (const Photon& p : set.photons) (p.isDirect() ? d : n).push_back(p);
        PhotonMap directMap(std::move(d)), indirectMap(std::move(n));
        auto phase = [&](float c) { return Color(hgPhase(c, g)); };
        for (int pi = 0; pi < 2; ++pi)
            for (int di = 0; di < 3; ++di) {
                float r = 0;
                direct[size_t(pi * 3 + di)].push_back(
                    average(directMap.estimateLi(probes[pi], dirs[di], k, phase, &r)));
                smoothedTruth[size_t(pi * 3 + di)].push_back(directLiOverBall(probes[pi], dirs[di], g, r));
                indirect[size_t(pi * 3 + di)].push_back(
                    average(indirectMap.estimateLi(probes[pi], dirs[di], k, phase)));
            }
    }
    for (int pi = 0; pi < 2; ++pi)
        for (int di = 0; di < 3; ++di) {
            const Vec3& x = probes[pi];
            const Vec3& wo = dirs[di];
            PhotonEstimate pd = meanAndError(direct[size_t(pi * 3 + di)]);
            double truth = meanAndError(smoothedTruth[size_t(pi * 3 + di)]).mean;
            EXPECT_NEAR(pd.mean, truth, 4 * pd.stdError)
                << "direct photons, g " << g << " probe " << pi << " direction " << di << " (SE " << pd.stdError << ")";
            PhotonEstimate pn = meanAndError(indirect[size_t(pi * 3 + di)]);
            PhotonEstimate ref = referenceIndirect(*shorter, x, wo, g, 20000);
            double se = std::sqrt(pn.stdError * pn.stdError + ref.stdError * ref.stdError);
            EXPECT_NEAR(pn.mean, ref.mean, 4 * se) << "scattered photons vs reference, g " << g << " probe " << pi
                                                   << " direction " << di;
            EXPECT_GT(ref.mean, 0);
            if (std::getenv("VDBMARCH_VERBOSE"))
                std::printf("g %.2f probe %d dir %d: direct %.4g +- %.2g (truth %.4g, point %.4g); scattered %.4g +- %.2g, reference %.4g +- %.2g\n", g, pi, di, pd.mean, pd.stdError, truth, directLi(x, wo, g), pn.mean, pn.stdError, ref.mean, ref.stdError);
        }
}

TEST(PhotonMapAccuracy, IsotropicMatchesClosedFormAndReference) { checkAgainstTruth(0.f); }

TEST(PhotonMapAccuracy, ForwardScatteringMatchesClosedFormAndReference) { checkAgainstTruth(0.9f); }

TEST(PhotonTracing, DeterministicForAnyThreadCount) {
    auto scene = sceneFromJson(boxScene(0.5f, 4));
    PhotonSet one, two;
    tbb::task_arena(1).execute([&] { one = tracePhotons(*scene, 100000, 5); });
    tbb::task_arena(2).execute([&] { two = tracePhotons(*scene, 100000, 5); });
    ASSERT_GT(one.photons.size(), 10000u);
    ASSERT_EQ(one.photons.size(), two.photons.size());
    EXPECT_EQ(0, std::memcmp(one.photons.data(), two.photons.data(), one.photons.size() * sizeof(Photon)));
}

TEST(PhotonTracing, StoresNothingWithoutScattering) {
    auto scene = sceneFromJson(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
        "lights": [{"type": "point", "position": [0, 3, 0], "intensity": [10, 10, 10]}],
        "media": [{"name": "m", "type": "homogeneous", "sigma_a": [1, 1, 1], "sigma_s": [0, 0, 0],
                   "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}]})");
    EXPECT_FALSE(sceneScatters(*scene));
    PhotonSet set = tracePhotons(*scene, 1000, 1);
    EXPECT_EQ(set.paths, 0u);
    EXPECT_TRUE(set.photons.empty());
}

TEST(PhotonTracing, LightsThatCannotReachAMediumEmitNothing) {
    // A spot aimed away from the medium shares no photons with the point light.
    auto scene = sceneFromJson(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
        "lights": [{"type": "point", "position": [0, 3, 0], "intensity": [1, 1, 1]},
                   {"type": "spot", "position": [0, 3, 0], "direction": [0, 1, 0], "intensity": [1000, 1000, 1000],
                    "cone_deg": 20}],
        "media": [{"name": "m", "type": "homogeneous", "sigma_a": [0, 0, 0], "sigma_s": [1, 1, 1],
                   "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}]})");
    PhotonSet set = tracePhotons(*scene, 5000, 1);
    EXPECT_EQ(set.paths, 5000u);
    // All the emitted power is the point light's, in its cone towards the box.
    Color pointPower = PhotonEmitter::forLight(scene->lights[0], photonTarget(*scene)).power();
    EXPECT_EQ(set.emittedPower.x, pointPower.x);
    EXPECT_LT(pointPower.x, 4 * Pi);
    EXPECT_GT(set.photons.size(), 0u);
}

TEST(PhotonStorage, CompactDirectionAndPhase) {
    EXPECT_EQ(sizeof(Photon), 32u);
    Rng rng(9);
    for (int i = 0; i < 10000; ++i) {
        Vec3 d = sampleUniformSphere(rng.uniform(), rng.uniform());
        EXPECT_LT(length(decodeDirection(encodeDirection(d)) - d), 1e-4f);  // ~3e-5 rad quantisation
    }
    for (float g : {-0.999f, -0.3f, 0.f, 0.85f, 0.999f}) {
        Photon p{};
        p.flags = Photon::packFlags(Photon::Direct, g);
        EXPECT_TRUE(p.isDirect());
        EXPECT_FALSE(p.isCaustic());
        EXPECT_NEAR(p.g(), g, 1.f / 32767);
        p.flags = Photon::packFlags(Photon::Caustic | Photon::FromPointLight, g);
        EXPECT_FALSE(p.isDirect());
        EXPECT_TRUE(p.isCaustic());
        EXPECT_TRUE(p.isFromPointLight());
        EXPECT_NEAR(p.g(), g, 1.f / 32767);
        EXPECT_EQ(p.region(), 0);
        for (int region : {1, 7, Photon::MaxRegion}) {
            p.flags = Photon::packFlags(Photon::Caustic | Photon::Connected, g, region);
            EXPECT_EQ(p.region(), region);
            EXPECT_TRUE(p.isCaustic() && p.isConnected() && !p.isDirect() && !p.isFromPointLight());
            EXPECT_NEAR(p.g(), g, 1.f / 32767);
        }
        p.flags = Photon::packFlags(0, g, Photon::MaxRegion + 5);  // beyond: shares the last
        EXPECT_EQ(p.region(), Photon::MaxRegion);
    }
}

// Search::ByRegion: the k nearest of the query's region, exactly those a
// brute-force search over that region's photons finds, whatever lies
// nearer on the other side of a boundary.
TEST(PhotonMapRegions, NearestAreTheNearestOfTheQuerysRegion) {
    Rng rng(21);
    std::vector<Photon> photons(6000);
    for (Photon& p : photons) {
        p.position = Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 2.f - Vec3(1.f);
        p.direction = encodeDirection(Vec3(0, 0, 1));
        // Region 1 is the ball of radius 0.5 and is dense; region 0 the rest.
        const int region = length(p.position) < 0.5f ? 1 : rng.uniform() < 0.5f ? 0 : 3;
        p.weight = Color(region == 1 ? 0.005f : 1.f);
        p.flags = Photon::packFlags(0, 0.f, region);
    }
    const PhotonMap all(photons), byRegion(photons, PhotonMap::Search::ByRegion);
    constexpr size_t K = 20;
    uint32_t idx[K];
    float d2[K];
    int checked = 0;
    for (int q = 0; q < 200; ++q) {
        // Queries near the ball's surface, on either side.
        const Vec3 x = sampleUniformSphere(rng.uniform(), rng.uniform()) * (0.45f + 0.1f * rng.uniform());
        for (int region : {0, 1, 2, 3}) {
            std::vector<float> brute;
            for (const Photon& p : photons)
                if (p.region() == region) brute.push_back(lengthSquared(p.position - x));
            std::sort(brute.begin(), brute.end());
            const size_t n = byRegion.nearest(x, K, idx, d2, region);
            ASSERT_EQ(n, std::min(K, brute.size()));
            for (size_t i = 0; i < n; ++i) {
                EXPECT_EQ(byRegion[idx[i]].region(), region);
                EXPECT_FLOAT_EQ(d2[i], lengthSquared(byRegion[idx[i]].position - x));
                EXPECT_FLOAT_EQ(d2[i], brute[i]);
            }
            checked += int(n);
        }
        // Search::All ignores the region.
        const size_t n = all.nearest(x, K, idx, d2, 1);
        ASSERT_EQ(n, K);
        std::vector<float> brute;
        for (const Photon& p : photons) brute.push_back(lengthSquared(p.position - x));
        std::sort(brute.begin(), brute.end());
        for (size_t i = 0; i < n; ++i) EXPECT_FLOAT_EQ(d2[i], brute[i]);
    }
    EXPECT_GT(checked, 200 * 3 * int(K) - 1);  // regions 0, 1 and 3 hold photons; 2 none
}

// Photons carry the region they landed in: those inside a glass ball
// holding a medium are the interior's, the rest the world's.
TEST(PhotonTracing, PhotonsCarryTheRegionTheyLandedIn) {
    auto scene = buildScene(loadSceneFile(test::samplePath("scenes/exp1_sphere.json"), {}));
    ASSERT_GT(scene->regions.size(), 1u);
    const PhotonSet set = tracePhotons(*scene, 20000, 3);
    std::vector<size_t> perRegion(scene->regions.size(), 0);
    for (const Photon& p : set.photons) {
        ASSERT_LT(size_t(p.region()), scene->regions.size());
        ++perRegion[size_t(p.region())];
        // The region a ray from the photon's position finds itself in.
        EXPECT_EQ(p.region(), regionAtRayStart(*scene, Ray{p.position, Vec3(0.267f, 0.534f, 0.802f)}))
            << "photon at " << p.position.x << " " << p.position.y << " " << p.position.z;
    }
    // The fog around the knot and the milk inside it.
    EXPECT_EQ(std::count_if(perRegion.begin(), perRegion.end(), [](size_t n) { return n > 0; }), 2);
}

}  // namespace
}  // namespace vdbmarch

namespace vdbmarch {
namespace {

// Photon::Connected marks the caustic photons whose light sphere caustic
// connections compute at the photon's position: each must be a caustic of
// the point light that came straight out of the ball from it. The
// marchers' map (render.li = "path") then leaves them out, and only those.
TEST(PhotonTracing, ConnectedPhotonsAreTheCausticsTheConnectionsFind) {
    auto scene = buildScene(loadSceneFile(test::samplePath("scenes/fig4_caustic.json"), {}));
    ASSERT_TRUE(scene->deltaLightCaustics);
    const PhotonSet set = tracePhotons(*scene, 100000, 5);
    const GlassSphere& ball = scene->glassSpheres.at(0);
    const Vec3 light = scene->lights.at(0).desc().position;
    size_t connected = 0, caustic = 0;
    for (const Photon& p : set.photons) {
        caustic += p.isCaustic();
        if (!p.isConnected()) continue;
        ++connected;
        EXPECT_TRUE(p.isCaustic() && p.isFromPointLight() && !p.isDirect());
        // Back along its travel through the ball, the photon's path must
        // leave towards the light (within the 32-bit direction's precision).
        SphereConnection tr;
        ASSERT_TRUE(traceThroughSphere(ball, p.position, -p.travelDirection(), tr));
        const Vec3 v = light - tr.p2;
        EXPECT_GT(dot(v, tr.wo), 0.f);
        EXPECT_LT(length(v - tr.wo * dot(v, tr.wo)), 1e-3f * length(v))
            << "photon at " << p.position.x << " " << p.position.y << " " << p.position.z;
    }
    EXPECT_GT(connected, 100u);
    EXPECT_LT(connected, caustic);  // reflections off the ball and later bounces stay caustic only

    const IlluminationRequest rq = illuminationRequest(*scene, Method::Guided);
    EXPECT_TRUE(rq.exceptConnected);
    const auto off = buildScene(loadSceneFile(test::samplePath("scenes/fig4_caustic.json"), {"experiments.sphere_caustics=false"}));
    EXPECT_FALSE(off->deltaLightCaustics);
    EXPECT_FALSE(illuminationRequest(*off, Method::Guided).exceptConnected);
    for (const Photon& p : tracePhotons(*off, 20000, 5).photons) EXPECT_FALSE(p.isConnected());
}

}  // namespace
}  // namespace vdbmarch
