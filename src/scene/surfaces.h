// Surfaces (glass, diffuse and medium interfaces) intersected with Embree 3.
// Meshes are stored in world space; spheres (ellipsoids after transform) are
// instances of one exact unit sphere.
#pragma once

#include <memory>
#include <vector>

#include "core/math.h"
#include "core/transform.h"
#include "parse/mesh.h"
#include "parse/scene_desc.h"

struct RTCGeometryTy;  // Embree's geometry handle, kept out of this header

namespace vdbmarch {

struct SurfaceHit {
    float t = Infinity;
    Vec3 p;
    Vec3 n;        // unit geometric normal, pointing outwards
    Vec3 ns;       // unit shading normal (interpolated vertex normals, or n)
    int surface = -1;
};

class SurfaceSet {
public:
    SurfaceSet();
    ~SurfaceSet();
    SurfaceSet(const SurfaceSet&) = delete;
    SurfaceSet& operator=(const SurfaceSet&) = delete;

    // smoothNormals: interpolate area-weighted vertex normals for shading.
    void addMesh(TriangleMesh worldMesh, int surfaceIndex, bool smoothNormals = false);
    void addSphere(const Transform& objectToWorld, int surfaceIndex);
    void commit();
    bool empty() const { return mGeometries.empty(); }
    // Closest hit with t in (tMin, tMax).
    bool intersect(const Ray& r, float tMin, float tMax, SurfaceHit& hit) const;
    // World bounds of every surface (empty box when there are none).
    BBox bounds() const;
    // Whether surface `surfaceIndex` may come within distance r of c: exact
    // for meshes (closest point on each triangle), by its bounding box for
    // spheres (so true errs on the safe side).
    bool mayComeWithin(int surfaceIndex, const Vec3& c, float r) const;
    // Number of triangles and spheres, for stats.
    size_t primitiveCount() const;

    struct Embree;  // Embree handles and the error callback's state

private:
    struct Geometry {
        int surface;
        bool sphere;
        TriangleMesh mesh;
        Transform toWorld;
        std::vector<Vec3> vertexNormals;  // empty: flat shading
    };
    void attach(::RTCGeometryTy* geometry, const char* what);
    std::unique_ptr<Embree> mEmbree;
    std::vector<Geometry> mGeometries;
    // bounds(), padded (commit()): a ray that misses it skips Embree.
    BBox mCullBounds;
};

}  // namespace vdbmarch
