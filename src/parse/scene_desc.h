// The scene as the user described it: plain data parsed from JSON (or built
// for a bare .vdb), before any file is loaded. Loading happens in scene.cpp.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/math.h"
#include "core/transform.h"
#include "parse/method.h"

namespace vdbmarch {

struct CameraDesc {
    enum class Type { Perspective, Orthographic } type = Type::Perspective;
    Vec3 position{0, 0, 5}, lookAt{0, 0, 0}, up{0, 1, 0};
    float fovDeg = 40;      // vertical, perspective
    float widthWorld = 2;   // frame width, orthographic
    int width = 640, height = 480;
};

struct LightDesc {
    enum class Type { Point, Spot, Directional, CollimatedQuad, Sphere } type = Type::Point;
    Vec3 position, direction{0, -1, 0}, center, u{1, 0, 0}, v{0, 0, 1};
    Color intensity, irradiance, power;
    float coneDeg = 30, falloffDeg = 5, radius = 1;
};

struct MediumDesc {
    enum class Type { Homogeneous, Vdb } type = Type::Homogeneous;
    std::string name;
    Color sigma_a, sigma_s;
    float g = 0;
    bool hasBounds = false;
    BBox bounds;
    // VDB only
    std::string file, grid = "density";
    float densityScale = 1;
    bool hasEmission = false;
    std::string emissionGrid = "temperature";
    float emissionScale = 1;  // scale, or intensity with blackbody
    Color emissionColor{1, 1, 1};
    // Blackbody mode: the grid maps to Kelvin as value x temperatureScale +
    // temperatureOffset (active voxels only) and L_e = emissionScale x
    // emissionColor x blackbodyRadiance(T) (core/blackbody.h).
    bool blackbody = false;
    float temperatureScale = 1, temperatureOffset = 0;
    Mat4 transform = Mat4::identity();
};

struct MaterialDesc {
    enum class Type { Dielectric, Diffuse, Interface } type = Type::Dielectric;
    float ior = 1.5f;
    Color albedo{0.5f, 0.5f, 0.5f};
};

struct SurfaceDesc {
    enum class Shape { Sphere, Box, Mesh, VdbIsosurface } shape = Shape::Sphere;
    std::string file, grid = "density";
    float isovalue = 0.5f;
    Mat4 transform = Mat4::identity();
    MaterialDesc material;
    std::string interior, exterior;  // empty: vacuum inside / world media outside
    bool smoothNormals = false;      // default true for vdb_isosurface
};

// Extra EXR layers a render may write (render.aovs; docs/aovs.md).
struct AovSet {
    bool depth = false, albedo = false, normal = false, direct = false, indirect = false;
    bool any() const { return firstEvent() || splitDirect(); }
    // Layers of the first event along the camera ray (a feature pass of its own).
    bool firstEvent() const { return depth || albedo || normal; }
    // Layers that split the beauty by scattering order.
    bool splitDirect() const { return direct || indirect; }
};

// The names render.aovs accepts, in documentation order.
const std::vector<std::string>& aovNames();

// How free flights in media find point, spot and sphere lights (Cycles'
// "volume sampling"): by transmittance alone (delta tracking), by distance
// sampling towards each light (equiangular) alone, or by both weighed by
// multiple importance sampling (strategies/light_distances.h).
enum class VolumeSampling { Distance, Equiangular, Mis };

struct RenderSettings {
    Method method = Method::Uniform;
    // render.method = "auto" (the default): `method` is chosen from what the
    // scene contains (parse/auto_method.h), `methodReason` says why.
    bool methodAuto = true;
    std::string methodReason;
    int spp = 1;
    float step = 0;        // world units; 0 = automatic
    float shadowStep = 0;  // 0 = same as step
    int maxDepth = 1;
    uint64_t seed = 0;
    int threads = 0;       // 0 = all cores
    int maxSurfaceBounces = 32;
    bool pixelJitter = true;  // false: one ray through each pixel centre
    float exposure = 0;       // PNG preview, stops
    // How the marchers estimate L_i at their samples.
    LiSource li = LiSource::Path;
    int raySamples = 4;  // transmittance and guided: L_i samples per ray segment (mean for guided)
    AovSet aovs;  // none by default: the EXR holds RGBA only
    // Noise target (render --noise): > 0 stops the render once the
    // estimated RMSE over the image's mean is below it, sampling only the
    // blocks of pixels still above it (adaptive sampling, docs/noise.md).
    float noise = 0;
    // The denoiser (docs/denoise.md): Preview denoises the PNG only; On also
    // the EXR's RGBA (the noisy beauty kept as a layer).
    enum class Denoise { Off, Preview, On } denoise = Denoise::Preview;
};

// Switches of default-on sampling strategies, for A/B measurements rather
// than shots (scene key "experiments"; docs/scene-format.md).
struct ExperimentSettings {
    VolumeSampling volumeSampling = VolumeSampling::Mis;
    // Path vertices connect to sphere lights through glass spheres
    // (strategies/sphere_caustics.h), weighed by MIS against the path's hits.
    bool sphereCaustics = true;
    // Medium vertices draw a share of their directions towards spot and
    // collimated beams (strategies/beam_directions.h).
    bool beamDirections = true;
    // Camera paths follow both outcomes of their first glass event, and
    // every other glass event counts the light its reflection sees
    // (strategies/glass_splitting.h).
    bool glassSplitting = true;
    // Sphere lights' caustics through refracting glass other than the glass
    // spheres that sphere_caustics connects come from caustic photons where
    // a method gathers them; paths leave them out past the vertex that
    // gathered them (Scene::sphereLightCausticPhotons).
    bool causticPhotons = true;
    // Adaptive sampling in timed renders (render --time): blocks of pixels
    // whose share of the time left is spent stop receiving samples
    // (docs/noise.md, "Timed renders").
    bool adaptive = true;
};

// The volume photon map (scene key "photons").
struct PhotonSettings {
    int64_t count = 100000;  // photon paths traced
    int k = 50;              // photons per radiance estimate (eq. 4)
    int64_t seed = -1;       // photon tracing's seed; -1: render.seed
    // Progressive passes (Knaus & Zwicker 2011; docs/method.md): every
    // sppPerPass camera samples trace a fresh batch of `count` paths and the
    // gather radius shrinks by alpha's rule, so the photon part of L_i
    // converges; the cache averages batches 1, 2, 4, 8, ...
    bool progressive = true;
    int sppPerPass = 0;      // 0: automatic, ceil(count / (4 pixels))
    float alpha = 4.f / 7;   // radius rule r_{i+1}^3 = r_i^3 (i + alpha) / (i + 1); 4/7 balances bias and variance in 3D
    uint64_t seedFor(uint64_t renderSeed) const { return seed >= 0 ? uint64_t(seed) : renderSeed; }
};

// The radiance cache (scene key "cache"; sections 3.1-3.4).
struct CacheSettings {
    int shOrder = 3;        // K: (K + 1)^2 coefficients; 0 is the paper's scalar cache
    float quality = 1;      // the paper's a
    bool adaptive = false;  // octree-like subdivision where photons are dense
    float minCell = 0;      // smallest adaptive cell, world units (0: automatic)
};

// An environment map (scene key "environment"): a lat-long EXR of the
// radiance arriving from each direction (docs/scene-format.md has the
// orientation convention).
struct EnvironmentDesc {
    std::string file;        // empty: no map (the constant background applies)
    float scale = 1;         // multiplies the texels
    float rotationDeg = 0;   // turns the map about +Y (counter-clockwise seen from above)
};

struct SceneDesc {
    std::string file;     // scene file (or .vdb) the description came from
    std::string baseDir;  // relative paths resolve against this
    CameraDesc camera;
    std::vector<LightDesc> lights;
    std::vector<MediumDesc> media;
    std::vector<SurfaceDesc> surfaces;
    Color background{0, 0, 0};
    EnvironmentDesc environment;
    RenderSettings render;
    PhotonSettings photons;
    CacheSettings cache;
    ExperimentSettings experiments;
    std::string jsonText;  // the effective document (compact JSON), recorded in outputs
    // The frame the scene was loaded for (--frames): its file paths have the
    // frame token replaced (parse/frames.h); none for a single render.
    std::optional<int> frame;
};

// Parses scene JSON text; `file` is used in messages and to resolve paths.
// Throws InputError with file, line and column for malformed JSON, and with
// the key path and bad value for semantic errors. With a `frame`, the frame
// token (a run of '#') in every file path of the scene becomes that frame
// number (parse/frames.h), in the description and in its jsonText; without
// one, a path holding the token is an error that asks for --frames.
SceneDesc parseSceneText(const std::string& text, const std::string& file,
                         const std::vector<std::string>& overrides = {}, std::optional<int> frame = std::nullopt);
// Reads and parses a scene file.
SceneDesc loadSceneFile(const std::string& path, const std::vector<std::string>& overrides = {},
                        std::optional<int> frame = std::nullopt);

// The key paths and values of the scene's file paths, resolved against its
// folder: media[i].file (vdb), surfaces[i].file (mesh, vdb_isosurface) and
// environment.file.
std::vector<std::pair<std::string, std::string>> sceneFilePaths(const SceneDesc& desc);

// Hash of everything in the scene that changes the light field (media,
// lights, surfaces, background, max_depth) but not the camera or render
// settings: a cache baked for one scene is refused for another.
std::string sceneHash(const SceneDesc& desc);

std::string resolvePath(const std::string& baseDir, const std::string& path);

}  // namespace vdbmarch
