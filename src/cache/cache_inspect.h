// `vdbmarch inspect`: a text summary of a baked cache and a false-colour
// slice through it.
#pragma once

#include <string>

#include "cache/radiance_cache.h"

namespace vdbmarch {

// Levels, cells per level, memory, metadata and the range of every coefficient.
std::string cacheSummary(const RadianceCache& cache);

// PNG of L_i on the plane `axis` (0, 1, 2 = x, y, z) = value, in the
// direction wo (or, when wo is zero, averaged over directions: f_00 Y_00),
// on a log scale over four decades below the slice's maximum; black where
// the cache has no cell. Returns the maximum, for the legend.
float writeCacheSlice(const RadianceCache& cache, int axis, float value, const Vec3& wo, const std::string& path);

}  // namespace vdbmarch
