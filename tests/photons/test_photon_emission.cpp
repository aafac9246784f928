// Photon emission against closed forms: the irradiance the photons deliver to
// small discs inside the target, power() against the photons' mean power and
// closed forms, beam culling, and the cases that must give zero (not NaN).
// Tolerances are 4 standard errors computed from the samples themselves.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "photons/photon_emission.h"
#include "scene/environment.h"
#include "scene/lights.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

BBox makeBox(const Vec3& lo, const Vec3& hi) {
    BBox b;
    b.expand(lo);
    b.expand(hi);
    return b;
}

PhotonTarget boundedTarget(const Vec3& lo, const Vec3& hi) { return {makeBox(lo, hi), false}; }

// Radius of the bounding sphere the emitters use (1% margin).
double targetRadius(const PhotonTarget& t) { return 0.5 * length(t.bounds.extent()) * 1.01; }

// Sum and sum of squares of per-photon contributions (photons that
// contribute nothing count as zeros).
struct Tally {
    double sum = 0, sum2 = 0;
    long hits = 0;
    void add(double v) {
        sum += v;
        sum2 += v * v;
        ++hits;
    }
    double mean(long n) const { return sum / n; }
    double stdErr(long n) const {
        double m = sum / n;
        return std::sqrt(std::max(0.0, sum2 / n - m * m) / (n - 1));
    }
};

// A small test disc; `expected` is the true irradiance on it (channel x).
// One-sided discs count only photons arriving at their front (against n).
struct TestDisc {
    Vec3 x, n;
    double radius;
    double expected;
    bool oneSided = false;
};

struct Shot {
    long n = 0;
    std::vector<Tally> discs;
    Tally power[3];  // every photon's power, per channel
    long badPhotons = 0;  // non-finite origin, direction or power, or power on a miss
};

// Shoots n photons; each disc's tally gets the photon's flux (channel x)
// divided by the disc's area when the photon crosses it.
Shot shoot(const PhotonEmitter& e, const std::vector<TestDisc>& discs, long n, uint64_t seed) {
    Shot s;
    s.n = n;
    s.discs.resize(discs.size());
    Rng rng(seed, 7);
    for (long i = 0; i < n; ++i) {
        float u[4] = {rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()};
        EmittedPhoton p;
        bool ok = e.sample(u, p);
        if (!isFinite(p.ray.o) || !isFinite(p.ray.d) || !isFinite(p.power) || (!ok && !isBlack(p.power)))
            ++s.badPhotons;
        if (!ok) continue;
        for (int c = 0; c < 3; ++c)
            if (p.power[c] != 0) s.power[c].add(p.power[c]);
        for (size_t k = 0; k < discs.size(); ++k) {
            const TestDisc& d = discs[k];
            double cosD = dot(p.ray.d, d.n);
            if (cosD == 0 || (d.oneSided && cosD > 0)) continue;
            double t = dot(d.x - p.ray.o, d.n) / cosD;
            if (!(t > 0)) continue;
            double h[3];
            for (int a = 0; a < 3; ++a) h[a] = double(p.ray.o[a]) + double(p.ray.d[a]) * t - d.x[a];
            if (h[0] * h[0] + h[1] * h[1] + h[2] * h[2] <= d.radius * d.radius)
                s.discs[k].add(p.power.x / (PiD * d.radius * d.radius));
        }
    }
    return s;
}

void expectIrradiance(const Shot& s, const std::vector<TestDisc>& discs, long minHits = 200) {
    EXPECT_EQ(s.badPhotons, 0);
    for (size_t k = 0; k < discs.size(); ++k) {
        const Tally& t = s.discs[k];
        double m = t.mean(s.n), se = t.stdErr(s.n);
        if (discs[k].expected > 0) {
            EXPECT_GE(t.hits, minHits) << "disc " << k << ": too few photons to judge";
        }
        EXPECT_NEAR(m, discs[k].expected, 4 * se + 1e-6 * discs[k].expected)
            << "disc " << k << " hits " << t.hits << " rel.err " << m / discs[k].expected - 1;
    }
}

// power() is the expectation of a photon's power, channel by channel.
void expectPowerIsMean(const PhotonEmitter& e, const Shot& s) {
    for (int c = 0; c < 3; ++c) {
        double m = s.power[c].mean(s.n), se = s.power[c].stdErr(s.n), want = e.power()[c];
        EXPECT_NEAR(m, want, 4 * se + 1e-5 * want) << "channel " << c << " rel.err " << m / want - 1;
    }
}

// Shoots n photons: the discs get their irradiance, and power() is the mean.
void expectIrradianceAndPower(const PhotonEmitter& e, const std::vector<TestDisc>& discs, long n, uint64_t seed) {
    Shot s = shoot(e, discs, n, seed);
    expectIrradiance(s, discs);
    expectPowerIsMean(e, s);
}

// Irradiance a delta light gives a disc at x with normal n, from Light::sample.
double deltaIrradiance(const Light& l, const Vec3& x, const Vec3& n) {
    LightSample ls;
    if (!l.sample(x, 0.5f, 0.5f, ls)) return 0;
    return ls.L.x * std::fabs(dot(ls.wi, n));
}

std::vector<TestDisc> deltaDiscs(const Light& l, const std::vector<std::pair<Vec3, Vec3>>& where, double radius) {
    std::vector<TestDisc> discs;
    for (const auto& [x, n] : where) {
        Vec3 un = normalize(n);
        discs.push_back({x, un, radius, deltaIrradiance(l, x, un)});
    }
    return discs;
}

void expectPowerNear(const Color& got, const Color& want, double rel = 1e-5) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], rel * std::fabs(want[c]) + 1e-30) << "channel " << c;
}

// ---------------------------------------------------------------------------

TEST(PhotonEmissionPoint, InsideTargetShootsWholeSphere) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    const auto light = makeLight(pointLight({0.2f, 0.3f, -0.1f}, {2, 1, 0.5f}));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    expectPowerNear(e.power(), Color(2, 1, 0.5f) * float(4 * PiD));

    auto discs = deltaDiscs(*light,
                            {{{0.9f, 0.3f, -0.1f}, {1, 0, 0}},
                             {{-0.5f, -0.6f, 0.7f}, {1, 1, 0}},
                             {{0.2f, 0.9f, 0.5f}, {0, 0, 1}}},
                            0.04);
    expectIrradianceAndPower(e, discs, 4000000, 1);
}

TEST(PhotonEmissionPoint, OutsideTargetShootsConeAtItsBoundingSphere) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    Vec3 p(4, 1.5f, -0.5f);
    const auto light = makeLight(pointLight(p, {3, 2, 1}));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    double d = length(p), sinA = targetRadius(target) / d;
    double solidAngle = 2 * PiD * (1 - std::sqrt(1 - sinA * sinA));
    expectPowerNear(e.power(), Color(3, 2, 1) * float(solidAngle), 1e-4);

    auto discs = deltaDiscs(*light,
                            {{{0.9f, 0.9f, -0.9f}, {1, 0, 0}},
                             {{-0.8f, 0.2f, 0.6f}, {1, -1, 2}},
                             {{0, 0, 0}, {0, 1, 0}}},
                            0.06);
    expectIrradianceAndPower(e, discs, 3000000, 2);
}

// A tiny target cone (distant light) keeps its spread despite float cosines.
TEST(PhotonEmissionPoint, DistantLightTinyCone) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    const auto light = makeLight(pointLight({3000, 4000, 0}, {1, 1, 1}));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    double sin2 = std::pow(targetRadius(target) / 5000, 2);
    expectPowerNear(e.power(), Color(float(2 * PiD * sin2 / (1 + std::sqrt(1 - sin2)))), 1e-4);

    auto discs = deltaDiscs(*light, {{{0, 0, 0}, {0.6f, 0.8f, 0}}, {{0.5f, -0.5f, 0.5f}, {0, 1, 0}}}, 0.3);
    Shot s = shoot(e, discs, 200000, 3);
    expectIrradiance(s, discs);
}

TEST(PhotonEmissionSpot, NarrowSpotInsideTargetCone) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    LightDesc desc = spotLight({0, 3, 0}, {0, -1, 0}, 20, 8, {5, 4, 3});
    const auto light = makeLight(desc);
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    // Closed form: the smoothstep averages 1/2 over the falloff band.
    double cc = std::cos(double(radians(20))), cf = std::cos(double(radians(12)));
    double integral = 2 * PiD * ((1 - cf) + 0.5 * (cf - cc));
    expectPowerNear(e.power(), Color(5, 4, 3) * float(integral), 1e-5);

    // Discs on axis, in the falloff band (12..20 degrees) and outside the cone.
    auto discs = deltaDiscs(*light,
                            {{{0, 0, 0}, {0, 1, 0}},
                             {{0.8f, 0, 0}, {0, 1, 0}},
                             {{0, -0.2f, 0.9f}, {0.3f, 1, -0.4f}},
                             {{0.9f, 0.5f, -0.9f}, {0, 1, 0}}},
                            0.03);
    ASSERT_GT(discs[1].expected, 0);
    ASSERT_LT(discs[1].expected, deltaIrradiance(*light, {0, 0, 0}, {0, 1, 0}));  // really in the falloff
    ASSERT_EQ(discs[3].expected, 0);
    expectIrradianceAndPower(e, discs, 3000000, 4);
}

// Wide spot far away: the target cone is narrower and is the one sampled;
// the falloff weights the photons.
TEST(PhotonEmissionSpot, WideSpotSamplesTargetCone) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    const auto light = makeLight(spotLight({0, 10, 0}, {0.3f, -1, 0}, 30, 20, {5, 4, 3}));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    auto discs = deltaDiscs(*light,
                            {{{0.9f, 0, 0}, {0, 1, 0}},
                             {{0, 0.5f, 0}, {0, 1, 0}},
                             {{-0.8f, -0.5f, 0.3f}, {1, 1, 1}}},
                            0.1);
    for (const TestDisc& d : discs) ASSERT_GT(d.expected, 0);
    expectIrradianceAndPower(e, discs, 2000000, 5);
}

// Cones overlapping in part, either one sampled, smooth and hard edges: the
// quadrature behind power() against the photons' mean.
TEST(PhotonEmissionSpot, PartialOverlapPowerIsMean) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    struct Case {
        Vec3 position, direction;
        float cone, falloff;
    };
    const Case cases[] = {
        {{0, 3, 0}, {0.6f, -1, 0}, 15, 5},    // spot narrower, clipped by the target cone
        {{0, 3, 0}, {0.6f, -1, 0.1f}, 15, 0},  // same, hard edge
        {{0, 8, 0}, {0.45f, -1, 0}, 30, 25},  // target narrower, spot edge across it
        {{0, 8, 0}, {0.45f, -1, 0}, 30, 0},   // same, hard edge
        {{2, 2, 2}, {-1, -1, -1}, 80, 60},    // wide falloff band across the target
        {{0, 3000, 0}, {0.0005f, -1, 0}, 0.05f, 0.01f},  // hair-thin and far: float cosines would bias it
    };
    int seed = 10;
    for (const Case& c : cases) {
        SCOPED_TRACE(::testing::Message() << "cone " << c.cone << " falloff " << c.falloff);
        const auto light = makeLight(spotLight(c.position, c.direction, c.cone, c.falloff, {1, 2, 3}));
        PhotonEmitter e = PhotonEmitter::forLight(*light, target);
        ASSERT_GT(e.power().x, 0);
        Shot s = shoot(e, {}, 1000000, seed++);
        EXPECT_EQ(s.badPhotons, 0);
        expectPowerIsMean(e, s);
    }
}

// Clipped spot: photons outside the target cone carry nothing, the rest
// still deliver the right irradiance.
TEST(PhotonEmissionSpot, ClippedSpotIrradiance) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    const auto light = makeLight(spotLight({0, 3, 0}, {0.6f, -1, 0}, 15, 5, {5, 4, 3}));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    auto discs = deltaDiscs(*light, {{{0.9f, 1.5f, 0}, {0, 1, 0}}, {{0.8f, 0.9f, 0.2f}, {1, 0, 0}}}, 0.03);
    for (const TestDisc& d : discs) ASSERT_GT(d.expected, 0);
    Shot s = shoot(e, discs, 2000000, 20);
    expectIrradiance(s, discs);
}

// A target cone wholly inside the spot's flat core: power is exactly I times
// the target cone's solid angle (checks the overlap quadrature).
TEST(PhotonEmissionSpot, TargetInsideFlatCoreIsExact) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    const auto light = makeLight(spotLight({0, 20, 0}, {0.05f, -1, 0}, 40, 10, {1, 2, 3}));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    double sin2 = std::pow(targetRadius(target) / 20, 2);
    double solidAngle = 2 * PiD * sin2 / (1 + std::sqrt(1 - sin2));
    expectPowerNear(e.power(), Color(1, 2, 3) * float(solidAngle), 1e-5);
}

TEST(PhotonEmissionDirectional, DiscCoversTarget) {
    PhotonTarget target = boundedTarget({-1, -1, 0}, {2, 1, 1});
    Color irradiance(3, 2, 1);
    const auto light = makeLight(directionalLight({1, -2, 0.5f}, irradiance));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    double r = targetRadius(target);
    expectPowerNear(e.power(), irradiance * float(PiD * r * r));

    // Uniform field: a larger disc has no bias.
    auto discs = deltaDiscs(*light,
                            {{{0, 0, 0.5f}, {-1, 2, -0.5f}},
                             {{1.7f, 0.7f, 0.2f}, {0, 1, 0}},
                             {{-0.7f, -0.7f, 0.8f}, {1, 0, 1}}},
                            0.25);
    expectIrradianceAndPower(e, discs, 1000000, 30);
    // Every photon starts outside the bounding sphere.
    Rng rng(31);
    for (int i = 0; i < 1000; ++i) {
        float u[4] = {rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()};
        EmittedPhoton p;
        ASSERT_TRUE(e.sample(u, p));
        EXPECT_GT(length(p.ray.o - target.bounds.center()), r);
    }
}

TEST(PhotonEmissionCollimatedQuad, IrradianceInsideAndOutsideBeam) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    Vec3 c(0, 3, 0), u(1.2f, 0, 0.3f), v(0.2f, 0.1f, 0.9f), dir = normalize(Vec3(0.2f, -1, 0.1f));
    Color irradiance(2, 1, 4);
    const auto light = makeLight(quadLight(c, u, v, dir, irradiance));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    // Flux through the quad: E times its area seen along the beam.
    expectPowerNear(e.power(), irradiance * std::fabs(dot(cross(u, v), dir)));

    // Points in the beam at quad coordinates (a, b), pushed down to y ~ 0.
    auto inBeam = [&](float a, float b) {
        Vec3 h = c + u * a + v * b;
        return h + dir * (h.y / -dir.y);
    };
    const double radius = 0.08;
    auto discs = deltaDiscs(*light,
                            {{inBeam(0, 0), -dir},
                             {inBeam(0.2f, -0.15f), {1, 1, 0}},
                             {inBeam(-0.2f, 0.25f), {0, 0, 1}},
                             {inBeam(0.85f, 0), {0, 1, 0}}},  // beside the beam
                            radius);
    // Each disc lies wholly inside or wholly outside the beam.
    for (const TestDisc& d : discs) {
        Vec3 s, t;
        coordinateSystem(d.n, s, t);
        for (int k = 0; k < 16; ++k) {
            float phi = 2 * Pi * k / 16;
            Vec3 rim = d.x + (s * std::cos(phi) + t * std::sin(phi)) * float(radius);
            ASSERT_EQ(deltaIrradiance(*light, rim, d.n) > 0, d.expected > 0);
        }
    }
    ASSERT_EQ(discs[3].expected, 0);
    expectIrradianceAndPower(e, discs, 1000000, 40);
}

TEST(PhotonEmissionCollimatedQuad, BeamMissingTargetHasNoPower) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    // Beside the box, pointing past it.
    const auto beside = makeLight(quadLight({3, 3, 0}, {1, 0, 0}, {0, 0, 1}, {0, -1, 0}, {1, 1, 1}));
    EXPECT_TRUE(isBlack(PhotonEmitter::forLight(*beside, target).power()));
    // Downstream of the box, pointing away from it.
    const auto away = makeLight(quadLight({0, 3, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 1, 1}));
    EXPECT_TRUE(isBlack(PhotonEmitter::forLight(*away, target).power()));
    // Passing diagonally 0.17 beside a vertical edge of the box: the box's
    // own axes do not separate it, the beam's side face does.
    const auto diagonal = makeLight(quadLight({2.2f, 0.2f, 0}, {0, 0, 1}, {0.15f, 0.15f, 0}, {-1, 1, 0}, {1, 1, 1}));
    EXPECT_TRUE(isBlack(PhotonEmitter::forLight(*diagonal, target).power()));
    // Unbounded target: nothing is culled.
    PhotonTarget everywhere = target;
    everywhere.unbounded = true;
    EXPECT_FALSE(isBlack(PhotonEmitter::forLight(*beside, everywhere).power()));
}

// The beam test is conservative: a quad it culls never sends a photon into the box.
TEST(PhotonEmissionCollimatedQuad, CullingIsConservative) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    Rng rng(50);
    auto uniformIn = [&](float lo, float hi) { return lo + (hi - lo) * rng.uniform(); };
    auto randomVec = [&](float s) { return Vec3(uniformIn(-s, s), uniformIn(-s, s), uniformIn(-s, s)); };
    int culled = 0, kept = 0;
    for (int config = 0; config < 400; ++config) {
        Vec3 dir = sampleUniformSphere(rng.uniform(), rng.uniform());
        const auto light = makeLight(quadLight(randomVec(3), randomVec(1.5f), randomVec(1.5f), dir, {1, 1, 1}));
        PhotonEmitter e = PhotonEmitter::forLight(*light, target);
        if (!isBlack(e.power())) {
            ++kept;
            continue;
        }
        ++culled;
        // Shoot the same beam from an unbounded target's emitter.
        PhotonEmitter all = PhotonEmitter::forLight(*light, {target.bounds, true});
        for (int i = 0; i < 2000; ++i) {
            float u[4] = {rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()};
            EmittedPhoton p;
            if (!all.sample(u, p)) continue;
            float t0 = 0, t1 = Infinity;
            ASSERT_FALSE(target.bounds.intersect(p.ray, t0, t1)) << "config " << config;
        }
    }
    EXPECT_GT(culled, 20);
    EXPECT_GT(kept, 20);
}

TEST(PhotonEmissionSphere, LambertianSurfaceIrradiance) {
    PhotonTarget target = boundedTarget({-2, -2, -2}, {2, 2, 2});
    Vec3 center(0.3f, 0.2f, -0.1f);
    float r = 0.4f;
    Color power(10, 5, 2);
    const auto light = makeLight(sphereLight(center, r, power));
    PhotonEmitter e = PhotonEmitter::forLight(*light, target);
    expectPowerNear(e.power(), power, 0);

    // Discs facing the sphere's centre: E = pi Lrad sin^2(alpha).
    double lrad = light->emittedRadiance().x;
    std::vector<TestDisc> discs;
    for (Vec3 x : {Vec3(1.8f, 0.2f, -0.1f), Vec3(-0.7f, -1.0f, 1.1f)}) {
        Vec3 n = normalize(center - x);
        double sin2 = double(r) * r / lengthSquared(center - x);
        discs.push_back({x, n, 0.1, PiD * lrad * sin2, true});
    }
    // A tilted disc: the expected value from Light::sample's own estimator.
    Vec3 x(0.3f, 1.6f, 0.4f), n = normalize(Vec3(1, -1, 0.5f));
    Tally nee;
    const long m = 200000;
    Rng rng(60);
    for (long i = 0; i < m; ++i) {
        LightSample ls;
        if (light->sample(x, rng.uniform(), rng.uniform(), ls)) nee.add(ls.L.x * std::max(0.f, dot(ls.wi, n)));
    }
    discs.push_back({x, n, 0.1, nee.mean(m), true});

    Shot s = shoot(e, discs, 3000000, 61);
    expectIrradiance(s, discs);
    // The tilted disc's reference has its own noise.
    const Tally& t = s.discs[2];
    EXPECT_NEAR(t.mean(s.n), nee.mean(m), 4 * std::hypot(t.stdErr(s.n), nee.stdErr(m)));
    expectPowerIsMean(e, s);
}

TEST(PhotonEmissionEnvironment, ConstantRadianceGivesPiL) {
    PhotonTarget target = boundedTarget({-1, -0.5f, 0}, {1, 0.5f, 2});
    Color radiance(0.5f, 1, 2);
    PhotonEmitter e = PhotonEmitter::forEnvironment(radiance, target);
    double r = targetRadius(target);
    expectPowerNear(e.power(), radiance * float(4 * PiD * PiD * r * r));

    // One-sided discs: irradiance pi L from the hemisphere they face.
    std::vector<TestDisc> discs;
    for (auto [x, n] : std::vector<std::pair<Vec3, Vec3>>{
             {{0, 0, 1}, {0, 0, 1}}, {{0.7f, -0.3f, 0.2f}, {1, -1, 0}}, {{-0.6f, 0.3f, 1.7f}, {-1, 2, -3}}})
        discs.push_back({x, normalize(n), 0.25, PiD * radiance.x, true});
    expectIrradianceAndPower(e, discs, 1000000, 70);
}

// An environment map: photons drawn by texel power deliver to one-sided
// discs the irradiance the map gives them (quadrature over sub-texels), and
// power() is the map's integral times the disc area.
TEST(PhotonEmissionEnvironment, MapDeliversItsIrradiance) {
    const int w = 32, h = 16;
    std::vector<Color> texels(size_t(w * h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) texels[size_t(y * w + x)] = Color(0.2f + 0.1f * float((x + 2 * y) % 5), 1, 1);
    for (int y = 4; y < 6; ++y)
        for (int x = 9; x < 11; ++x) texels[size_t(y * w + x)] = Color(30, 1, 1);  // a sun
    const Environment env(texels, w, h, 1, 20);
    PhotonTarget target = boundedTarget({-1, -0.5f, 0}, {1, 0.5f, 2});
    PhotonEmitter e = PhotonEmitter::forEnvironment(env, target);
    double r = targetRadius(target);
    expectPowerNear(e.power(), env.integral() * float(PiD * r * r));
    auto irradiance = [&](const Vec3& n) { return environmentIrradianceByQuadrature(env, n, 20); };
    std::vector<TestDisc> discs;
    for (auto [x, n] : std::vector<std::pair<Vec3, Vec3>>{
             {{0, 0, 1}, {0, 1, 0}}, {{0.7f, -0.3f, 0.2f}, {1, -1, 0}}, {{-0.6f, 0.3f, 1.7f}, {-1, 2, -3}}})
        discs.push_back({x, normalize(n), 0.25, irradiance(normalize(n)), true});
    // The quadrature's error (cosine across an eighth of a texel) is ~1e-3.
    Shot s = shoot(e, discs, 1000000, 71);
    EXPECT_EQ(s.badPhotons, 0);
    for (size_t k = 0; k < discs.size(); ++k)
        EXPECT_NEAR(s.discs[k].mean(s.n), discs[k].expected, 4 * s.discs[k].stdErr(s.n) + 2e-3 * discs[k].expected)
            << "disc " << k;
    expectPowerIsMean(e, s);
}

// An unbounded target still uses its (finite) box for the disc emitters and
// does not cull the others.
TEST(PhotonEmissionTarget, UnboundedTarget) {
    PhotonTarget target{makeBox({-1, -1, -1}, {1, 1, 1}), true};
    double r = targetRadius(target);
    const auto sun = makeLight(directionalLight({0, -1, 0}, {1, 1, 1}));
    expectPowerNear(PhotonEmitter::forLight(*sun, target).power(), Color(float(PiD * r * r)));
    const auto point = makeLight(pointLight({10, 0, 0}, {1, 1, 1}));
    expectPowerNear(PhotonEmitter::forLight(*point, target).power(), Color(float(4 * PiD)));
    const auto spot = makeLight(spotLight({10, 0, 0}, {1, 0, 0}, 30, 0, {1, 1, 1}));  // pointing away, still counts
    expectPowerNear(PhotonEmitter::forLight(*spot, target).power(),
                    Color(float(2 * PiD * (1 - std::cos(double(radians(30)))))), 1e-4);
}

// ---------------------------------------------------------------------------
// Cases that must give zero power, never NaN.

void expectNothingEmitted(const PhotonEmitter& e) {
    EXPECT_TRUE(isBlack(e.power()));
    Rng rng(80);
    for (int i = 0; i < 1000; ++i) {
        float u[4] = {rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()};
        EmittedPhoton p;
        EXPECT_FALSE(e.sample(u, p));
        EXPECT_TRUE(isBlack(p.power));
        EXPECT_TRUE(isFinite(p.ray.o));
    }
}

TEST(PhotonEmissionZero, SpotPointingAwayFromTarget) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(spotLight({0, 3, 0}, {0, 1, 0}, 30, 5, {1, 1, 1})), target));
    // Just missing sideways: the cone edge passes beside the bounding sphere.
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(spotLight({0, 5, 0}, {1, -0.2f, 0}, 20, 5, {1, 1, 1})), target));
}

TEST(PhotonEmissionZero, ZeroIntensityAndDegenerateLights) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    const Color black(0, 0, 0);
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(pointLight({0, 0, 0}, black)), target));
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(pointLight({5, 0, 0}, black)), target));
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(spotLight({0, 3, 0}, {0, -1, 0}, 30, 5, black)), target));
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(spotLight({0, 3, 0}, {0, -1, 0}, 0, 0, {1, 1, 1})), target));
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(directionalLight({0, -1, 0}, black)), target));
    expectNothingEmitted(
        PhotonEmitter::forLight(*makeLight(quadLight({0, 3, 0}, {1, 0, 0}, {0, 0, 1}, {0, -1, 0}, black)), target));
    // Quad seen edge-on along the beam: no area, no flux.
    expectNothingEmitted(
        PhotonEmitter::forLight(*makeLight(quadLight({0, 3, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {1, 1, 1})), target));
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(sphereLight({0, 0, 0}, 0.5f, black)), target));
    expectNothingEmitted(PhotonEmitter::forEnvironment(black, target));
}

TEST(PhotonEmissionZero, EmptyOrDegenerateTarget) {
    PhotonTarget empty;  // bounded, empty box: nothing scatters
    const Color one(1, 1, 1);
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(pointLight({0, 0, 0}, one)), empty));
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(sphereLight({0, 0, 0}, 0.5f, one)), empty));
    expectNothingEmitted(PhotonEmitter::forEnvironment(one, empty));
    // Unbounded with no finite box: the disc emitters have nowhere to aim.
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(directionalLight({0, -1, 0}, one)), {BBox(), true}));
    // A single point scatters nothing measurable.
    PhotonTarget point = boundedTarget({0, 0, 0}, {0, 0, 0});
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(directionalLight({0, -1, 0}, one)), point));
    expectNothingEmitted(PhotonEmitter::forLight(*makeLight(pointLight({1, 0, 0}, one)), point));
}

// Odd but legal inputs: finite photons throughout.
TEST(PhotonEmissionZero, ExtremeInputsStayFinite) {
    PhotonTarget target = boundedTarget({-1, -1, -1}, {1, 1, 1});
    const Color one(1, 1, 1);
    const LightDesc lights[] = {
        sphereLight({0, 3, 0}, 0, one),                      // zero-radius sphere light
        spotLight({0, 3, 0}, {0, -1, 0}, 180, 180, one),     // the whole sphere
        spotLight({0, 3, 0}, {0, -1, 0}, 1e-3f, 1e-3f, one),  // hair-thin spot
        spotLight({0, 1e5f, 0}, {0, -1, 0}, 30, 5, one),     // very distant spot
        pointLight({0, 1e6f, 0}, one),                       // very distant point
    };
    for (const LightDesc& d : lights) {
        PhotonEmitter e = PhotonEmitter::forLight(*makeLight(d), target);
        EXPECT_TRUE(isFinite(e.power()));
        Shot s = shoot(e, {}, 20000, 90);
        EXPECT_EQ(s.badPhotons, 0);
        if (!isBlack(e.power())) expectPowerIsMean(e, s);
    }
}

}  // namespace
}  // namespace vdbmarch
