// A VDB grid's isosurface as a closed triangle mesh (OpenVDB's volume-to-mesh),
// so a fog volume or level set becomes a glass object.
#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

#include "core/error.h"
#include "parse/mesh.h"
#include "volume/vdb_io.h"
#include "volume/vdb_mesh.h"

namespace vdbmarch {

TriangleMesh meshVdbIsosurface(const std::string& file, const std::string& grid, float isovalue) {
    auto floatGrid = readFloatGrid(file, grid);
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*floatGrid, points, triangles, quads, double(isovalue), 0.0);
    TriangleMesh mesh;
    mesh.positions.reserve(points.size());
    for (const auto& p : points) mesh.positions.push_back(Vec3(p.x(), p.y(), p.z()));
    for (const auto& t : triangles) mesh.indices.insert(mesh.indices.end(), {t[0], t[1], t[2]});
    for (const auto& q : quads) mesh.indices.insert(mesh.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    if (mesh.indices.empty())
        throw InputError(str(file, ": grid '", grid, "' has no isosurface at isovalue ", isovalue,
                             " (values never cross it)"));
    // volumeToMesh's winding depends on whether the grid is a level set or a
    // fog volume; orient by the signed volume so normals point outwards.
    orientOutward(mesh);
    return mesh;
}

}  // namespace vdbmarch
