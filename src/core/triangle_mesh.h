// Triangle meshes for the boundaries of participating media and for
// geometry, and the few topological checks the scene needs before a mesh may
// enclose a medium (files: parse/mesh.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/math.h"

namespace vdbmarch {

struct TriangleMesh {
    std::vector<Vec3> positions;
    // Three per triangle; counter-clockwise seen from outside = front.
    std::vector<uint32_t> indices;

    size_t triangleCount() const { return indices.size() / 3; }
};

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

// The point of triangle (a, b, c) closest to p (Ericson 2005, "Real-Time
// Collision Detection", 5.1.5: by the Voronoi region of p).
Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Unit cube centred at the origin: 8 vertices, 12 outward-facing triangles.
TriangleMesh makeUnitBox();

// Applies pointTransform to every vertex; when the transform mirrors space
// (a reference tetrahedron's signed volume changes sign), the winding is
// flipped so the front stays outward.
void transformMesh(TriangleMesh& mesh, const std::function<Vec3(const Vec3&)>& pointTransform);

}  // namespace vdbmarch
