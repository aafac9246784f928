// make_samples: deterministic generator of the sample volumes bundled in
// vdb_samples/ (cloud.vdb, plume.vdb, sparse.vdb) and of the closed glass mesh
// used by the paper's test scenes (scenes/knot.obj, a trefoil-knot tube).
//
// Usage: make_samples OUTPUT_DIR [cloud|plume|sparse|knot ...]
//
// With no names every file is written; with names only those (so that
// `make_samples vdb_samples knot` rewrites the mesh without touching the .vdb
// files and their random UUIDs).
//
// Standalone: depends only on OpenVDB, TBB and the C++17 standard library.
// Every voxel value is a pure function of its index coordinate (fixed-seed
// hash noise, no shared mutable state), grids are filled in leaf-sized 8^3
// blocks with tbb::parallel_for and the resulting leaves are inserted into the
// tree serially in block order, so the voxel data is bit-identical for any
// thread count (the per-grid checksum printed at the end makes this easy to
// check). Note that io::File stamps every .vdb with a random UUID, so two runs
// produce files that differ in those ~36 header bytes only. The OBJ mesh is
// plain text written with fixed precision: byte-identical on every run.

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/tools/Count.h>
#include <openvdb/tools/Prune.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::FloatGrid;
using openvdb::FloatTree;
using Vec3 = openvdb::Vec3d;
using LeafT = FloatTree::LeafNodeType;

// ---------------------------------------------------------------------------
// Small deterministic 3D gradient noise (Perlin-style, integer hash lattice).
// ---------------------------------------------------------------------------

inline std::uint32_t hash3(std::int32_t x, std::int32_t y, std::int32_t z, std::uint32_t seed)
{
    std::uint32_t h = seed * 0x9E3779B1u;
    h ^= static_cast<std::uint32_t>(x) * 0x8DA6B343u;
    h ^= static_cast<std::uint32_t>(y) * 0xD8163841u;
    h ^= static_cast<std::uint32_t>(z) * 0xCB1AB31Fu;
    // murmur3 finaliser
    h ^= h >> 16;
    h *= 0x85EBCA6Bu;
    h ^= h >> 13;
    h *= 0xC2B2AE35u;
    h ^= h >> 16;
    return h;
}

// The 12 cube-edge gradients plus 4 repeats (Perlin's improved noise set).
inline double gradDot(std::uint32_t h, double x, double y, double z)
{
    switch (h & 15u) {
    case 0: return x + y;
    case 1: return -x + y;
    case 2: return x - y;
    case 3: return -x - y;
    case 4: return x + z;
    case 5: return -x + z;
    case 6: return x - z;
    case 7: return -x - z;
    case 8: return y + z;
    case 9: return -y + z;
    case 10: return y - z;
    case 11: return -y - z;
    case 12: return x + y;
    case 13: return -x + y;
    case 14: return -y + z;
    default: return -y - z;
    }
}

inline double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
inline double lerp(double a, double b, double t) { return a + (b - a) * t; }

// Gradient noise, roughly in [-1, 1].
double gnoise(const Vec3& p, std::uint32_t seed)
{
    const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
    const auto ix = static_cast<std::int32_t>(fx);
    const auto iy = static_cast<std::int32_t>(fy);
    const auto iz = static_cast<std::int32_t>(fz);
    const double x = p.x() - fx, y = p.y() - fy, z = p.z() - fz;
    const double u = fade(x), v = fade(y), w = fade(z);

    const double n000 = gradDot(hash3(ix, iy, iz, seed), x, y, z);
    const double n100 = gradDot(hash3(ix + 1, iy, iz, seed), x - 1, y, z);
    const double n010 = gradDot(hash3(ix, iy + 1, iz, seed), x, y - 1, z);
    const double n110 = gradDot(hash3(ix + 1, iy + 1, iz, seed), x - 1, y - 1, z);
    const double n001 = gradDot(hash3(ix, iy, iz + 1, seed), x, y, z - 1);
    const double n101 = gradDot(hash3(ix + 1, iy, iz + 1, seed), x - 1, y, z - 1);
    const double n011 = gradDot(hash3(ix, iy + 1, iz + 1, seed), x, y - 1, z - 1);
    const double n111 = gradDot(hash3(ix + 1, iy + 1, iz + 1, seed), x - 1, y - 1, z - 1);

    const double nx00 = lerp(n000, n100, u), nx10 = lerp(n010, n110, u);
    const double nx01 = lerp(n001, n101, u), nx11 = lerp(n011, n111, u);
    const double nxy0 = lerp(nx00, nx10, v), nxy1 = lerp(nx01, nx11, v);
    return lerp(nxy0, nxy1, w);
}

// Fractal sum of gradient noise; each octave is shifted to break up lattice
// alignment. Normalised to roughly [-1, 1].
double fbm(Vec3 p, int octaves, std::uint32_t seed, double lacunarity = 2.03, double gain = 0.5)
{
    double sum = 0.0, amp = 1.0, norm = 0.0;
    for (int o = 0; o < octaves; ++o) {
        sum += amp * gnoise(p, seed + 101u * static_cast<std::uint32_t>(o));
        norm += amp;
        amp *= gain;
        p = Vec3(p.y() * lacunarity + 17.3, p.z() * lacunarity - 5.1, p.x() * lacunarity + 9.7);
    }
    return sum / norm;
}

// "Billow" fractal: sum of |noise|, gives rounded cauliflower-like bumps.
// Roughly in [0, 1].
double billow(Vec3 p, int octaves, std::uint32_t seed, double lacunarity = 2.07, double gain = 0.5)
{
    double sum = 0.0, amp = 1.0, norm = 0.0;
    for (int o = 0; o < octaves; ++o) {
        sum += amp * std::abs(gnoise(p, seed + 977u * static_cast<std::uint32_t>(o)));
        norm += amp;
        amp *= gain;
        p = Vec3(p.z() * lacunarity - 3.3, p.x() * lacunarity + 11.9, p.y() * lacunarity + 2.5);
    }
    return 1.6 * sum / norm;
}

inline double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }
inline double smoothstep(double e0, double e1, double x)
{
    const double t = clamp01((x - e0) / (e1 - e0));
    return t * t * (3.0 - 2.0 * t);
}
// Polynomial smooth minimum / maximum (Quilez).
inline double smin(double a, double b, double k)
{
    const double h = clamp01(0.5 + 0.5 * (b - a) / k);
    return lerp(b, a, h) - k * h * (1.0 - h);
}
inline double smax(double a, double b, double k) { return -smin(-a, -b, k); }

// Approximate signed distance to an axis-aligned ellipsoid.
inline double sdEllipsoid(const Vec3& p, const Vec3& c, const Vec3& r)
{
    const Vec3 q = p - c;
    const double k0 = Vec3(q.x() / r.x(), q.y() / r.y(), q.z() / r.z()).length();
    const double k1 =
        Vec3(q.x() / (r.x() * r.x()), q.y() / (r.y() * r.y()), q.z() / (r.z() * r.z())).length();
    if (k1 < 1e-12) return -std::min(r.x(), std::min(r.y(), r.z()));
    return k0 * (k0 - 1.0) / k1;
}

// ---------------------------------------------------------------------------
// Parallel, deterministic grid construction in 8^3 leaf blocks.
// ---------------------------------------------------------------------------

// Value quantum below which a voxel is treated as background (inactive 0).
constexpr float kCutoff = 1.0f / 1024.0f;

// Leaf origins (multiples of 8) of all leaves touching bbox.
std::vector<Coord> leafOriginsIn(const CoordBBox& bbox)
{
    std::vector<Coord> out;
    const Coord lo = bbox.min() & ~(LeafT::DIM - 1);
    const Coord hi = bbox.max() & ~(LeafT::DIM - 1);
    for (int x = lo.x(); x <= hi.x(); x += LeafT::DIM)
        for (int y = lo.y(); y <= hi.y(); y += LeafT::DIM)
            for (int z = lo.z(); z <= hi.z(); z += LeafT::DIM) out.emplace_back(x, y, z);
    return out;
}

// Evaluate fn (Coord -> std::array<float, N>) at every voxel of each candidate
// leaf block, in parallel, and build N fog-volume grids whose active voxels are
// exactly those with value >= kCutoff (values clamped to [0, 1]). Leaves are
// added serially in block order, so the result does not depend on scheduling.
template <size_t N, typename Fn>
std::array<FloatGrid::Ptr, N> buildGrids(const std::vector<Coord>& origins, const Fn& fn,
                                         const openvdb::math::Transform::Ptr& xform)
{
    std::vector<std::array<std::unique_ptr<LeafT>, N>> leaves(origins.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, origins.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) {
                              std::array<std::unique_ptr<LeafT>, N> block;
                              for (auto& leaf : block) leaf = std::make_unique<LeafT>(origins[i], 0.0f, false);
                              std::array<bool, N> any{};
                              for (openvdb::Index n = 0; n < LeafT::SIZE; ++n) {
                                  const std::array<float, N> v = fn(block[0]->offsetToGlobalCoord(n));
                                  for (size_t c = 0; c < N; ++c) {
                                      if (!(v[c] >= kCutoff)) continue; // also rejects NaN
                                      block[c]->setValueOn(n, std::min(v[c], 1.0f));
                                      any[c] = true;
                                  }
                              }
                              for (size_t c = 0; c < N; ++c)
                                  if (any[c]) leaves[i][c] = std::move(block[c]);
                          }
                      });
    std::array<FloatGrid::Ptr, N> grids;
    for (size_t c = 0; c < N; ++c) {
        grids[c] = FloatGrid::create(0.0f);
        grids[c]->setTransform(xform->copy());
        for (auto& block : leaves)
            if (block[c]) grids[c]->tree().addLeaf(block[c].release());
        openvdb::tools::prune(grids[c]->tree());
    }
    return grids;
}

void tagGrid(FloatGrid& grid, const std::string& name, const std::string& generator)
{
    grid.setName(name);
    grid.setGridClass(openvdb::GRID_FOG_VOLUME);
    grid.setSaveFloatAsHalf(true);
    grid.insertMeta("generator", openvdb::StringMetadata(generator));
}

// ---------------------------------------------------------------------------
// 1. cloud.vdb: cumulus-like cloud.
// ---------------------------------------------------------------------------

constexpr double kCloudVoxel = 0.016;
constexpr std::uint32_t kCloudSeed = 1234u;
constexpr double kCloudBase = -0.4;

struct Sphere {
    Vec3 c;
    Vec3 r;
};

const std::array<Sphere, 13>& cloudPuffs()
{
    static const std::array<Sphere, 13> puffs = {{
        // broad flat-bottomed body
        {Vec3(0.0, -0.16, 0.0), Vec3(0.90, 0.36, 0.66)},
        {Vec3(-0.55, -0.20, 0.10), Vec3(0.40, 0.32, 0.42)},
        {Vec3(0.58, -0.22, -0.08), Vec3(0.38, 0.30, 0.40)},
        // puffy towers on top
        {Vec3(-0.30, 0.18, 0.02), Vec3(0.36, 0.34, 0.34)},
        {Vec3(0.28, 0.18, -0.06), Vec3(0.38, 0.36, 0.36)},
        {Vec3(0.02, 0.40, 0.02), Vec3(0.34, 0.32, 0.32)},
        {Vec3(-0.06, 0.58, -0.02), Vec3(0.20, 0.18, 0.20)},
        {Vec3(0.42, 0.36, 0.10), Vec3(0.22, 0.22, 0.22)},
        {Vec3(-0.58, 0.12, -0.10), Vec3(0.24, 0.22, 0.24)},
        {Vec3(0.10, 0.08, 0.34), Vec3(0.30, 0.28, 0.26)},
        {Vec3(-0.18, 0.10, -0.34), Vec3(0.28, 0.26, 0.24)},
        {Vec3(0.48, -0.10, 0.34), Vec3(0.30, 0.24, 0.28)},
        {Vec3(-0.42, -0.12, -0.36), Vec3(0.30, 0.24, 0.28)},
    }};
    return puffs;
}

// Undisplaced signed distance of the cloud's base shape (world units).
double cloudBaseSdf(const Vec3& p)
{
    double d = 1e9;
    for (const Sphere& s : cloudPuffs()) d = smin(d, sdEllipsoid(p, s.c, s.r), 0.08);
    return smax(d, kCloudBase - p.y(), 0.04); // flat-ish bottom
}

constexpr double kCloudDispMax = 0.17; // bound on |displacement| + edge width

float cloudDensity(const Vec3& p)
{
    const double d0 = cloudBaseSdf(p);
    if (d0 > kCloudDispMax) return 0.0f;
    // Displacement is suppressed near the base so the bottom stays flat.
    const double up = smoothstep(kCloudBase, kCloudBase + 0.25, p.y());
    // Domain warp for less regular puffs.
    const Vec3 w(fbm(p * 1.7, 2, kCloudSeed + 1), fbm(p * 1.7, 2, kCloudSeed + 2),
                 fbm(p * 1.7, 2, kCloudSeed + 3));
    const Vec3 q = p + 0.12 * w;
    // Large cauliflower bumps (outward) plus finer billows.
    const double big = billow(q * 3.2, 4, kCloudSeed + 10);
    const double fine = fbm(q * 14.0, 3, kCloudSeed + 20);
    const double disp = (0.10 * big - 0.035) * (0.35 + 0.65 * up) + 0.022 * fine;
    const double d = d0 - disp;
    // Soft edge, eroded by high-frequency noise so the boundary is wispy.
    const double wisp = fbm(p * 28.0, 2, kCloudSeed + 30);
    const double edge = 0.045;
    double dens = smoothstep(0.0, edge, -d + 0.012 * wisp);
    // Internal variation.
    dens *= 0.82 + 0.18 * fbm(p * 6.0, 3, kCloudSeed + 40);
    return static_cast<float>(clamp01(dens * 1.15));
}

FloatGrid::Ptr makeCloud()
{
    auto xform = openvdb::math::Transform::createLinearTransform(kCloudVoxel);
    const double m = kCloudDispMax;
    const CoordBBox region(xform->worldToIndexCellCentered(Vec3(-1.0 - m, kCloudBase - 0.05, -0.7 - m)),
                           xform->worldToIndexCellCentered(Vec3(1.0 + m, 0.8 + m, 0.7 + m)));
    std::vector<Coord> origins;
    const double blockRadius = 0.5 * std::sqrt(3.0) * LeafT::DIM * kCloudVoxel;
    for (const Coord& o : leafOriginsIn(region)) {
        const Vec3 c = xform->indexToWorld(o.asVec3d() + Vec3(3.5));
        if (cloudBaseSdf(c) <= kCloudDispMax + blockRadius) origins.push_back(o);
    }
    auto grid = buildGrids<1>(
        origins,
        [&](const Coord& ijk) { return std::array<float, 1>{cloudDensity(xform->indexToWorld(ijk))}; },
        xform)[0];
    std::ostringstream gen;
    gen << "make_samples cloud: " << cloudPuffs().size() << " ellipsoids, base y=" << kCloudBase
        << ", billow+fbm displacement, seed=" << kCloudSeed << ", voxel=" << kCloudVoxel;
    tagGrid(*grid, "density", gen.str());
    return grid;
}

// ---------------------------------------------------------------------------
// 2. plume.vdb: rising smoke plume with temperature.
// ---------------------------------------------------------------------------

constexpr double kPlumeVoxel = 0.02;
constexpr std::uint32_t kPlumeSeed = 777u;
constexpr double kPlumeHeight = 2.9;  // 145 voxels (top fades out)
constexpr double kPlumeR0 = 0.12;     // source disk radius
constexpr double kPlumeR1 = 0.72;     // radius at the top

struct PlumeSample {
    double density;
    double temperature;
};

PlumeSample plumeAt(const Vec3& p)
{
    const double t = p.y() / kPlumeHeight;
    if (t < 0.0 || t > 1.0) return {0.0, 0.0};
    // Swaying centre line.
    const double sway = 0.18 * std::pow(t, 1.3);
    const double cx = sway * gnoise(Vec3(0.0, p.y() * 0.9, 0.5), kPlumeSeed + 1);
    const double cz = sway * gnoise(Vec3(0.5, p.y() * 0.9, 0.0), kPlumeSeed + 2);
    // Turbulent domain warp growing with height (eddies get bigger and
    // stronger as the plume rises and mixes).
    const double wamp = 0.03 + 0.24 * t;
    const double famp = 0.025 + 0.03 * t;
    const double R = kPlumeR0 + (kPlumeR1 - kPlumeR0) * std::pow(t, 0.8);
    // Conservative early out (|noise| <= ~1, padded by 25%): far from the
    // axis the result is 0 whatever the noise does.
    if (std::hypot(p.x(), p.z()) > 1.5 * R + 1.25 * (std::sqrt(2.0) * sway + std::sqrt(3.0) * (wamp + famp)))
        return {0.0, 0.0};
    const Vec3 pn(p.x() * 2.8, p.y() * 2.2, p.z() * 2.8);
    const Vec3 w(fbm(pn, 4, kPlumeSeed + 10), fbm(pn, 4, kPlumeSeed + 11), fbm(pn, 4, kPlumeSeed + 12));
    const Vec3 pf(p.x() * 9.0, p.y() * 7.0, p.z() * 9.0);
    const Vec3 wf(fbm(pf, 2, kPlumeSeed + 13), fbm(pf, 2, kPlumeSeed + 14), fbm(pf, 2, kPlumeSeed + 15));
    const Vec3 q = p + wamp * w + famp * wf;
    const double dx = q.x() - cx, dz = q.z() - cz;
    const double r = std::sqrt(dx * dx + dz * dz);
    if (r > 1.5 * R) return {0.0, 0.0};

    // Billowing puffs; contrast grows with height so the top breaks up.
    const double puff = fbm(Vec3(q.x() * 6.5, q.y() * 4.5, q.z() * 6.5), 5, kPlumeSeed + 20);
    const double radial = std::exp(-2.4 * (r / R) * (r / R));
    const double fadeTop = 1.0 - smoothstep(0.7, 1.0, t + 0.22 * puff);
    const double fadeBase = smoothstep(0.0, 0.03, t);
    const double contrast = 0.9 + 0.8 * t;
    double dens = radial * (1.0 + contrast * puff) * (1.0 - 0.55 * t) * fadeTop * fadeBase;
    dens = clamp01((dens - 0.08) / 0.75);

    const double core = std::exp(-3.5 * (r / R) * (r / R));
    double temp = 1.2 * std::exp(-3.0 * t) * core * (0.85 + 0.3 * puff) * fadeTop * fadeBase;
    temp = clamp01((temp - 0.02) / 0.95);
    return {dens, temp};
}

std::vector<FloatGrid::Ptr> makePlume()
{
    auto xform = openvdb::math::Transform::createLinearTransform(kPlumeVoxel);
    const CoordBBox region(Coord(-48, 0, -48), Coord(48, 150, 48));
    const std::vector<Coord> origins = leafOriginsIn(region);
    auto grids = buildGrids<2>(
        origins,
        [&](const Coord& ijk) {
            const PlumeSample s = plumeAt(xform->indexToWorld(ijk));
            return std::array<float, 2>{static_cast<float>(s.density), static_cast<float>(s.temperature)};
        },
        xform);
    FloatGrid::Ptr density = grids[0], temperature = grids[1];
    std::ostringstream gen;
    gen << "make_samples plume: source disk r=" << kPlumeR0 << " at y=0, top r=" << kPlumeR1
        << ", height=" << kPlumeHeight << ", warped fbm turbulence, seed=" << kPlumeSeed
        << ", voxel=" << kPlumeVoxel;
    tagGrid(*density, "density", gen.str());
    tagGrid(*temperature, "temperature", gen.str());
    return {density, temperature};
}

// ---------------------------------------------------------------------------
// 3. sparse.vdb: six small blobs in a ~400^3 voxel bounding box.
// ---------------------------------------------------------------------------

constexpr double kSparseVoxel = 0.01;
constexpr std::uint32_t kSparseSeed = 4242u;

struct Blob {
    Coord c;  // index-space centre
    double r; // radius in voxels
};

const std::array<Blob, 6>& sparseBlobs()
{
    static const std::array<Blob, 6> blobs = {{
        {Coord(-188, -180, -185), 8.0},
        {Coord(190, 185, 188), 10.0},
        {Coord(-150, 160, 120), 7.0},
        {Coord(170, -140, -60), 9.0},
        {Coord(20, 30, -170), 6.0},
        {Coord(-40, -20, 40), 10.0},
    }};
    return blobs;
}

float sparseDensity(const Coord& ijk)
{
    double best = 0.0;
    std::uint32_t k = 0;
    for (const Blob& b : sparseBlobs()) {
        ++k;
        const Vec3 d = ijk.asVec3d() - b.c.asVec3d();
        const double dist = d.length();
        if (dist > 1.5 * b.r) continue;
        const Vec3 pn = ijk.asVec3d() * (1.0 / 3.5);
        const double n = fbm(pn, 3, kSparseSeed + 13u * k);
        const double rr = dist / b.r + 0.35 * n;
        const double v = smoothstep(1.0, 0.15, rr) * (0.8 + 0.2 * fbm(pn * 2.0, 2, kSparseSeed + 7u * k));
        best = std::max(best, v);
    }
    return static_cast<float>(clamp01(best));
}

FloatGrid::Ptr makeSparse()
{
    auto xform = openvdb::math::Transform::createLinearTransform(kSparseVoxel);
    std::set<Coord> unique;
    for (const Blob& b : sparseBlobs()) {
        const int ext = static_cast<int>(std::ceil(1.5 * b.r)) + 1;
        for (const Coord& o : leafOriginsIn(CoordBBox(b.c - Coord(ext), b.c + Coord(ext)))) unique.insert(o);
    }
    const std::vector<Coord> origins(unique.begin(), unique.end());
    auto grid = buildGrids<1>(
        origins, [](const Coord& ijk) { return std::array<float, 1>{sparseDensity(ijk)}; }, xform)[0];
    std::ostringstream gen;
    gen << "make_samples sparse: " << sparseBlobs().size() << " noisy blobs r=6..10 voxels in ~400^3 voxels"
        << ", seed=" << kSparseSeed << ", voxel=" << kSparseVoxel;
    tagGrid(*grid, "density", gen.str());
    return grid;
}


// ---------------------------------------------------------------------------
// 4. scenes/knot.obj: a closed, smooth glass object (trefoil-knot tube).
// ---------------------------------------------------------------------------
//
// The paper's experiments put a Fresnel glass dragon around a forward-scattering
// medium; the Stanford models cannot be bundled (and the bunny is not
// watertight), so the scenes use this procedural stand-in instead: a tube of
// constant radius swept along the (2,3) torus knot
//     c(t) = ((R + r cos 3t) cos 2t, (R + r cos 3t) sin 2t, r sin 3t)
// with R = 1, r = 0.45, tube radius 0.34, then scaled by 0.4 (about 1.4 x 1.4
// x 0.6 world units, tube radius 0.136, centred on the origin, the knot's
// symmetry axis along z). The curve is resampled at equal arc length; the
// frame around it is the direction away from the torus core circle,
// orthogonalised against the tangent, which is periodic (unlike a
// parallel-transport frame), so the surface closes on itself in both
// directions with shared vertex indices: watertight by construction. Every
// vertex has its exact normal (the tube is a canal surface: the normal is the
// unit offset from the curve). Triangles are counter-clockwise seen from
// outside. The generator checks all of it (each edge used twice in opposite
// directions, positive enclosed volume, normals agreeing with the winding,
// no self-intersection) and refuses to write a broken mesh.

constexpr double kKnotR = 1.0;          // torus core radius
constexpr double kKnotr = 0.45;         // torus tube radius the curve winds on
constexpr double kKnotTube = 0.34;      // radius of the glass tube around the curve
constexpr double kKnotScale = 0.4;      // final uniform scale
constexpr int kKnotSegments = 200;      // rings along the curve
constexpr int kKnotSides = 16;          // vertices per ring

Vec3 knotCurve(double t)
{
    const double rho = kKnotR + kKnotr * std::cos(3.0 * t);
    return Vec3(rho * std::cos(2.0 * t), rho * std::sin(2.0 * t), kKnotr * std::sin(3.0 * t));
}

Vec3 knotTangent(double t)
{
    // Analytic derivative of knotCurve.
    const double rho = kKnotR + kKnotr * std::cos(3.0 * t);
    const double drho = -3.0 * kKnotr * std::sin(3.0 * t);
    return Vec3(drho * std::cos(2.0 * t) - 2.0 * rho * std::sin(2.0 * t),
                drho * std::sin(2.0 * t) + 2.0 * rho * std::cos(2.0 * t), 3.0 * kKnotr * std::cos(3.0 * t));
}

struct Mesh {
    std::vector<Vec3> positions, normals;
    std::vector<std::array<int, 3>> triangles; // 0-based
};

Mesh makeKnot()
{
    // Equal arc-length parameters from a fine cumulative-length table.
    constexpr int kFine = 20000;
    std::vector<double> cum(kFine + 1, 0.0);
    for (int i = 0; i < kFine; ++i) {
        const double t0 = 2.0 * M_PI * i / kFine, t1 = 2.0 * M_PI * (i + 1) / kFine;
        cum[i + 1] = cum[i] + (knotCurve(t1) - knotCurve(t0)).length();
    }
    const double length = cum[kFine];
    std::vector<double> params(kKnotSegments);
    int j = 0;
    for (int i = 0; i < kKnotSegments; ++i) {
        const double target = length * i / kKnotSegments;
        while (j < kFine - 1 && cum[j + 1] < target) ++j;
        const double f = (target - cum[j]) / (cum[j + 1] - cum[j]);
        params[i] = 2.0 * M_PI * (j + f) / kFine;
    }

    Mesh m;
    for (int i = 0; i < kKnotSegments; ++i) {
        const double t = params[i];
        const Vec3 c = knotCurve(t);
        const Vec3 T = knotTangent(t).unitSafe();
        // Away from the torus core circle, made orthogonal to the tangent.
        Vec3 N = c - kKnotR * Vec3(std::cos(2.0 * t), std::sin(2.0 * t), 0.0);
        N = (N - N.dot(T) * T).unitSafe();
        const Vec3 B = T.cross(N);
        for (int k = 0; k < kKnotSides; ++k) {
            const double phi = 2.0 * M_PI * k / kKnotSides;
            const Vec3 n = std::cos(phi) * N + std::sin(phi) * B;
            m.positions.push_back(kKnotScale * (c + kKnotTube * n));
            m.normals.push_back(n);
        }
    }
    auto id = [](int i, int k) { return (i % kKnotSegments) * kKnotSides + (k % kKnotSides); };
    // d/dt x d/dphi = T x (-sin N + cos B) points inwards, so each quad goes
    // (i,k) -> (i,k+1) -> (i+1,k+1) -> (i+1,k): counter-clockwise from outside.
    for (int i = 0; i < kKnotSegments; ++i)
        for (int k = 0; k < kKnotSides; ++k) {
            const int a = id(i, k), b = id(i, k + 1), c = id(i + 1, k + 1), d = id(i + 1, k);
            m.triangles.push_back({a, b, c});
            m.triangles.push_back({a, c, d});
        }
    return m;
}

// Throws unless the mesh is closed, consistently wound outwards, its normals
// agree with the winding and the tube does not touch itself.
void checkKnot(const Mesh& m)
{
    std::map<std::pair<int, int>, int> directed;
    double volume = 0.0;
    int normalDisagree = 0;
    for (const auto& tri : m.triangles) {
        for (int e = 0; e < 3; ++e) ++directed[{tri[e], tri[(e + 1) % 3]}];
        const Vec3 &p0 = m.positions[tri[0]], &p1 = m.positions[tri[1]], &p2 = m.positions[tri[2]];
        volume += p0.dot(p1.cross(p2)) / 6.0;
        const Vec3 fn = (p1 - p0).cross(p2 - p0);
        if (fn.dot(m.normals[tri[0]] + m.normals[tri[1]] + m.normals[tri[2]]) <= 0.0) ++normalDisagree;
    }
    for (const auto& [edge, uses] : directed)
        if (uses != 1 || directed.count({edge.second, edge.first}) != 1)
            throw std::runtime_error("knot mesh is not a closed, consistently wound manifold");
    if (!(volume > 0.0)) throw std::runtime_error("knot mesh is wound inwards");
    if (normalDisagree) throw std::runtime_error("knot mesh normals disagree with the winding");
    // Self-intersection: curve points further apart along the curve than half
    // a loop of the tube's circumference must be more than two tube radii
    // apart (plus margin); the tube radius must also stay below the smallest
    // radius of curvature, checked by the same test on nearby points.
    constexpr int kN = 1000;
    std::vector<Vec3> pts(kN);
    for (int i = 0; i < kN; ++i) pts[i] = knotCurve(2.0 * M_PI * i / kN);
    double minSep = 1e30;
    for (int a = 0; a < kN; ++a)
        for (int b = a + 1; b < kN; ++b) {
            const int gap = std::min(b - a, kN - (b - a));
            if (gap < kN / 12) continue; // neighbours along the curve
            minSep = std::min(minSep, (pts[a] - pts[b]).length());
        }
    if (minSep < 2.2 * kKnotTube) throw std::runtime_error("knot tube intersects itself");
    std::printf("  knot: closed, outward, normals consistent; volume %.4f, strand clearance %.3f\n", volume,
                kKnotScale * (minSep - 2.0 * kKnotTube));
}

void writeObj(const std::filesystem::path& path, const Mesh& m, const std::string& comment, double genSeconds)
{
    std::filesystem::create_directories(path.parent_path());
    const std::string tmp = path.string() + ".tmp";
    std::FILE* f = std::fopen(tmp.c_str(), "w");
    if (!f) throw std::runtime_error("cannot write " + tmp);
    std::fprintf(f, "# %s\n# %zu vertices, %zu triangles, closed, counter-clockwise seen from outside\n",
                 comment.c_str(), m.positions.size(), m.triangles.size());
    auto num = [](double v) { return std::abs(v) < 5e-6 ? 0.0 : v; }; // no "-0.00000"
    for (const Vec3& p : m.positions) std::fprintf(f, "v %.5f %.5f %.5f\n", num(p.x()), num(p.y()), num(p.z()));
    for (const Vec3& n : m.normals) std::fprintf(f, "vn %.4f %.4f %.4f\n", num(n.x()), num(n.y()), num(n.z()));
    for (const auto& t : m.triangles)
        std::fprintf(f, "f %d//%d %d//%d %d//%d\n", t[0] + 1, t[0] + 1, t[1] + 1, t[1] + 1, t[2] + 1, t[2] + 1);
    const bool ok = std::fflush(f) == 0 && !std::ferror(f);
    std::fclose(f);
    if (!ok) throw std::runtime_error("error writing " + tmp);
    std::filesystem::rename(tmp, path);

    Vec3 lo(1e30), hi(-1e30);
    for (const Vec3& p : m.positions)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    std::printf("%s: %llu bytes, generated in %.2f s\n", path.string().c_str(),
                static_cast<unsigned long long>(std::filesystem::file_size(path)), genSeconds);
    std::printf("  %zu vertices, %zu triangles, bbox (%.3f,%.3f,%.3f)..(%.3f,%.3f,%.3f)\n", m.positions.size(),
                m.triangles.size(), lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
}

// ---------------------------------------------------------------------------

// FNV-1a over (coord, value bits) of all active voxels in tree order: a
// fingerprint to check that the output is the same for any thread count.
std::uint64_t checksum(const FloatGrid& grid)
{
    std::uint64_t h = 0xCBF29CE484222325ull;
    auto mix = [&h](std::uint32_t v) {
        for (int b = 0; b < 4; ++b) {
            h ^= (v >> (8 * b)) & 0xFFu;
            h *= 0x100000001B3ull;
        }
    };
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        CoordBBox bb;
        it.getBoundingBox(bb);
        for (int a = 0; a < 3; ++a) mix(static_cast<std::uint32_t>(bb.min()[a]));
        for (int a = 0; a < 3; ++a) mix(static_cast<std::uint32_t>(bb.max()[a]));
        const float v = *it;
        std::uint32_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        mix(bits);
    }
    return h;
}

void writeFile(const std::filesystem::path& path, const openvdb::GridPtrVec& grids, double genSeconds)
{
    openvdb::io::File file(path.string());
#ifdef OPENVDB_USE_BLOSC
    file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
#else
    file.setCompression(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK);
#endif
    openvdb::MetaMap meta;
    meta.insertMeta("generator", openvdb::StringMetadata("make_samples (vdbmarch)"));
    file.write(grids, meta);
    file.close();

    std::printf("%s: %llu bytes, generated in %.2f s\n", path.string().c_str(),
                static_cast<unsigned long long>(std::filesystem::file_size(path)), genSeconds);
    for (const auto& base : grids) {
        const auto grid = openvdb::gridConstPtrCast<FloatGrid>(base);
        if (!grid) continue;
        const CoordBBox bb = grid->evalActiveVoxelBoundingBox();
        const auto mm = openvdb::tools::minMax(grid->tree());
        const Coord dim = bb.dim();
        const double frac = static_cast<double>(grid->activeVoxelCount()) /
                            (static_cast<double>(dim.x()) * dim.y() * dim.z());
        std::printf("  grid '%s': active voxels %llu (%.3f%% of bbox), leaves %llu, tiles %llu\n",
                    grid->getName().c_str(), static_cast<unsigned long long>(grid->activeVoxelCount()),
                    100.0 * frac, static_cast<unsigned long long>(grid->tree().leafCount()),
                    static_cast<unsigned long long>(grid->tree().activeTileCount()));
        std::printf("    index bbox [%d,%d,%d]..[%d,%d,%d] (%dx%dx%d), voxel size %g\n", bb.min().x(),
                    bb.min().y(), bb.min().z(), bb.max().x(), bb.max().y(), bb.max().z(), dim.x(),
                    dim.y(), dim.z(), grid->voxelSize().x());
        const Vec3 wlo = grid->indexToWorld(bb.min().asVec3d() - Vec3(0.5));
        const Vec3 whi = grid->indexToWorld(bb.max().asVec3d() + Vec3(0.5));
        std::printf("    world bbox (%.3f,%.3f,%.3f)..(%.3f,%.3f,%.3f)\n", wlo.x(), wlo.y(), wlo.z(),
                    whi.x(), whi.y(), whi.z());
        std::printf("    value range [%g, %g], checksum %016llx\n", mm.min(), mm.max(),
                    static_cast<unsigned long long>(checksum(*grid)));
    }
}

} // namespace

int main(int argc, char** argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "Usage: %s OUTPUT_DIR [cloud|plume|sparse|knot ...]\n",
                     argc > 0 ? argv[0] : "make_samples");
        return 2;
    }
    const std::set<std::string> known = {"cloud", "plume", "sparse", "knot"};
    std::set<std::string> wanted;
    for (int i = 2; i < argc; ++i) {
        if (!known.count(argv[i])) {
            std::fprintf(stderr, "make_samples: error: unknown sample '%s' (expected cloud, plume, sparse or knot)\n",
                         argv[i]);
            return 2;
        }
        wanted.insert(argv[i]);
    }
    if (wanted.empty()) wanted = known;
    try {
        openvdb::initialize();
        const std::filesystem::path dir(argv[1]);
        std::filesystem::create_directories(dir);
        using Clock = std::chrono::steady_clock;
        const auto t0 = Clock::now();
        auto since = [](Clock::time_point t) {
            return std::chrono::duration<double>(Clock::now() - t).count();
        };

        auto t = Clock::now();
        if (wanted.count("cloud")) {
            auto cloud = makeCloud();
            writeFile(dir / "cloud.vdb", {cloud}, since(t));
        }

        if (wanted.count("plume")) {
            t = Clock::now();
            auto plume = makePlume();
            writeFile(dir / "plume.vdb", openvdb::GridPtrVec(plume.begin(), plume.end()), since(t));
        }

        if (wanted.count("sparse")) {
            t = Clock::now();
            auto sparse = makeSparse();
            writeFile(dir / "sparse.vdb", {sparse}, since(t));
        }

        if (wanted.count("knot")) {
            t = Clock::now();
            const Mesh knot = makeKnot();
            checkKnot(knot);
            std::ostringstream gen;
            gen << "make_samples knot: (2,3) torus knot R=" << kKnotR << " r=" << kKnotr << ", tube radius "
                << kKnotTube << ", scale " << kKnotScale << ", " << kKnotSegments << "x" << kKnotSides
                << " rings";
            writeObj(dir / "scenes" / "knot.obj", knot, gen.str(), since(t));
        }

        std::printf("done in %.2f s\n", since(t0));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "make_samples: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
