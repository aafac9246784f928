// Internal to src/volume: conditioning a grid as read (vdb_conditioning.cpp).
// Includes OpenVDB; never include it outside volume/.
#pragma once

#include <string>

#include <openvdb/openvdb.h>

#include "core/transform.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

// NaN, Inf and negative values become 0 (counted, one warning naming
// `what`); inactive values and the background become 0 so that "inactive"
// means "empty".
void sanitize(openvdb::FloatGrid& grid, const std::string& what);

// Blackbody emission: active values become Kelvin, value x temperature_scale
// + temperature_offset (inactive space stays 0 K: nothing emits there). A
// negative temperature, or one above 1e9 K, is refused naming the value and
// the voxel.
void toKelvin(openvdb::FloatGrid& grid, const MediumDesc& d, const std::string& what);

// Index->world of the grid's own (linear) transform, followed by the
// scene's; a non-linear grid transform is refused.
Mat4 indexToWorldMatrix(const openvdb::FloatGrid& grid, const Mat4& scene, const std::string& what);

}  // namespace vdbmarch
