#include "scene/auto_scene.h"

#include <cmath>

#include "core/error.h"
#include "volume/medium.h"

namespace vdbmarch {

namespace {
nlohmann::json vec(const Vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }
}  // namespace

nlohmann::json autoSceneJson(const std::string& vdbPath) {
    VdbGridSummary s = summarizeVdb(vdbPath, "");
    using nlohmann::json;
    BBox b = s.worldBounds;
    if (b.empty()) {  // the medium itself warns that it is empty
        b.lo = Vec3(-1);
        b.hi = Vec3(1);
    }
    Vec3 c = b.center();
    const float fovDeg = 35, aspect = 640.f / 480.f;
    Vec3 viewDir = normalize(Vec3(0.45f, 0.22f, 1.f));  // from the asset towards the camera
    Vec3 forward = -viewDir, right = normalize(cross(forward, Vec3(0, 1, 0))), up = cross(right, forward);
    // Closest distance at which all eight bbox corners fall inside 90% of the frame.
    float tanH = std::tan(radians(fovDeg) * 0.5f) * 0.9f, tanW = tanH * aspect;
    float dist = 0;
    for (int i = 0; i < 8; ++i) {
        Vec3 p = Vec3(i & 1 ? b.hi.x : b.lo.x, i & 2 ? b.hi.y : b.lo.y, i & 4 ? b.hi.z : b.lo.z) - c;
        float depth = dot(p, forward);
        dist = std::max({dist, std::fabs(dot(p, right)) / tanW - depth, std::fabs(dot(p, up)) / tanH - depth});
    }
    dist = std::max(dist, 1e-3f * std::max(1.f, length(b.extent())));
    Vec3 camPos = c + viewDir * dist;

    // Extinction so that the mean-density optical depth across the typical
    // chord of the active region is ~6: dense enough to read as a cloud,
    // thin enough that light reaches inside. The chord is the cube root of
    // the active volume.
    double activeVolume = double(s.activeVoxels) * double(s.voxelSize) * s.voxelSize * s.voxelSize;
    double chord = std::max(std::cbrt(std::max(activeVolume, 1e-30)), double(s.voxelSize));
    double meanDensity = s.meanValue > 0 ? s.meanValue : (s.maxValue > 0 ? s.maxValue : 1.0);
    double sigmaT = 6.0 / (meanDensity * chord);
    const double albedo = 0.95;
    float sigmaS = float(sigmaT * albedo), sigmaA = float(sigmaT * (1 - albedo));

    json doc;
    doc["camera"] = {{"type", "perspective"}, {"position", vec(camPos)}, {"look_at", vec(c)},
                     {"up", json::array({0, 1, 0})}, {"fov_deg", fovDeg}, {"resolution", json::array({640, 480})}};
    // Sun from the upper left, slightly in front of the asset.
    doc["lights"] = json::array({{{"type", "directional"},
                                  {"direction", vec(normalize(Vec3(0.55f, -0.75f, -0.35f)))},
                                  {"irradiance", json::array({6.4, 6.0, 5.4})}}});
    doc["media"] = json::array({{{"name", "asset"},
                                 {"type", "vdb"},
                                 // relative to the scene's folder, which is the file's own
                                 {"file", vdbPath.substr(vdbPath.find_last_of('/') + 1)},
                                 {"grid", s.gridName},
                                 {"sigma_a", json::array({sigmaA, sigmaA, sigmaA})},
                                 {"sigma_s", json::array({sigmaS, sigmaS, sigmaS})},
                                 {"g", 0.2}}});
    doc["background"] = json::array({0.18, 0.26, 0.42});
    // Multiple scattering (a white cloud), the method chosen from the scene.
    doc["render"] = {{"method", "auto"}, {"spp", 48}, {"max_depth", 64}};
    return doc;
}

SceneDesc loadAutoScene(const std::string& vdbPath, const std::vector<std::string>& overrides,
                        std::optional<int> frame) {
    nlohmann::json doc = autoSceneJson(vdbPath);
    for (const auto& o : overrides) applyOverride(doc, o);
    return parseSceneJson(doc, vdbPath, frame);
}

}  // namespace vdbmarch
