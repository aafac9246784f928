// VDB density media: the medium made from its grids (read by vdb_io.cpp,
// conditioned by vdb_conditioning.cpp), trilinear sampling in index space,
// empty-space skipping and density bounds by a two-level 3D-DDA over an index
// of the dilated active topology's blocks, and emission sampling. One of the
// few files that include OpenVDB headers.
#include <algorithm>
#include <cmath>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>

#include "core/error.h"
#include "core/memory.h"
#include "core/transform.h"
#include "volume/medium.h"
#include "volume/padded_blocks.h"
#include "volume/vdb_conditioning.h"
#include "volume/vdb_io.h"
#include "volume/vdb_read_guard.h"

namespace vdbmarch {

namespace {

using FloatTree = openvdb::FloatTree;
using LeafT = FloatTree::LeafNodeType;
using BoolTree = openvdb::BoolTree;

struct Affine {  // 3x4, double: index coordinates of large grids need it
    double m[3][4];
    explicit Affine(const Mat4& a) {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) m[r][c] = a.m[r][c];
    }
    openvdb::Vec3d point(const Vec3& p) const {
        return {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
                m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
                m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
    }
    openvdb::Vec3d vector(const Vec3& v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
};

// Trilinear interpolation between voxel centres (integer index coordinates).
// Fast path: all eight corners in one leaf, read straight from its buffer.
inline float sampleTrilinear(openvdb::FloatGrid::ConstAccessor& acc, const openvdb::Vec3d& p) {
    const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
    const int ix = int(fx), iy = int(fy), iz = int(fz);
    const float tx = float(p.x() - fx), ty = float(p.y() - fy), tz = float(p.z() - fz);
    const openvdb::Coord c(ix, iy, iz);
    float v[8];
    const LeafT* leaf = acc.probeConstLeaf(c);
    if (leaf && (ix & 7) != 7 && (iy & 7) != 7 && (iz & 7) != 7) {
        const float* d = leaf->buffer().data();
        const openvdb::Index o = LeafT::coordToOffset(c);
        v[0] = d[o];       v[1] = d[o + 1];       v[2] = d[o + 8];       v[3] = d[o + 9];
        v[4] = d[o + 64];  v[5] = d[o + 65];      v[6] = d[o + 72];      v[7] = d[o + 73];
    } else if (!leaf && !acc.isValueOn(c) && (ix & 7) != 7 && (iy & 7) != 7 && (iz & 7) != 7) {
        // Inside an inactive tile (value 0) that also covers the +1 neighbours.
        return 0.f;
    } else {
        v[0] = acc.getValue(c);
        v[1] = acc.getValue(c.offsetBy(0, 0, 1));
        v[2] = acc.getValue(c.offsetBy(0, 1, 0));
        v[3] = acc.getValue(c.offsetBy(0, 1, 1));
        v[4] = acc.getValue(c.offsetBy(1, 0, 0));
        v[5] = acc.getValue(c.offsetBy(1, 0, 1));
        v[6] = acc.getValue(c.offsetBy(1, 1, 0));
        v[7] = acc.getValue(c.offsetBy(1, 1, 1));
    }
    // v index bits: x*4 + y*2 + z
    float a00 = v[0] + (v[1] - v[0]) * tz, a01 = v[2] + (v[3] - v[2]) * tz;
    float a10 = v[4] + (v[5] - v[4]) * tz, a11 = v[6] + (v[7] - v[6]) * tz;
    float b0 = a00 + (a01 - a00) * ty, b1 = a10 + (a11 - a10) * ty;
    return b0 + (b1 - b0) * tx;
}

class VdbMedium;

class VdbQuery final : public MediumQuery {
public:
    explicit VdbQuery(const VdbMedium& m);
    float density(const Vec3& p) override;
    float emission(const Vec3& p) override;
    void activeIntervals(const Ray& r, float tMin, float tMax, std::vector<Interval>& out) override;
    void forEachDensityBound(const Ray& r, float tMin, float tMax,
                         const std::function<bool(const DensityBound&)>& visit) override;

private:
    // Calls visit(t0, t1, block) for each block's tight box along the ray,
    // in increasing t, until visit returns false.
    template <typename Visit>
    void walkBlocks(const Ray& r, float tMin, float tMax, Visit&& visit);

    const VdbMedium& mMedium;
    std::unique_ptr<openvdb::FloatGrid::ConstAccessor> mEmission;
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> mBlockIndex;
    const float* mBlock = nullptr;            // cached block for mBlockOrigin
    openvdb::Coord mBlockOrigin{INT32_MIN, 0, 0};
};

class VdbMedium final : public Medium {
public:
    explicit VdbMedium(const MediumDesc& d) : mW2I(Mat4::identity()), mEmissionW2I(Mat4::identity()) {
        name = d.name;
        sigma_a = d.sigma_a;
        sigma_s = d.sigma_s;
        g = d.g;
        const std::string what = str(d.file, ": grid '", d.grid, "'");
        // Guards the read and everything that walks or frees what it built:
        // heap damage from a bad file shows there, when glibc checks a free.
        const auto guard = guardVdbRead(d.file);
        const MediumMemory need = predictMediumMemory(d);
        if (need.loading > 0)
            checkMemory(residentMemoryBytes() + need.loading,
                        str(what, " (", formatBytes(need.gridBytes), " in memory; loading it with what this process "
                                  "holds, docs/memory.md)"));
        mDensity = readFloatGrid(d.file, d.grid);
        sanitize(*mDensity, what);
        mScale = d.densityScale;
        Mat4 i2w = indexToWorldMatrix(*mDensity, d.transform, what);
        mW2I = Affine(i2w.inverse(what.c_str()));
        mI2W = i2w;
        // World-space length of each index axis; the step default uses the smallest.
        mMinVoxel = Infinity;
        for (int c = 0; c < 3; ++c) {
            double len = std::sqrt(i2w.m[0][c] * i2w.m[0][c] + i2w.m[1][c] * i2w.m[1][c] + i2w.m[2][c] * i2w.m[2][c]);
            mMinVoxel = std::min(mMinVoxel, float(len));
        }
        mActiveVoxels = mDensity->activeVoxelCount();
        // The padded blocks answer every density lookup: the grid's leaves
        // are freed while they are built, and the grid is dropped. Their
        // largest value is the grid's (inactive values are 0).
        if (mActiveVoxels > 0) {
            mBlocks.build(*mDensity);
            const openvdb::CoordBBox& ib = mBlocks.activeBounds;
            mIndexLo = openvdb::Vec3d(ib.min().x(), ib.min().y(), ib.min().z());
            mIndexHi = openvdb::Vec3d(ib.max().x() + 1, ib.max().y() + 1, ib.max().z() + 1);
        }
        float hi = 0;
        for (float m : mBlocks.blockMax) hi = std::max(hi, m);
        mMaxDensity = hi * mScale;
        if (mActiveVoxels == 0 || mMaxDensity <= 0) {
            warn(str(what, " has no active voxels with density > 0: the medium is empty"));
            mMaxDensity = 0;
        }
        mDensity.reset();
        if (mMaxDensity > 0)
            for (int i = 0; i < 8; ++i) {
                Vec3 corner(float(i & 1 ? mIndexHi.x() : mIndexLo.x()), float(i & 2 ? mIndexHi.y() : mIndexLo.y()),
                            float(i & 4 ? mIndexHi.z() : mIndexLo.z()));
                mWorldBounds.expand(i2w.point(corner));
            }
        if (d.hasEmission) {
            const std::string ewhat = str(d.file, ": emission grid '", d.emissionGrid, "'");
            mEmissionGrid = readFloatGrid(d.file, d.emissionGrid);
            if (d.blackbody) toKelvin(*mEmissionGrid, d, ewhat);
            sanitize(*mEmissionGrid, ewhat);
            mEmissionI2W = indexToWorldMatrix(*mEmissionGrid, d.transform, ewhat);
            mEmissionW2I = Affine(mEmissionI2W.inverse(ewhat.c_str()));
            hasEmission = d.emissionScale > 0 && !isBlack(d.emissionColor) && !isBlack(d.sigma_a);
            blackbody = d.blackbody;
            // Blackbody: the grid holds Kelvin and the intensity goes into the colour.
            mEmissionScale = blackbody ? 1.f : d.emissionScale;
            emissionColor = blackbody ? d.emissionColor * d.emissionScale : d.emissionColor;
        }
    }

    std::unique_ptr<MediumQuery> makeQuery() const override { return std::make_unique<VdbQuery>(*this); }
    BBox worldBounds() const override { return mWorldBounds; }
    float minVoxelSize() const override { return mMinVoxel; }
    float maxDensity() const override { return mMaxDensity; }
    size_t activeVoxelCount() const override { return mActiveVoxels; }
    uint64_t memoryBytes() const override {
        return mBlocks.memoryBytes() + (mEmissionGrid ? uint64_t(mEmissionGrid->memUsage()) : 0);
    }
    void activeBoxes(std::vector<BBox>& out) const override;
    std::unique_ptr<EmissionSampler> makeEmissionSampler() const override;

private:
    friend class VdbQuery;
    friend class VdbEmissionSampler;
    Mat4 mI2W = Mat4::identity(), mEmissionI2W = Mat4::identity();
    openvdb::FloatGrid::Ptr mDensity;  // only while loading
    openvdb::FloatGrid::Ptr mEmissionGrid;
    PaddedBlocks mBlocks;
    Affine mW2I, mEmissionW2I;
    openvdb::Vec3d mIndexLo{0, 0, 0}, mIndexHi{0, 0, 0};
    BBox mWorldBounds;
    float mScale = 1, mEmissionScale = 0, mMinVoxel = 0, mMaxDensity = 0;
    size_t mActiveVoxels = 0;
};

// World AABB of an index-space box [lo, hi] under an affine index-to-world map.
BBox worldBoxOf(const Mat4& i2w, const openvdb::Vec3d& lo, const openvdb::Vec3d& hi) {
    BBox b;
    for (int i = 0; i < 8; ++i) {
        b.expand(i2w.point(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z()));
    }
    return b;
}

void VdbMedium::activeBoxes(std::vector<BBox>& out) const {
    if (mMaxDensity <= 0) return;
    for (auto it = mBlocks.index.cbeginValueOn(); it; ++it) {
        int32_t id = *it;
        if (id <= 0 || !(mBlocks.blockMax[size_t(id - 1)] > 0)) continue;
        uint32_t tb = mBlocks.tightBox[size_t(id - 1)];
        openvdb::Coord o = it.getCoord();
        openvdb::Vec3d lo, hi;
        for (int a = 0; a < 3; ++a) {
            lo[a] = o[a] + double((tb >> (4 * a)) & 15u);
            hi[a] = o[a] + double((tb >> (12 + 4 * a)) & 15u);
        }
        if (hi.x() > lo.x() && hi.y() > lo.y() && hi.z() > lo.z()) out.push_back(worldBoxOf(mI2W, lo, hi));
    }
}

// Voxels of the emission grid, dilated by one (the trilinear stencil), each
// weighted by the largest emission value its interpolation can see (with
// blackbody emission the luminance at the largest temperature: it grows with
// T, so it is positive wherever L_e can be); a point is drawn uniformly
// inside the chosen voxel's [c, c+1)^3 index cell.
class VdbEmissionSampler final : public EmissionSampler {
public:
    explicit VdbEmissionSampler(const VdbMedium& m) : mI2W(m.mEmissionI2W) {
        const auto& grid = *m.mEmissionGrid;
        BoolTree topology(grid.tree(), false, openvdb::TopologyCopy());
        openvdb::tools::dilateActiveValues(topology, 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                           openvdb::tools::EXPAND_TILES);
        auto acc = grid.getConstAccessor();
        VdbQuery density(m);
        mVoxelVolume = float(std::fabs(mI2W.det3()));
        double total = 0, estimate = 0, colour[3] = {0, 0, 0};
        for (auto it = topology.cbeginValueOn(); it; ++it) {
            openvdb::Coord c = it.getCoord();
            // The cell [c, c+1) interpolates the values at c + {0,1}^3.
            float w = 0;
            for (int i = 0; i < 8; ++i)
                w = std::max(w, acc.getValue(c.offsetBy(i & 1, (i >> 1) & 1, (i >> 2) & 1)));
            if (m.blackbody) w = blackbodyLuminance(w);
            if (!(w > 0)) continue;
            total += w;
            mCoords.push_back(c);
            mCdf.push_back(total);
            // Density at the cell centre, for the power estimate only.
            openvdb::Vec3d centre(c.x() + 0.5, c.y() + 0.5, c.z() + 0.5);
            Vec3 wc = mI2W.point(centre.x(), centre.y(), centre.z());
            const float rho = density.density(wc);
            const float e = sampleTrilinear(acc, centre);
            estimate += double(rho) * e;
            if (m.blackbody) {
                const Color le = blackbodyRadiance(e);
                for (int k = 0; k < 3; ++k) colour[k] += double(rho) * le[k];
            }
        }
        for (double& v : mCdf) v /= total;
        mIntegral = float(estimate * mVoxelVolume * m.mEmissionScale);
        for (int k = 0; k < 3; ++k) mColourIntegral[k] = float(colour[k] * mVoxelVolume);
        for (size_t i = 0; i < mCdf.size(); ++i) mWeights.push_back(float((i ? mCdf[i] - mCdf[i - 1] : mCdf[i])));
    }

    bool empty() const { return mCoords.empty(); }

    void sample(const float u[4], Vec3& p, float& pdf) const override {
        size_t i = size_t(std::lower_bound(mCdf.begin(), mCdf.end(), double(u[0])) - mCdf.begin());
        i = std::min(i, mCdf.size() - 1);
        const openvdb::Coord& c = mCoords[i];
        p = mI2W.point(c.x() + double(u[1]), c.y() + double(u[2]), c.z() + double(u[3]));
        pdf = mWeights[i] / mVoxelVolume;
    }

    float integralEstimate() const override { return mIntegral; }
    Color blackbodyIntegral() const override { return mColourIntegral; }

private:
    Mat4 mI2W;
    Color mColourIntegral{0, 0, 0};
    std::vector<openvdb::Coord> mCoords;
    std::vector<double> mCdf;
    std::vector<float> mWeights;
    float mVoxelVolume = 1, mIntegral = 0;
};

std::unique_ptr<EmissionSampler> VdbMedium::makeEmissionSampler() const {
    if (!hasEmission || !mEmissionGrid || mMaxDensity <= 0) return nullptr;
    auto s = std::make_unique<VdbEmissionSampler>(*this);
    if (s->empty()) return nullptr;
    return s;
}

VdbQuery::VdbQuery(const VdbMedium& m)
    : mMedium(m), mBlockIndex(m.mBlocks.index) {
    if (m.mEmissionGrid) mEmission = std::make_unique<openvdb::FloatGrid::ConstAccessor>(m.mEmissionGrid->getConstAccessor());
}

// floor() without a libm call on baseline x86-64 (no SSE4.1 rounding).
inline int fastFloor(double x) {
    int i = int(x);
    return i - (x < double(i));
}

float VdbQuery::density(const Vec3& p) {
    const openvdb::Vec3d q = mMedium.mW2I.point(p);
    const int ix = fastFloor(q.x()), iy = fastFloor(q.y()), iz = fastFloor(q.z());
    const double fx = ix, fy = iy, fz = iz;
    const openvdb::Coord origin(ix & ~7, iy & ~7, iz & ~7);
    if (origin != mBlockOrigin) {
        mBlockOrigin = origin;
        int32_t id = mBlockIndex.getValue(origin);
        mBlock = id > 0 ? mMedium.mBlocks.block(id) : nullptr;
    }
    if (!mBlock) return 0.f;
    const float tx = float(q.x() - fx), ty = float(q.y() - fy), tz = float(q.z() - fz);
    constexpr int N = PaddedBlocks::N;
    const float* v = mBlock + ((ix & 7) * N + (iy & 7)) * N + (iz & 7);
    // corners: +1 in z is +1, in y is +N, in x is +N*N
    float a00 = v[0] + (v[1] - v[0]) * tz, a01 = v[N] + (v[N + 1] - v[N]) * tz;
    float a10 = v[N * N] + (v[N * N + 1] - v[N * N]) * tz, a11 = v[N * N + N] + (v[N * N + N + 1] - v[N * N + N]) * tz;
    float b0 = a00 + (a01 - a00) * ty, b1 = a10 + (a11 - a10) * ty;
    return (b0 + (b1 - b0) * tx) * mMedium.mScale;
}

float VdbQuery::emission(const Vec3& p) {
    if (!mEmission) return 0;
    return sampleTrilinear(*mEmission, mMedium.mEmissionW2I.point(p)) * mMedium.mEmissionScale;
}

template <typename Visit>
void VdbQuery::walkBlocks(const Ray& r, float tMin, float tMax, Visit&& visit) {
    if (mMedium.mMaxDensity <= 0) return;
    // The index-space ray keeps the world parameter t: its direction is the
    // (unnormalised) image of the world direction.
    openvdb::Vec3d eye = mMedium.mW2I.point(r.o), dir = mMedium.mW2I.vector(r.d);
    double t0 = tMin, t1 = tMax;
    for (int a = 0; a < 3; ++a) {
        if (dir[a] == 0) {
            if (eye[a] < mMedium.mIndexLo[a] || eye[a] > mMedium.mIndexHi[a]) return;
            continue;
        }
        double inv = 1.0 / dir[a];
        double ta = (mMedium.mIndexLo[a] - eye[a]) * inv, tb = (mMedium.mIndexHi[a] - eye[a]) * inv;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 >= t1) return;
    }
    // Nudge exactly-zero components so the DDA's 1/dir stays finite.
    for (int a = 0; a < 3; ++a)
        if (dir[a] == 0) dir[a] = 1e-30;
    // Two nested 3D-DDAs (Amanatides & Woo) in index space: over the block
    // index's level-1 nodes (128 voxels a side), absent ones empty and skipped
    // whole, and within each present node over its 8^3 blocks, keeping only
    // the part of the ray inside each block's tight box of non-zero stencils.
    // Lazy: visit returning false ends the walk where it is (a collision,
    // a shadow ray ended by roulette), with nothing computed beyond.
    using IndexNode = openvdb::Int32Tree::RootNodeType::ChildNodeType::ChildNodeType;
    const openvdb::Vec3d inv(1.0 / dir.x(), 1.0 / dir.y(), 1.0 / dir.z());
    struct Dda {
        int cell[3], step[3];
        double tNext[3], tDelta[3];
        // The cell of `size` voxels holding the ray just after t (tEnd: the
        // walk's end, for the nudge), and the times of its faces ahead.
        void init(const openvdb::Vec3d& eye, const openvdb::Vec3d& dir, const openvdb::Vec3d& inv, double t,
                  double tEnd, int size) {
            const openvdb::Vec3d p = eye + dir * (t + 1e-9 * (tEnd - t));
            for (int a = 0; a < 3; ++a) {
                cell[a] = fastFloor(p[a]) & ~(size - 1);
                step[a] = dir[a] > 0 ? size : -size;
                const double boundary = dir[a] > 0 ? cell[a] + size : cell[a];
                tNext[a] = (boundary - eye[a]) * inv[a];
                tDelta[a] = size * std::fabs(inv[a]);
            }
        }
        int axis() const { return tNext[0] < tNext[1] ? (tNext[0] < tNext[2] ? 0 : 2) : (tNext[1] < tNext[2] ? 1 : 2); }
        // Time of leaving the current cell; steps to the next.
        double advance() {
            const int a = axis();
            const double t = tNext[a];
            cell[a] += step[a];
            tNext[a] += tDelta[a];
            return t;
        }
    };
    Dda outer, inner;
    outer.init(eye, dir, inv, t0, t1, int(IndexNode::DIM));
    double tNode = t0;
    while (tNode < t1) {
        const double nodeExit = std::min(outer.tNext[outer.axis()], t1);
        if (const IndexNode* node =
                mBlockIndex.probeConstNode<IndexNode>(openvdb::Coord(outer.cell[0], outer.cell[1], outer.cell[2]))) {
            // Every entry of an index node is a tile (padded_blocks.h): its
            // value is read from the node's table, with no tree descent.
            const auto* table = node->getTable();
            inner.init(eye, dir, inv, tNode, nodeExit, 8);
            double tCur = tNode;
            while (tCur < nodeExit) {
                const double tExit = std::min(inner.tNext[inner.axis()], nodeExit);
                const openvdb::Index n = IndexNode::coordToOffset(openvdb::Coord(inner.cell[0], inner.cell[1], inner.cell[2]));
                const int32_t id = table[n].getValue();
                if (id > 0) {
                    const uint32_t box = mMedium.mBlocks.tightBox[size_t(id - 1)];
                    double a = tCur, b = tExit;
                    // A box of all 8^3 cells (most blocks inside a cloud) clips nothing.
                    constexpr uint32_t AllCells = 0x888000;
                    for (int ax = 0; ax < 3 && a < b && box != AllCells; ++ax) {
                        double lo = inner.cell[ax] + double((box >> (4 * ax)) & 15);
                        double hi = inner.cell[ax] + double((box >> (12 + 4 * ax)) & 15);
                        double ta = (lo - eye[ax]) * inv[ax], tb = (hi - eye[ax]) * inv[ax];
                        if (ta > tb) std::swap(ta, tb);
                        a = std::max(a, ta);
                        b = std::min(b, tb);
                    }
                    if (b > a && !visit(a, b, size_t(id - 1))) return;
                }
                tCur = inner.advance();
            }
        }
        tNode = outer.advance();
    }
}

void VdbQuery::activeIntervals(const Ray& r, float tMin, float tMax, std::vector<Interval>& out) {
    walkBlocks(r, tMin, tMax, [&](double a, double b, size_t) {
        float fa = float(a), fb = float(b);
        if (!(fb > fa)) return true;
        if (!out.empty() && fa <= out.back().t1) out.back().t1 = std::max(out.back().t1, fb);
        else out.push_back({fa, fb});
        return true;
    });
}

void VdbQuery::forEachDensityBound(const Ray& r, float tMin, float tMax,
                               const std::function<bool(const DensityBound&)>& visit) {
    const auto& maxima = mMedium.mBlocks.blockMax;
    const auto& minima = mMedium.mBlocks.blockMin;
    const float scale = mMedium.mScale;
    // Adjacent blocks with the same bounds are merged before visiting.
    DensityBound pending{0, 0, -1};
    bool stopped = false;
    walkBlocks(r, tMin, tMax, [&](double a, double b, size_t block) {
        float fa = float(a), fb = float(b), m = maxima[block] * scale, lo = minima[block] * scale;
        if (!(fb > fa)) return true;
        if (pending.maxDensity == m && pending.minDensity == lo && fa <= pending.t1) {
            pending.t1 = std::max(pending.t1, fb);
            return true;
        }
        if (pending.maxDensity >= 0 && !visit(pending)) {
            stopped = true;
            return false;
        }
        pending = {fa, fb, m, lo};
        return true;
    });
    if (!stopped && pending.maxDensity >= 0) visit(pending);
}

}  // namespace

std::unique_ptr<Medium> loadVdbMedium(const MediumDesc& desc) { return std::make_unique<VdbMedium>(desc); }

}  // namespace vdbmarch
