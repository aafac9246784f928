// Density bounds and active intervals of a VDB medium against exact geometry,
// on grids the test builds and writes itself (after OpenVDB's
// TestVolumeRayIntersector: a few voxels or 8^3 boxes of known values, rays
// along the axes). The medium interpolates trilinearly between voxel
// centres, so a voxel at index c can only make the density non-zero inside
// the open index box (c - 1, c + 1)^3, and a box of voxels [lo, hi] inside
// (lo - 1, hi + 1): that support, mapped through the grid's transform and
// cut to [tMin, tMax], is exactly what the union of the segments of
// forEachDensityBound (and of activeIntervals) must be along any ray: they
// must cover it, and the blocks' tight boxes (volume/padded_blocks.h: the
// cells whose stencil touches a non-zero value) add nothing beyond it. Each
// segment's maxDensity is then the box's value x density_scale (no other
// value reaches it), and a lone voxel's minDensity 0 (the density falls to
// 0 at the support's faces). On a grid of random voxels and rays in all directions:
// the segments come in increasing t without overlap, every point of
// non-zero density lies in one, and minDensity <= density <= maxDensity at
// dense points along each segment.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "core/rng.h"
#include "core/sampling.h"
#include "support/support.h"
#include "volume/medium.h"

namespace vdbmarch {
namespace {

using test::TempDir;
using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::Vec3d;

// A fog grid "density" whose index (i, j, k) lies at world
// (0.5 i + 1, 0.25 j - 2, k + 0.5): a non-uniform scale and an offset that
// keep axis-aligned rays axis-aligned in index space and every face exact.
openvdb::FloatGrid::Ptr newGrid() {
    initOpenVdb();
    auto g = openvdb::FloatGrid::create(0.f);
    g->setName("density");
    g->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto xf = openvdb::math::Transform::createLinearTransform(1.0);
    xf->preScale(Vec3d(0.5, 0.25, 1.0));
    xf->postTranslate(Vec3d(1.0, -2.0, 0.5));
    g->setTransform(xf);
    return g;
}

struct Loaded {
    openvdb::FloatGrid::Ptr grid;
    std::unique_ptr<Medium> medium;
    std::unique_ptr<MediumQuery> query;
    // World position of a (fractional) index position, by OpenVDB's transform.
    Vec3d world(const Vec3d& index) const { return grid->indexToWorld(index); }
};

// Writes `g` to a new file in `dir` and loads it as a medium.
Loaded load(const TempDir& dir, openvdb::FloatGrid::Ptr g, float densityScale = 1) {
    static int serial = 0;
    const std::string path = dir / ("grid" + std::to_string(serial++) + ".vdb");
    openvdb::io::File f(path);
    f.write({g});
    f.close();
    MediumDesc d;
    d.type = MediumDesc::Type::Vdb;
    d.file = path;
    d.sigma_s = Vec3(1);
    d.densityScale = densityScale;
    Loaded l;
    l.grid = g;
    l.medium = loadVdbMedium(d);
    l.query = l.medium->makeQuery();
    return l;
}

Vec3 toVec3(const Vec3d& v) { return Vec3(float(v.x()), float(v.y()), float(v.z())); }

struct Span {
    double t0, t1;
};

std::ostream& operator<<(std::ostream& os, const std::vector<Span>& s) {
    os << "{";
    for (const Span& x : s) os << " [" << x.t0 << ", " << x.t1 << "]";
    return os << " }";
}

// The part of ray r inside the world box [lo, hi] within [tMin, tMax], by
// the slab method in double; false when the ray misses it.
bool slab(const Ray& r, const Vec3d& lo, const Vec3d& hi, double tMin, double tMax, Span& out) {
    double a = tMin, b = tMax;
    for (int ax = 0; ax < 3; ++ax) {
        const double o = r.o[ax], d = r.d[ax];
        if (d == 0) {
            if (!(lo[ax] < o && o < hi[ax])) return false;
            continue;
        }
        double ta = (lo[ax] - o) / d, tb = (hi[ax] - o) / d;
        if (ta > tb) std::swap(ta, tb);
        a = std::max(a, ta);
        b = std::min(b, tb);
    }
    if (!(b > a)) return false;
    out = {a, b};
    return true;
}

// World box of the trilinear support (lo - 1, hi + 1) of the index box [lo, hi]
// (the transform has no rotation, so its image is a box).
void supportBox(const Loaded& l, const CoordBBox& b, Vec3d& lo, Vec3d& hi) {
    const Vec3d a = l.world(Vec3d(b.min().x() - 1, b.min().y() - 1, b.min().z() - 1));
    const Vec3d c = l.world(Vec3d(b.max().x() + 1, b.max().y() + 1, b.max().z() + 1));
    lo = Vec3d(std::min(a.x(), c.x()), std::min(a.y(), c.y()), std::min(a.z(), c.z()));
    hi = Vec3d(std::max(a.x(), c.x()), std::max(a.y(), c.y()), std::max(a.z(), c.z()));
}

std::vector<DensityBound> boundsAlong(MediumQuery& q, const Ray& r, float tMin, float tMax) {
    std::vector<DensityBound> out;
    q.forEachDensityBound(r, tMin, tMax, [&](const DensityBound& s) {
        out.push_back(s);
        return true;
    });
    return out;
}

// Union of the pieces, touching ones (within eps) joined; pieces must come sorted.
template <typename T>
std::vector<Span> unite(const std::vector<T>& pieces, double eps) {
    std::vector<Span> out;
    for (const T& p : pieces) {
        if (!out.empty() && p.t0 <= out.back().t1 + eps) out.back().t1 = std::max(out.back().t1, double(p.t1));
        else out.push_back({p.t0, p.t1});
    }
    return out;
}

// Sorted union of the expected supports.
std::vector<Span> uniteExpected(std::vector<Span> s) {
    std::sort(s.begin(), s.end(), [](const Span& a, const Span& b) { return a.t0 < b.t0; });
    return unite(s, 0);
}

constexpr double kTol = 2e-5;  // world units: float t of rays ~20 long

void expectSameSpans(const std::vector<Span>& got, const std::vector<Span>& want, const std::string& what) {
    ASSERT_EQ(got.size(), want.size()) << what << ": got " << got << ", expected " << want;
    for (size_t i = 0; i < got.size(); ++i) {
        EXPECT_NEAR(got[i].t0, want[i].t0, kTol) << what << " piece " << i << ": got " << got << ", expected " << want;
        EXPECT_NEAR(got[i].t1, want[i].t1, kTol) << what << " piece " << i << ": got " << got << ", expected " << want;
    }
}

// One box of constant value v in a grid: what each ray must see.
struct ValueBox {
    CoordBBox box;
    float v;
};

// Checks both queries along r against the supports of `boxes`, and that
// each segment over a box's support has that box's value as its bound.
// `scale` is the medium's density_scale.
void checkRay(const Loaded& l, const std::vector<ValueBox>& boxes, float scale, const Ray& r, float tMin, float tMax,
              const std::string& what) {
    std::vector<Span> want;
    std::vector<float> valueOf;  // per expected support, before uniting
    for (const ValueBox& b : boxes) {
        Vec3d lo, hi;
        supportBox(l, b.box, lo, hi);
        Span s;
        if (slab(r, lo, hi, tMin, tMax, s)) {
            want.push_back(s);
            valueOf.push_back(b.v);
        }
    }
    const std::vector<Span> pieces = want;
    want = uniteExpected(want);

    const std::vector<DensityBound> segs = boundsAlong(*l.query, r, tMin, tMax);
    expectSameSpans(unite(segs, kTol), want, what + " (forEachDensityBound)");
    for (size_t i = 0; i < segs.size(); ++i) {
        const DensityBound& s = segs[i];
        EXPECT_LT(s.t0, s.t1) << what;
        if (i > 0) {
            EXPECT_LE(segs[i - 1].t1, s.t0 + kTol) << what << ": segments out of order or overlapping";
        }
        // The box whose support holds the segment's middle gives its bound.
        const double mid = 0.5 * (double(s.t0) + s.t1);
        for (size_t j = 0; j < pieces.size(); ++j)
            if (pieces[j].t0 < mid && mid < pieces[j].t1) {
                EXPECT_EQ(s.maxDensity, valueOf[j] * scale) << what << ": segment " << i;
            }
        // A valid lower bound (that it bounds the density is sampled in the
        // random-ray test; a lone voxel's is 0, asserted where it is tested).
        EXPECT_GE(s.minDensity, 0.f) << what;
        EXPECT_LE(s.minDensity, s.maxDensity) << what;
    }

    std::vector<Interval> iv;
    l.query->activeIntervals(r, tMin, tMax, iv);
    for (size_t i = 1; i < iv.size(); ++i) EXPECT_LE(iv[i - 1].t1, iv[i].t0 + kTol) << what;
    expectSameSpans(unite(iv, kTol), want, what + " (activeIntervals)");
}

// Ray with direction `dir` (unit) through world point p, starting `back` before it.
Ray rayThrough(const Vec3d& p, const Vec3& dir, float back) { return Ray{toVec3(p) - dir * back, dir}; }

const Vec3 kAxes[6] = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(0, 0, -1)};

TEST(DensityBounds, SingleVoxelIsBoundedByItsTrilinearSupport) {
    TempDir dir("bounds");
    auto g = newGrid();
    const Coord c(3, -2, 5);
    g->tree().setValueOn(c, 2.f);
    const float scale = 1.5f;
    Loaded l = load(dir, g, scale);
    const std::vector<ValueBox> boxes{{CoordBBox(c, c), 2.f}};
    // Along each axis, both ways, through points off the voxel centre.
    const Vec3d offsets[3] = {Vec3d(0.3, -0.4, 0.6), Vec3d(-0.7, 0.2, -0.1), Vec3d(0.05, 0.9, -0.85)};
    for (const Vec3& a : kAxes)
        for (const Vec3d& o : offsets) {
            const Ray r = rayThrough(l.world(c.asVec3d() + o), a, 10);
            std::ostringstream what;
            what << "axis (" << a.x << "," << a.y << "," << a.z << ") offset " << o;
            checkRay(l, boxes, scale, r, 0, 100, what.str());
            // The segment's bound is the voxel's value x density_scale, and
            // the density at the voxel centre reaches it.
            const auto segs = boundsAlong(*l.query, r, 0, 100);
            ASSERT_FALSE(segs.empty());
            EXPECT_EQ(segs.front().maxDensity, 3.f);
            EXPECT_EQ(segs.front().minDensity, 0.f);
        }
    EXPECT_NEAR(l.query->density(toVec3(l.world(c.asVec3d()))), 3.f, 1e-5f);
    // Rays that pass outside the support (a quarter voxel beyond a face) see nothing.
    for (const Vec3& a : kAxes) {
        const int side = a.x != 0 ? 1 : 0;  // move off along an axis across the ray
        Vec3d off(0.1, 0.1, 0.1);
        off[side] = 1.25;
        const Ray r = rayThrough(l.world(c.asVec3d() + off), a, 10);
        EXPECT_TRUE(boundsAlong(*l.query, r, 0, 100).empty());
        std::vector<Interval> iv;
        l.query->activeIntervals(r, 0, 100, iv);
        EXPECT_TRUE(iv.empty());
    }
    // Oblique rays: the exact slab intersection of the support box.
    Rng rng(3, 1);
    for (int i = 0; i < 50; ++i) {
        const Vec3 d = sampleUniformSphere(rng.uniform(), rng.uniform());
        const Vec3d p = c.asVec3d() + Vec3d(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 1.6;
        checkRay(l, boxes, scale, rayThrough(l.world(p), d, 10), 0, 100, "oblique ray " + std::to_string(i));
    }
}

TEST(DensityBounds, VoxelOnBlockCornerIsBoundedAcrossTheEightBlocksItReaches) {
    // Index 8 starts a block and 0 and -8 too: the support (7, 9) x (-1, 1) x
    // (-9, -7) straddles eight 8^3 blocks, each of which must bound it.
    TempDir dir("bounds");
    auto g = newGrid();
    const Coord c(8, 0, -8);
    g->tree().setValueOn(c, 0.75f);
    Loaded l = load(dir, g);
    const std::vector<ValueBox> boxes{{CoordBBox(c, c), 0.75f}};
    const Vec3d offsets[4] = {Vec3d(0.3, 0.4, 0.6), Vec3d(-0.7, -0.2, -0.1), Vec3d(0.05, -0.9, 0.85),
                              Vec3d(-0.5, 0.5, -0.5)};
    for (const Vec3& a : kAxes)
        for (const Vec3d& o : offsets) {
            std::ostringstream what;
            what << "axis (" << a.x << "," << a.y << "," << a.z << ") offset " << o;
            checkRay(l, boxes, 1, rayThrough(l.world(c.asVec3d() + o), a, 10), 0, 100, what.str());
        }
    Rng rng(4, 1);
    for (int i = 0; i < 50; ++i) {
        const Vec3 d = sampleUniformSphere(rng.uniform(), rng.uniform());
        const Vec3d p = c.asVec3d() + Vec3d(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 1.6;
        checkRay(l, boxes, 1, rayThrough(l.world(p), d, 10), 0, 100, "oblique ray " + std::to_string(i));
    }
}

// Boxes of constant value: a leaf-aligned one, one across blocks, and a
// small one, filled as voxels (`asTiles` false) or, where OpenVDB can, as
// active tiles.
void checkBoxes(bool asTiles) {
    TempDir dir("bounds");
    auto g = newGrid();
    const std::vector<ValueBox> boxes{
        {CoordBBox(Coord(0, 0, 0), Coord(7, 7, 7)), 1.f},          // one leaf
        {CoordBBox(Coord(16, 0, 0), Coord(31, 15, 7)), 3.f},       // four leaves
        {CoordBBox(Coord(37, 2, 1), Coord(41, 5, 6)), 0.5f},      // part of two leaves
    };
    for (const ValueBox& b : boxes) {
        if (asTiles) g->tree().fill(b.box, b.v, true);
        else g->tree().denseFill(b.box, b.v, true);
    }
    if (asTiles) {
        ASSERT_GE(g->tree().activeTileCount(), 5u);  // the two leaf-aligned boxes are tiles
    } else {
        ASSERT_EQ(g->tree().activeTileCount(), 0u);
    }
    const float scale = 2.f;
    Loaded l = load(dir, g, scale);
    // Along x through every box (y, z inside all three), both ways, and from
    // inside with a clipped range.
    for (const Vec3d& yz : {Vec3d(0, 3.5, 3.3), Vec3d(0, 2.25, 5.75), Vec3d(0, 4.9, 1.1)}) {
        std::ostringstream what;
        what << (asTiles ? "tiles" : "voxels") << ", along x at index y, z = " << yz.y() << ", " << yz.z();
        checkRay(l, boxes, scale, rayThrough(l.world(Vec3d(-10, yz.y(), yz.z())), Vec3(1, 0, 0), 0), 0, 100,
                 what.str() + " +x");
        checkRay(l, boxes, scale, rayThrough(l.world(Vec3d(60, yz.y(), yz.z())), Vec3(-1, 0, 0), 0), 0, 100,
                 what.str() + " -x");
        // tMin and tMax inside supports: the pieces are cut there.
        checkRay(l, boxes, scale, rayThrough(l.world(Vec3d(-10, yz.y(), yz.z())), Vec3(1, 0, 0), 0), 6.f, 14.f,
                 what.str() + " +x in [6, 14]");
    }
    // Along y and z through each box.
    for (const ValueBox& b : boxes) {
        const Vec3d mid = (b.box.min().asVec3d() + b.box.max().asVec3d()) * 0.5 + Vec3d(0.3, 0.2, 0.1);
        for (const Vec3& a : kAxes) {
            std::ostringstream what;
            what << (asTiles ? "tiles" : "voxels") << ", box value " << b.v << ", axis (" << a.x << "," << a.y << ","
                 << a.z << ")";
            checkRay(l, boxes, scale, rayThrough(l.world(mid), a, 30), 0, 100, what.str());
        }
    }
    // A box's value is its density wherever the stencil is inside it.
    EXPECT_FLOAT_EQ(l.query->density(toVec3(l.world(Vec3d(3.5, 3.5, 3.3)))), 1.f * scale);
    EXPECT_FLOAT_EQ(l.query->density(toVec3(l.world(Vec3d(20.5, 8.5, 3.3)))), 3.f * scale);
}

TEST(DensityBounds, ConstantVoxelBoxesAreBoundedByTheirSupportsAndValues) { checkBoxes(false); }

// Active tiles hold the same values as the voxels above: the same supports.
//
// This test found tiles' low faces left out (the block below a tile was never
// built, so the density jumped from 0 to the tile's value at the face; fixed
// in padded_blocks.cpp, 2026-12-03): the leaf-aligned tile [0, 7]^3 along +x
// at index y, z = 3.5, 3.3 must be supported from index x = -1.
TEST(DensityBounds, ConstantActiveTilesAreBoundedByTheirSupportsAndValues) { checkBoxes(true); }

// Random voxels (and one tile) with random values; rays in all directions
// through the grid: segments ordered and disjoint, covering every point of
// non-zero density, bounding the density from both sides; the same
// coverage for activeIntervals.
TEST(DensityBounds, SegmentsCoverAndBoundTheDensityAlongRandomRays) {
    TempDir dir("bounds");
    auto g = newGrid();
    Rng rng(11, 2);
    auto acc = g->getAccessor();
    for (int i = 0; i < 4000; ++i) {
        // Clustered: most voxels near the centre, so blocks hold many values.
        const int spread = i < 3000 ? 8 : 20;
        const Coord c(int(std::floor((rng.uniform() - 0.5f) * 2 * spread)), int(std::floor((rng.uniform() - 0.5f) * 2 * spread)),
                      int(std::floor((rng.uniform() - 0.5f) * 2 * spread)));
        acc.setValueOn(c, 0.1f + 3.9f * rng.uniform());
    }
    // 27 tiles of one value over the voxels there, the middle block's padding
    // all inside them (a block with a positive minimum), and one voxel of
    // another value among them.
    g->tree().fill(CoordBBox(Coord(-24, -24, -24), Coord(-1, -1, -1)), 1.25f, true);
    acc.setValueOn(Coord(-20, -3, -5), 3.f);
    const float scale = 0.8f;
    Loaded l = load(dir, g, scale);
    MediumQuery& q = *l.query;
    const BBox wb = l.medium->worldBounds();
    const Vec3 centre = wb.center();
    const float radius = length(wb.extent());
    int inside = 0, outsidePositive = 0, withControl = 0, nonZero = 0;
    std::vector<Interval> iv;
    for (int ray = 0; ray < 300; ++ray) {
        const Vec3 from = centre + sampleUniformSphere(rng.uniform(), rng.uniform()) * radius;
        const Vec3 to = ray < 100 ? centre + (Vec3(rng.uniform(), rng.uniform(), rng.uniform()) - Vec3(0.5f)) * (0.3f * radius)
                                  : wb.lo + (wb.hi - wb.lo) * Vec3(rng.uniform(), rng.uniform(), rng.uniform());
        Ray r{from, normalize(to - from)};
        if (ray % 50 == 0) r = Ray{from, kAxes[(ray / 50) % 6]};  // and some along the axes
        const float tMax = 2 * radius;
        const std::vector<DensityBound> segs = boundsAlong(q, r, 0, tMax);
        iv.clear();
        q.activeIntervals(r, 0, tMax, iv);
        for (size_t i = 0; i < segs.size(); ++i) {
            ASSERT_LT(segs[i].t0, segs[i].t1);
            ASSERT_GE(segs[i].t0, 0.f);
            ASSERT_LE(segs[i].t1, tMax);
            if (i > 0) {
                ASSERT_LE(segs[i - 1].t1, segs[i].t0 + 1e-5f) << "ray " << ray;
            }
            ASSERT_LE(0.f, segs[i].minDensity);
            ASSERT_LE(segs[i].minDensity, segs[i].maxDensity);
            withControl += segs[i].minDensity > 0;
        }
        for (size_t i = 1; i < iv.size(); ++i) ASSERT_LE(iv[i - 1].t1, iv[i].t0 + 1e-5f) << "ray " << ray;
        const int n = 2000;
        size_t si = 0, ii = 0;
        for (int j = 0; j < n; ++j) {
            const float t = (j + 0.5f) / n * tMax;
            const float d = q.density(r.at(t));
            while (si < segs.size() && segs[si].t1 < t) ++si;
            while (ii < iv.size() && iv[ii].t1 < t) ++ii;
            const bool inSeg = si < segs.size() && segs[si].t0 <= t;
            const bool inIv = ii < iv.size() && iv[ii].t0 <= t;
            nonZero += d > 0;
            if (inSeg) {
                ++inside;
                const DensityBound& s = segs[si];
                ASSERT_LE(d, s.maxDensity * (1 + 1e-5f)) << "ray " << ray << " t " << t;
                ASSERT_GE(d, s.minDensity * (1 - 1e-5f)) << "ray " << ray << " t " << t;
            } else if (d > 0) {
                ++outsidePositive;
                ADD_FAILURE() << "ray " << ray << " t " << t << ": density " << d << " outside every segment";
            }
            if (!inIv && d > 0) ADD_FAILURE() << "ray " << ray << " t " << t << ": density " << d << " outside every active interval";
        }
    }
    std::printf("%d of %d points with density > 0, %d in segments, %d segments with a control\n", nonZero,
                300 * 2000, inside, withControl);
    EXPECT_EQ(outsidePositive, 0);
    EXPECT_GT(nonZero, 300 * 2000 / 40);  // the rays do cross the grid
    EXPECT_GT(inside, nonZero);    // and segments hold empty space too, but not all of the ray
    EXPECT_LT(inside, 300 * 2000);
    EXPECT_GT(withControl, 0);     // some blocks give residual tracking a control
}

}  // namespace
}  // namespace vdbmarch
