#include "core/triangle_mesh.h"

#include <cmath>
#include <unordered_map>

#include "core/hash.h"

namespace vdbmarch {

namespace {

// Identical positions weld; -0 and +0 compare equal, so hash them alike.
struct PositionHash {
    size_t operator()(const Vec3& p) const {
        Fnv1a h;
        for (int a = 0; a < 3; ++a) h.addValue(p[a] + 0.f);  // -0 + 0 = +0
        return size_t(h.value);
    }
};

}  // namespace

double signedVolume(const TriangleMesh& mesh) {
    // Relative to the bounding-box centre: the same value for a closed mesh,
    // but far less cancellation when the mesh sits far from the origin.
    BBox box;
    for (const Vec3& p : mesh.positions) box.expand(p);
    if (box.empty()) return 0;
    const Vec3 c = box.center();
    double sum = 0;
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const Vec3& p0 = mesh.positions[mesh.indices[t]];
        const Vec3& p1 = mesh.positions[mesh.indices[t + 1]];
        const Vec3& p2 = mesh.positions[mesh.indices[t + 2]];
        double ax = double(p0.x) - c.x, ay = double(p0.y) - c.y, az = double(p0.z) - c.z;
        double bx = double(p1.x) - c.x, by = double(p1.y) - c.y, bz = double(p1.z) - c.z;
        double cx = double(p2.x) - c.x, cy = double(p2.y) - c.y, cz = double(p2.z) - c.z;
        sum += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
    }
    return sum / 6.0;
}

void flipWinding(TriangleMesh& mesh) {
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
}

void orientOutward(TriangleMesh& mesh) {
    if (signedVolume(mesh) < 0) flipWinding(mesh);
}

bool isClosed(const TriangleMesh& mesh) {
    if (mesh.triangleCount() == 0) return false;
    std::unordered_map<Vec3, uint32_t, PositionHash> weldIds;
    weldIds.reserve(mesh.positions.size());
    std::vector<uint32_t> weld(mesh.positions.size());
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        weld[i] = weldIds.emplace(mesh.positions[i], uint32_t(weldIds.size())).first->second;
    }
    std::unordered_map<uint64_t, uint32_t> edgeUses;
    edgeUses.reserve(mesh.indices.size());
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        uint32_t v[3] = {weld[mesh.indices[t]], weld[mesh.indices[t + 1]], weld[mesh.indices[t + 2]]};
        // Collapsed by welding: zero area, bounds nothing.
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
        for (int k = 0; k < 3; ++k) {
            uint32_t a = v[k], b = v[(k + 1) % 3];
            if (a > b) std::swap(a, b);
            ++edgeUses[(uint64_t(a) << 32) | b];
        }
    }
    if (edgeUses.empty()) return false;
    for (const auto& [edge, uses] : edgeUses) {
        if (uses != 2) return false;
    }
    return true;
}

TriangleMesh makeUnitBox() {
    TriangleMesh mesh;
    // Vertex i has x from bit 0, y from bit 1, z from bit 2.
    for (int i = 0; i < 8; ++i) {
        mesh.positions.emplace_back((i & 1) ? 0.5f : -0.5f, (i & 2) ? 0.5f : -0.5f, (i & 4) ? 0.5f : -0.5f);
    }
    // One quad per face, counter-clockwise seen from outside.
    const uint32_t quads[6][4] = {
        {0, 4, 6, 2}, {1, 3, 7, 5},  // -x, +x
        {0, 1, 5, 4}, {2, 6, 7, 3},  // -y, +y
        {0, 2, 3, 1}, {4, 5, 7, 6},  // -z, +z
    };
    for (const auto& q : quads) mesh.indices.insert(mesh.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    return mesh;
}

void transformMesh(TriangleMesh& mesh, const std::function<Vec3(const Vec3&)>& pointTransform) {
    // Mirroring is judged on a reference tetrahedron (a closed mesh) sized to
    // the mesh, not on the mesh's own signed volume: for an open mesh that
    // volume depends on the origin, so a mere translation could flip its sign.
    BBox box;
    for (const Vec3& p : mesh.positions) box.expand(p);
    Vec3 c = box.empty() ? Vec3(0.f) : box.center();
    float s = box.empty() ? 1.f : maxComponent(box.extent());
    if (!(s > 0) || !std::isfinite(s)) s = 1.f;
    const Vec3 o = pointTransform(c);
    const Vec3 ex = pointTransform(c + Vec3(s, 0, 0)) - o;
    const Vec3 ey = pointTransform(c + Vec3(0, s, 0)) - o;
    const Vec3 ez = pointTransform(c + Vec3(0, 0, s)) - o;
    const double det = double(ex.x) * (double(ey.y) * ez.z - double(ey.z) * ez.y) -
                       double(ex.y) * (double(ey.x) * ez.z - double(ey.z) * ez.x) +
                       double(ex.z) * (double(ey.x) * ez.y - double(ey.y) * ez.x);

    for (Vec3& p : mesh.positions) p = pointTransform(p);
    if (det < 0) flipWinding(mesh);
}

Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const float d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3 bp = p - b;
    const float d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const float d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const float denom = va + vb + vc;
    if (!(denom > 0)) return a;  // degenerate: its vertices are what is left
    return a + ab * (vb / denom) + ac * (vc / denom);
}

}  // namespace vdbmarch
