// The shared surface event: interfaces, diffuse bounces and smooth
// dielectrics with the shading-normal rule (the shading normal bends the
// direction, the geometric normal decides the side), and the adjoint
// correction photons take where the two normals differ.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"
#include "transport/surface_event.h"

namespace vdbmarch {
namespace {

constexpr int Outside = 0, Inside = 2;

// A scene with no geometry: the event only reads the surfaces' materials
// and regions, and the scene scale for ray offsets.
std::unique_ptr<Scene> eventScene(MaterialDesc material) {
    auto s = std::make_unique<Scene>();
    SurfaceInfo info;
    info.material = material;
    info.interiorRegion = Inside;
    info.exteriorRegion = Outside;
    s->surfaces.push_back(info);
    s->sceneScale = 1;
    return s;
}

MaterialDesc glass(float ior) {
    MaterialDesc m;
    m.type = MaterialDesc::Type::Dielectric;
    m.ior = ior;
    return m;
}

SurfaceHit hitAt(const Vec3& n, const Vec3& ns) {
    SurfaceHit h;
    h.t = 1;
    h.p = Vec3(0);
    h.n = normalize(n);
    h.ns = normalize(ns);
    h.surface = 0;
    return h;
}

SurfaceEvent event(const Scene& s, const SurfaceHit& h, const Vec3& d, int region, float u0,
                   TransportMode mode = TransportMode::Radiance, float u1 = 0.3f, float u2 = 0.6f) {
    const float u[3] = {u0, u1, u2};
    return sampleSurfaceEvent(s, h, normalize(d), region, u, mode);
}

TEST(SurfaceEvent, InterfaceCrossesStraightAndSwitchesRegion) {
    MaterialDesc m;
    m.type = MaterialDesc::Type::Interface;
    auto s = eventScene(m);
    const SurfaceHit h = hitAt(Vec3(0, 0, 1), Vec3(0, 0, 1));
    const Vec3 d = normalize(Vec3(0.3f, 0.1f, -1));
    SurfaceEvent in = event(*s, h, d, Outside, 0.5f);
    EXPECT_EQ(in.kind, SurfaceEvent::Kind::Interface);
    EXPECT_TRUE(in.straight);
    EXPECT_EQ(in.region, Inside);
    EXPECT_EQ(in.ray.d, d);
    EXPECT_LT(in.ray.o.z, 0.f);  // offset to the side it leaves on
    SurfaceEvent out = event(*s, h, -d, Inside, 0.5f);
    EXPECT_EQ(out.region, Outside);
    EXPECT_GT(out.ray.o.z, 0.f);
}

TEST(SurfaceEvent, DiffuseBouncesOnTheArrivingSideWithCosinePdf) {
    MaterialDesc m;
    m.type = MaterialDesc::Type::Diffuse;
    m.albedo = Color(0.2f, 0.5f, 0.7f);
    auto s = eventScene(m);
    const SurfaceHit h = hitAt(Vec3(0, 0, 1), Vec3(0, 0, 1));
    Rng rng(11);
    for (int i = 0; i < 1000; ++i) {
        const Vec3 d = normalize(Vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() < 0.5f ? -1.f : 1.f));
        const SurfaceEvent e = event(*s, h, d, Outside, rng.uniform(), TransportMode::Radiance, rng.uniform(), rng.uniform());
        ASSERT_EQ(e.kind, SurfaceEvent::Kind::Diffuse);
        EXPECT_EQ(e.region, Outside);
        EXPECT_EQ(e.weight, m.albedo);
        const float cosOut = e.ray.d.z * (d.z < 0 ? 1.f : -1.f);  // towards the side the ray came from
        EXPECT_GT(cosOut, 0.f);
        EXPECT_NEAR(e.pdf, cosOut * InvPi, 1e-4f);
    }
}

TEST(SurfaceEvent, FlatGlassReflectsWithFresnelProbabilityAndRefractsBySnell) {
    auto s = eventScene(glass(1.5f));
    const SurfaceHit h = hitAt(Vec3(0, 0, 1), Vec3(0, 0, 1));
    const Vec3 d = normalize(Vec3(0.6f, 0, -1));
    const float cosI = -d.z, F = fresnelDielectric(cosI, 1.5f);
    const int n = 20000;
    int reflected = 0;
    for (int i = 0; i < n; ++i) {
        const SurfaceEvent e = event(*s, h, d, Outside, (float(i) + 0.5f) / float(n));
        EXPECT_EQ(e.weight, Color(1));
        if (e.kind == SurfaceEvent::Kind::Reflect) {
            ++reflected;
            EXPECT_EQ(e.region, Outside);
            EXPECT_NEAR(e.ray.d.x, d.x, 1e-6f);
            EXPECT_NEAR(e.ray.d.z, -d.z, 1e-6f);
        } else {
            ASSERT_EQ(e.kind, SurfaceEvent::Kind::Refract);
            EXPECT_FALSE(e.straight);
            EXPECT_EQ(e.region, Inside);
            const float sinT = std::sqrt(1 - e.ray.d.z * e.ray.d.z);
            EXPECT_NEAR(sinT * 1.5f, std::sqrt(1 - cosI * cosI), 1e-5f);  // Snell
            EXPECT_LT(e.ray.d.z, 0.f);
        }
    }
    // Stratified uniforms: the reflected count is F n to within one.
    EXPECT_NEAR(double(reflected), double(F) * n, 1.0);
}

TEST(SurfaceEvent, IndexMatchedGlassIsCrossedStraight) {
    auto s = eventScene(glass(1.f));
    const SurfaceHit h = hitAt(Vec3(0, 0, 1), Vec3(0.2f, 0, 1));  // even with a tilted shading normal
    const Vec3 d = normalize(Vec3(0.4f, -0.2f, -1));
    const SurfaceEvent e = event(*s, h, d, Outside, 0.9f);
    EXPECT_EQ(e.kind, SurfaceEvent::Kind::Refract);
    EXPECT_TRUE(e.straight);
    EXPECT_NEAR(length(e.ray.d - d), 0.f, 1e-6f);
}

TEST(SurfaceEvent, ShadingNormalBendsTheRefractedDirection) {
    auto s = eventScene(glass(1.5f));
    const Vec3 ns = normalize(Vec3(0.3f, 0, 1));
    const SurfaceHit h = hitAt(Vec3(0, 0, 1), ns);
    const Vec3 d = normalize(Vec3(-0.2f, 0.1f, -1));
    const SurfaceEvent e = event(*s, h, d, Outside, 0.999f);  // refracts
    ASSERT_EQ(e.kind, SurfaceEvent::Kind::Refract);
    // Snell about the shading normal: the tangential parts scale by 1/eta.
    const float cosI = -dot(d, ns);
    const Vec3 tangentIn = d + ns * cosI, tangentOut = e.ray.d - ns * dot(e.ray.d, ns);
    EXPECT_NEAR(length(tangentOut - tangentIn / 1.5f), 0.f, 1e-5f);
    // and not about the geometric normal.
    const SurfaceHit flat = hitAt(Vec3(0, 0, 1), Vec3(0, 0, 1));
    EXPECT_GT(length(event(*s, flat, d, Outside, 0.999f).ray.d - e.ray.d), 0.05f);
}

TEST(SurfaceEvent, OutgoingDirectionIsAlwaysOnTheGeometricSide) {
    // Strongly tilted shading normals send some rays the wrong way; the
    // geometric normal then redoes the event.
    auto s = eventScene(glass(1.5f));
    Rng rng(5);
    int redone = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 ng = sampleUniformSphere(rng.uniform(), rng.uniform());
        const Vec3 ns = normalize(ng + sampleUniformSphere(rng.uniform(), rng.uniform()) * 0.9f);
        const SurfaceHit h = hitAt(ng, ns);
        Vec3 d = sampleUniformSphere(rng.uniform(), rng.uniform());
        if (std::fabs(dot(d, ng)) < 1e-3f) continue;
        const int region = dot(d, ng) < 0 ? Outside : Inside;
        const SurfaceEvent e = event(*s, h, d, region, rng.uniform());
        ASSERT_TRUE(isFinite(e.ray.d));
        EXPECT_NEAR(length(e.ray.d), 1.f, 1e-4f);
        const float side = dot(e.ray.d, ng) * dot(d, ng);  // > 0: carried on through
        if (e.kind == SurfaceEvent::Kind::Reflect) {
            EXPECT_LT(side, 0.f);
            EXPECT_EQ(e.region, region);
        } else {
            EXPECT_GT(side, 0.f);
            EXPECT_EQ(e.region, region == Outside ? Inside : Outside);
        }
        const Vec3 n = dot(ns, dot(d, ng) < 0 ? ng : -ng) > 0 ? ns : -ns;
        redone += std::fabs(dot(e.ray.d - d, cross(n, d))) > 1e-3f;  // left the plane of d and ns
    }
    EXPECT_GT(redone, 0);  // the fallback was exercised
}

TEST(SurfaceEvent, BothGlassOutcomesAreTheEventsTheFresnelChoicePicks) {
    // dielectricEvents gives the two events sampleSurfaceEvent chooses
    // between, bit for bit, and the chance of the first: a path that follows
    // both, weighted by their chances, has the choice's expectation. With
    // tilted shading normals, so that the geometric-normal fallback is in.
    auto s = eventScene(glass(1.5f));
    Rng rng(17);
    int splits = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 ng = sampleUniformSphere(rng.uniform(), rng.uniform());
        const Vec3 ns = normalize(ng + sampleUniformSphere(rng.uniform(), rng.uniform()) * 0.5f);
        const SurfaceHit h = hitAt(ng, ns);
        const Vec3 d = sampleUniformSphere(rng.uniform(), rng.uniform());
        if (std::fabs(dot(d, ng)) < 1e-3f) continue;
        const int region = dot(d, ng) < 0 ? Outside : Inside;
        for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
            const DielectricEvents both = dielectricEvents(*s, h, d, region, mode);
            const float F = both.reflectProbability;
            ASSERT_GE(F, 0.f);
            ASSERT_LE(F, 1.f);
            EXPECT_EQ(both.outcome[0].kind, SurfaceEvent::Kind::Reflect);
            const float u[3] = {rng.uniform(), 0.3f, 0.6f};
            const SurfaceEvent e = sampleSurfaceEvent(*s, h, d, region, u, mode);
            const SurfaceEvent& pick = both.outcome[u[0] < F ? 0 : 1];
            EXPECT_EQ(e.kind, pick.kind);
            EXPECT_EQ(e.region, pick.region);
            EXPECT_EQ(e.ray.o, pick.ray.o);
            EXPECT_EQ(e.ray.d, pick.ray.d);
            EXPECT_EQ(e.weight, pick.weight);
            EXPECT_EQ(e.straight, pick.straight);
            splits += F > 0 && F < 1;
        }
    }
    EXPECT_GT(splits, 20000);  // of 40000: the rest reflect totally from inside
}

TEST(SurfaceEvent, PhotonsTakeTheAdjointShadingNormalCorrection) {
    auto s = eventScene(glass(1.5f));
    const Vec3 ns = normalize(Vec3(0.25f, 0.1f, 1));
    const SurfaceHit h = hitAt(Vec3(0, 0, 1), ns);
    const Vec3 d = normalize(Vec3(0.5f, -0.3f, -1));
    for (float u0 : {0.001f, 0.999f}) {  // reflect, refract
        const SurfaceEvent radiance = event(*s, h, d, Outside, u0, TransportMode::Radiance);
        const SurfaceEvent importance = event(*s, h, d, Outside, u0, TransportMode::Importance);
        EXPECT_EQ(radiance.weight, Color(1));
        EXPECT_EQ(radiance.ray.d, importance.ray.d);
        const Vec3& wo = importance.ray.d;
        float expected = std::fabs(dot(d, ns)) * std::fabs(wo.z) / (std::fabs(d.z) * std::fabs(dot(wo, ns)));
        if (importance.kind == SurfaceEvent::Kind::Refract) expected /= 1.5f * 1.5f;
        EXPECT_NEAR(importance.weight.x, expected, 1e-5f);
    }
}

TEST(SurfaceEvent, PhotonsEnteringGlassCarryFluxNotBasicRadiance) {
    // Camera paths carry L / n^2, unchanged by refraction (weight 1 both
    // ways); a photon's flux stands for radiance (eta_i / eta_t)^2 smaller
    // in that measure after it refracts: 1 / 2.25 entering ior 1.5, 2.25
    // leaving. Reflection changes nothing. Flat shading: no other factor.
    auto s = eventScene(glass(1.5f));
    const SurfaceHit flat = hitAt(Vec3(0, 0, 1), Vec3(0, 0, 1));
    const Vec3 d = normalize(Vec3(0.2f, 0, -1));
    EXPECT_NEAR(event(*s, flat, d, Outside, 0.999f, TransportMode::Importance).weight.x, 1 / 2.25f, 1e-6f);
    EXPECT_NEAR(event(*s, flat, -d, Inside, 0.999f, TransportMode::Importance).weight.x, 2.25f, 1e-5f);
    EXPECT_EQ(event(*s, flat, d, Outside, 0.001f, TransportMode::Importance).weight, Color(1));
    EXPECT_EQ(event(*s, flat, d, Outside, 0.999f, TransportMode::Radiance).weight, Color(1));
}

TEST(SurfaceEvent, ShadowRaysCrossOnlyInterfacesAndIndexMatchedGlass) {
    MaterialDesc m;
    m.type = MaterialDesc::Type::Interface;
    EXPECT_TRUE(crossedByShadowRays(m));
    EXPECT_TRUE(crossedByShadowRays(glass(1.f)));
    EXPECT_FALSE(crossedByShadowRays(glass(1.5f)));
    m.type = MaterialDesc::Type::Diffuse;
    EXPECT_FALSE(crossedByShadowRays(m));
}

}  // namespace
}  // namespace vdbmarch
