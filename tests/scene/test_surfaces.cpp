// SurfaceSet::intersect: rays that miss the surfaces' padded bounds skip
// Embree (SurfaceSet::commit). The cull must never change an answer: rays
// aimed at points on the faces, edges and corners of a box and on an
// ellipsoid, from every side and at grazing angles, give the same hit (or
// the same miss) as in a set whose bounds cull nothing near them (the same
// surface plus two specks far away).
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"
#include "core/transform.h"
#include "core/triangle_mesh.h"
#include "scene/surfaces.h"

namespace vdbmarch {
namespace {

// The surface alone (`culled`), and with two tiny spheres far out (`whole`,
// whose bounds hold every ray of the tests: nothing near it is culled).
struct CulledAndWhole {
    SurfaceSet culled, whole;
    template <typename Add>
    explicit CulledAndWhole(Add add) {
        add(culled);
        add(whole);
        for (float s : {-100.f, 100.f})
            whole.addSphere(Transform(Mat4::translate(Vec3(s)) * Mat4::scale(Vec3(0.01f))), 1);
        culled.commit();
        whole.commit();
    }
};

// The same hit or miss from both sets; hits beyond `far` (a speck) count as misses.
void expectSameAnswer(const SurfaceSet& culled, const SurfaceSet& whole, const Ray& r, int i, int& hits) {
    constexpr float Far = 50;
    SurfaceHit a, b;
    const bool ha = culled.intersect(r, 0.f, Infinity, a);
    const bool hb = whole.intersect(r, 0.f, Infinity, b) && b.t < Far;
    ASSERT_EQ(ha, hb) << "ray " << i << " from " << r.o.x << " " << r.o.y << " " << r.o.z << " along " << r.d.x
                      << " " << r.d.y << " " << r.d.z;
    if (!ha) return;
    ++hits;
    EXPECT_EQ(a.t, b.t) << "ray " << i;
    EXPECT_EQ(a.surface, 0);
}

TEST(SurfaceSet, BoundsCullingKeepsEveryHitOfABox) {
    // A thin, wide floor box off the origin (like fig3b_spots' floor).
    const Vec3 lo(-3, -0.9f, -4), hi(3, -0.8f, 3);
    TriangleMesh box = makeUnitBox();
    transformMesh(box, [&](const Vec3& p) { return lo + (hi - lo) * (p + Vec3(0.5f)); });
    const CulledAndWhole sets([&](SurfaceSet& set) { set.addMesh(box, 0); });
    Rng rng(5);
    int hits = 0;
    for (int i = 0; i < 40000; ++i) {
        // A target on the box's surface: a face point, or an edge or corner.
        Vec3 target(lo.x + (hi.x - lo.x) * rng.uniform(), lo.y + (hi.y - lo.y) * rng.uniform(),
                    lo.z + (hi.z - lo.z) * rng.uniform());
        const int snaps = 1 + int(rng.uniform() * 3);  // 1: a face, 2: an edge, 3: a corner
        for (int k = 0; k < snaps; ++k) {
            const int a = int(rng.uniform() * 3);
            target[a] = rng.uniform() < 0.5f ? lo[a] : hi[a];
        }
        // Towards it from afar (or leaving from it), some nearly parallel to a face.
        Vec3 dir = sampleUniformSphere(rng.uniform(), rng.uniform());
        if (i % 3 == 0) dir[int(rng.uniform() * 3)] *= 1e-4f;
        dir = normalize(dir);
        const Vec3 o = target - dir * (i % 5 == 0 ? 0.f : 2 + 10 * rng.uniform());
        expectSameAnswer(sets.culled, sets.whole, Ray{o, dir}, i, hits);
        if (::testing::Test::HasFatalFailure()) return;
    }
    EXPECT_GT(hits, 10000);
}

TEST(SurfaceSet, BoundsCullingKeepsEveryHitOfAnEllipsoid) {
    const Transform xf(Mat4::translate(Vec3(4, -1, 2)) * Mat4::scale(Vec3(0.5f, 2, 1)));
    const CulledAndWhole sets([&](SurfaceSet& set) { set.addSphere(xf, 0); });
    Rng rng(7);
    int hits = 0;
    for (int i = 0; i < 40000; ++i) {
        // A point on the surface, or on its bounding box (where the cull's
        // slab test decides), with rays towards it, some grazing.
        const Vec3 q = sampleUniformSphere(rng.uniform(), rng.uniform());
        Vec3 local = q;
        if (i % 2 == 0) local[int(rng.uniform() * 3)] = rng.uniform() < 0.5f ? -1.f : 1.f;
        const Vec3 target = xf.point(local);
        const Vec3 n = normalize(xf.normal(q));
        Vec3 dir = sampleUniformSphere(rng.uniform(), rng.uniform());
        if (dot(dir, n) > 0) dir = -dir;
        if (i % 3 == 0) dir = normalize(dir - n * (dot(dir, n) * 0.999f));
        const Vec3 o = target - dir * (2 + 10 * rng.uniform());
        expectSameAnswer(sets.culled, sets.whole, Ray{o, dir}, i, hits);
        if (::testing::Test::HasFatalFailure()) return;
    }
    EXPECT_GT(hits, 10000);
}

}  // namespace
}  // namespace vdbmarch
