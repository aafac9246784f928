// Triangle meshes for the boundaries of participating media and for
// geometry: loading (OBJ via tinyobjloader, PLY via our own parser), and the
// few topological checks the scene needs before a mesh may enclose a medium.
#pragma once

#include "core/math.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace vdbmarch {

struct TriangleMesh {
    std::vector<Vec3> positions;
    // Three per triangle; counter-clockwise seen from outside = front.
    std::vector<uint32_t> indices;

    size_t triangleCount() const { return indices.size() / 3; }
};

// Loads a .obj or .ply file (extension checked case-insensitively). OBJ:
// all shapes merged, polygons fan-triangulated. PLY: ascii and binary
// (either endianness) 1.0; vertex x,y,z of any numeric type, faces from a
// `vertex_indices`/`vertex_index` list, fan-triangulated; everything else
// skipped. Triangles with repeated indices are dropped.
// Throws IoError when the file cannot be opened or read, InputError (naming
// the file) for any malformed content or a mesh without triangles.
TriangleMesh loadMesh(const std::string& path);

// Volume enclosed by the mesh via the divergence theorem; positive when the
// triangles wind counter-clockwise seen from outside. Only meaningful for
// closed meshes (an open mesh's value depends on the origin).
double signedVolume(const TriangleMesh& mesh);

// Reverses every triangle's winding.
void flipWinding(TriangleMesh& mesh);

// Flips all triangles when the signed volume is negative (inside-out file).
void orientOutward(TriangleMesh& mesh);

// True when, after welding vertices with identical positions, every
// undirected edge is shared by exactly two triangles. Triangles that collapse
// under welding are ignored. An empty mesh is not closed.
bool isClosed(const TriangleMesh& mesh);

// Unit cube centred at the origin: 8 vertices, 12 outward-facing triangles.
TriangleMesh makeUnitBox();

// Applies pointTransform to every vertex; when the transform mirrors space
// (a reference tetrahedron's signed volume changes sign), the winding is
// flipped so the front stays outward.
void transformMesh(TriangleMesh& mesh, const std::function<Vec3(const Vec3&)>& pointTransform);

}  // namespace vdbmarch
