// Triangle mesh files: OBJ via tinyobjloader, PLY via our own parser. The
// mesh and its topology live in core/triangle_mesh.h.
#pragma once

#include <string>

#include "core/triangle_mesh.h"

namespace vdbmarch {

// Loads a .obj or .ply file (extension checked case-insensitively). OBJ:
// all shapes merged, polygons fan-triangulated. PLY: ascii and binary
// (either endianness) 1.0; vertex x,y,z of any numeric type, faces from a
// `vertex_indices`/`vertex_index` list, fan-triangulated; everything else
// skipped. Triangles with repeated indices are dropped.
// Throws IoError when the file cannot be opened or read, InputError (naming
// the file) for any malformed content or a mesh without triangles.
TriangleMesh loadMesh(const std::string& path);

}  // namespace vdbmarch
