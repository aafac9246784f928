#pragma once

#include <memory>
#include <string>

#include "parse/mesh.h"

namespace vdbmarch {

// Isosurface of a scalar VDB grid in world space (the grid's own transform),
// oriented outwards. Throws InputError naming the file and grid.
TriangleMesh meshVdbIsosurface(const std::string& file, const std::string& grid, float isovalue);

}  // namespace vdbmarch
