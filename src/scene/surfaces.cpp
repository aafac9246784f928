#include "scene/surfaces.h"

#include <embree3/rtcore.h>

#include <mutex>

#include "core/error.h"

namespace vdbmarch {

// Embree reports errors through one device callback; they are collected and
// rethrown as exceptions at the next checkpoint.
struct SurfaceSet::Embree {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    RTCScene unitSphere = nullptr;
    std::mutex errorMutex;
    std::string error;
    std::vector<unsigned> geomToIndex;  // Embree geometry ID -> mGeometries index

    void check(const char* what) {
        std::lock_guard<std::mutex> lock(errorMutex);
        if (!error.empty()) {
            std::string e = error;
            error.clear();
            throw std::runtime_error(str("Embree error during ", what, ": ", e));
        }
    }
};

static void embreeErrorCallback(void* user, RTCError code, const char* message) {
    auto* e = static_cast<SurfaceSet::Embree*>(user);
    std::lock_guard<std::mutex> lock(e->errorMutex);
    e->error = str("code ", int(code), ": ", message ? message : "");
}

SurfaceSet::SurfaceSet() : mEmbree(std::make_unique<Embree>()) {
    mEmbree->device = rtcNewDevice("threads=0");
    if (!mEmbree->device) throw std::runtime_error(str("Embree: cannot create a device (error ", int(rtcGetDeviceError(nullptr)), ")"));
    rtcSetDeviceErrorFunction(mEmbree->device, embreeErrorCallback, mEmbree.get());
    mEmbree->scene = rtcNewScene(mEmbree->device);
    rtcSetSceneFlags(mEmbree->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(mEmbree->scene, RTC_BUILD_QUALITY_HIGH);
}

SurfaceSet::~SurfaceSet() {
    if (mEmbree->unitSphere) rtcReleaseScene(mEmbree->unitSphere);
    if (mEmbree->scene) rtcReleaseScene(mEmbree->scene);
    if (mEmbree->device) rtcReleaseDevice(mEmbree->device);
}

// Commits and attaches a geometry that becomes mGeometries[mGeometries.size()].
void SurfaceSet::attach(RTCGeometry g, const char* what) {
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(mEmbree->scene, g);
    rtcReleaseGeometry(g);
    mEmbree->check(what);
    if (mEmbree->geomToIndex.size() <= id) mEmbree->geomToIndex.resize(id + 1);
    mEmbree->geomToIndex[id] = unsigned(mGeometries.size());
}

void SurfaceSet::addMesh(TriangleMesh mesh, int surfaceIndex, bool smoothNormals) {
    std::vector<Vec3> normals;
    if (smoothNormals) {
        // Area-weighted: the unnormalised cross product carries twice the area.
        normals.assign(mesh.positions.size(), Vec3(0));
        for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
            const uint32_t* tri = &mesh.indices[t];
            Vec3 n = cross(mesh.positions[tri[1]] - mesh.positions[tri[0]], mesh.positions[tri[2]] - mesh.positions[tri[0]]);
            for (int k = 0; k < 3; ++k) normals[tri[k]] += n;
        }
        for (auto& n : normals) {
            float len = length(n);
            n = len > 0 ? n / len : Vec3(0);
        }
    }
    RTCGeometry g = rtcNewGeometry(mEmbree->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.positions.size()));
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        v[3 * i] = mesh.positions[i].x;
        v[3 * i + 1] = mesh.positions[i].y;
        v[3 * i + 2] = mesh.positions[i].z;
    }
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(unsigned), mesh.triangleCount()));
    std::copy(mesh.indices.begin(), mesh.indices.end(), idx);
    attach(g, "adding a mesh");
    mGeometries.push_back({surfaceIndex, false, std::move(mesh), Transform(), std::move(normals)});
}

void SurfaceSet::addSphere(const Transform& toWorld, int surfaceIndex) {
    if (!mEmbree->unitSphere) {
        mEmbree->unitSphere = rtcNewScene(mEmbree->device);
        RTCGeometry s = rtcNewGeometry(mEmbree->device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        auto* p = static_cast<float*>(
            rtcSetNewGeometryBuffer(s, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
        p[0] = p[1] = p[2] = 0;
        p[3] = 1;
        rtcCommitGeometry(s);
        rtcAttachGeometry(mEmbree->unitSphere, s);
        rtcReleaseGeometry(s);
        rtcCommitScene(mEmbree->unitSphere);
    }
    RTCGeometry inst = rtcNewGeometry(mEmbree->device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(inst, mEmbree->unitSphere);
    float xfm[12];  // 3x4 column-major
    const Mat4& m = toWorld.matrix();
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) xfm[c * 3 + r] = float(m.m[r][c]);
    rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
    attach(inst, "adding a sphere");
    mGeometries.push_back({surfaceIndex, true, TriangleMesh(), toWorld, {}});
}

void SurfaceSet::commit() {
    rtcCommitScene(mEmbree->scene);
    mEmbree->check("building the surface BVH");
    // Padded by far more than the slab test's rounding, so that no hit
    // Embree would find is culled (pixels stay bit-identical).
    mCullBounds = bounds();
    if (!mCullBounds.empty()) {
        const Vec3 pad = (mCullBounds.hi - mCullBounds.lo) * 1e-3f + max(mCullBounds.hi, -mCullBounds.lo) * 1e-5f +
                         Vec3(1e-6f);
        mCullBounds.lo -= pad;
        mCullBounds.hi += pad;
    }
}

size_t SurfaceSet::primitiveCount() const {
    size_t n = 0;
    for (const auto& g : mGeometries) n += g.sphere ? 1 : g.mesh.triangleCount();
    return n;
}

bool SurfaceSet::intersect(const Ray& r, float tMin, float tMax, SurfaceHit& hit) const {
    if (mGeometries.empty()) return false;
    // Most rays of a scene with a few surfaces (a floor, a glass ball) miss
    // them all: a slab test costs a fraction of Embree's call.
    float t0 = tMin, t1 = tMax;
    if (!mCullBounds.intersect(r, t0, t1)) return false;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = r.o.x; rh.ray.org_y = r.o.y; rh.ray.org_z = r.o.z;
    rh.ray.dir_x = r.d.x; rh.ray.dir_y = r.d.y; rh.ray.dir_z = r.d.z;
    rh.ray.tnear = tMin;
    rh.ray.tfar = std::min(tMax, 3.0e38f);
    rh.ray.mask = 0xFFFFFFFF;
    rh.ray.flags = 0;
    rh.ray.time = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(mEmbree->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    unsigned top = rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rh.hit.instID[0] : rh.hit.geomID;
    const Geometry& g = mGeometries[mEmbree->geomToIndex[top]];
    hit.t = rh.ray.tfar;
    hit.p = r.at(hit.t);
    hit.surface = g.surface;
    if (g.sphere) {
        // Exact normal: the object-space point is its own normal.
        Vec3 q = g.toWorld.inverse().point(hit.p);
        hit.n = normalize(g.toWorld.normal(q));
    } else {
        const uint32_t* tri = &g.mesh.indices[3 * size_t(rh.hit.primID)];
        const Vec3& a = g.mesh.positions[tri[0]];
        const Vec3& b = g.mesh.positions[tri[1]];
        const Vec3& c = g.mesh.positions[tri[2]];
        hit.n = normalize(cross(b - a, c - a));
        if (!g.vertexNormals.empty()) {
            float u = rh.hit.u, v = rh.hit.v;  // barycentrics of vertices 1 and 2
            Vec3 ns = g.vertexNormals[tri[0]] * (1 - u - v) + g.vertexNormals[tri[1]] * u + g.vertexNormals[tri[2]] * v;
            float len = length(ns);
            hit.ns = len > 0 ? ns / len : hit.n;
        }
    }
    if (!isFinite(hit.n)) hit.n = -r.d;  // degenerate triangle: treat as facing the ray
    if (g.vertexNormals.empty() || !isFinite(hit.ns)) hit.ns = hit.n;
    return true;
}

namespace {
// World bounds of a unit sphere placed by toWorld: its cube's eight corners.
BBox sphereBounds(const Transform& toWorld) {
    BBox b;
    for (int i = 0; i < 8; ++i) b.expand(toWorld.point(Vec3(i & 1 ? 1.f : -1.f, i & 2 ? 1.f : -1.f, i & 4 ? 1.f : -1.f)));
    return b;
}
}  // namespace

BBox SurfaceSet::bounds() const {
    BBox b;
    for (const Geometry& g : mGeometries) {
        if (g.sphere) {
            b.expand(sphereBounds(g.toWorld));
        } else {
            for (const Vec3& p : g.mesh.positions) b.expand(p);
        }
    }
    return b;
}

bool SurfaceSet::mayComeWithin(int surfaceIndex, const Vec3& c, float r) const {
    const float r2 = r * r;
    for (const Geometry& g : mGeometries) {
        if (g.surface != surfaceIndex) continue;
        if (g.sphere) {
            const BBox b = sphereBounds(g.toWorld);
            if (lengthSquared(c - min(max(c, b.lo), b.hi)) <= r2) return true;
            continue;
        }
        const std::vector<uint32_t>& idx = g.mesh.indices;
        for (size_t t = 0; t + 2 < idx.size(); t += 3) {
            const Vec3 q = closestPointOnTriangle(c, g.mesh.positions[idx[t]], g.mesh.positions[idx[t + 1]],
                                                  g.mesh.positions[idx[t + 2]]);
            if (lengthSquared(c - q) <= r2) return true;
        }
    }
    return false;
}

}  // namespace vdbmarch
