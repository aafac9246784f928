// Conditioning a grid as read into what the renderer samples: NaN, Inf and
// negative values zeroed (with one warning), inactive values and the
// background made 0, blackbody emission turned into Kelvin, and the grid's
// own linear transform composed with the scene's. Includes OpenVDB.
#include <cmath>
#include <functional>

#include <openvdb/openvdb.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_reduce.h>

#include "core/error.h"
#include "volume/vdb_conditioning.h"

namespace vdbmarch {

namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;

// One value's rule: inactive becomes 0; active NaN, Inf or negative becomes
// 0 and counts (returns true).
inline bool sanitizeValue(float& v, bool active) {
    if (!active) {
        if (v != 0) v = 0;
        return false;
    }
    if (std::isfinite(v) && v >= 0) return false;
    v = 0;
    return true;
}

}  // namespace

// Blackbody emission: active values become Kelvin, value x temperature_scale
// + temperature_offset (inactive space stays 0 K: nothing emits there). A
// negative temperature is refused, naming the value and the voxel.
void toKelvin(openvdb::FloatGrid& grid, const MediumDesc& d, const std::string& what) {
    // Beyond 1e9 K, sigma T^4 overflows a float: no flame is near it.
    constexpr double MaxKelvin = 1e9;
    for (auto it = grid.tree().beginValueOn(); it; ++it) {
        const float v = *it;
        if (!std::isfinite(v)) continue;  // sanitize() zeroes and counts these
        const double k = double(v) * d.temperatureScale + d.temperatureOffset;
        if (k < 0 || k > MaxKelvin)
            throw InputError(str(what, ": value ", v, " at voxel ", it.getCoord(), " is ", k,
                                 " K (emission.temperature_scale ", d.temperatureScale, ", temperature_offset ",
                                 d.temperatureOffset, "): ",
                                 k < 0 ? "a temperature in Kelvin cannot be negative"
                                       : "above 1e9 K the blackbody radiance overflows"));
        it.setValue(float(k));
    }
}

void sanitize(openvdb::FloatGrid& grid, const std::string& what) {
    // Leaves in parallel, then the tiles of the interior nodes (a tile counts
    // once, as one value).
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(grid.tree());
    size_t bad = tbb::parallel_reduce(
        leaves.leafRange(), size_t(0),
        [](const openvdb::tree::LeafManager<openvdb::FloatTree>::LeafRange& r, size_t count) {
            for (auto leaf = r.begin(); leaf; ++leaf) {
                float* v = leaf->buffer().data();
                const auto& on = leaf->getValueMask();
                for (openvdb::Index i = 0; i < LeafT::SIZE; ++i) count += sanitizeValue(v[i], on.isOn(i));
            }
            return count;
        },
        std::plus<size_t>());
    auto tiles = grid.tree().beginValueAll();
    tiles.setMaxDepth(openvdb::FloatTree::DEPTH - 2);
    for (; tiles; ++tiles) {
        float v = *tiles;
        const float before = v;
        bad += sanitizeValue(v, tiles.isValueOn());
        if (v != before) tiles.setValue(v);  // NaN != 0 too
    }
    float bg = grid.background();
    if (bg != 0) {
        if (std::isfinite(bg) && bg > 0)
            warn(str(what, ": background value ", bg, " ignored: space outside the active voxels is empty"));
        grid.tree().root().setBackground(0.f, /*updateChildNodes=*/true);
    }
    if (bad > 0) warn(str(what, ": ", bad, " NaN, Inf or negative value", bad == 1 ? "" : "s", " set to 0"));
}

// Index->world of the grid's own (linear) transform, followed by the scene's.
Mat4 indexToWorldMatrix(const openvdb::FloatGrid& grid, const Mat4& scene, const std::string& what) {
    const openvdb::math::Transform& xf = grid.transform();
    if (!xf.isLinear())
        throw InputError(str(what, ": the grid's transform (", xf.mapType(),
                             ") is not linear; only affine grid transforms are supported"));
    openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
    Mat4 m = Mat4::identity();
    for (int c = 0; c < 3; ++c) {
        openvdb::Vec3d e(0, 0, 0);
        e[c] = 1;
        openvdb::Vec3d col = xf.indexToWorld(e) - o;
        for (int r = 0; r < 3; ++r) m.m[r][c] = col[r];
    }
    for (int r = 0; r < 3; ++r) m.m[r][3] = o[r];
    return scene * m;
}

}  // namespace vdbmarch
