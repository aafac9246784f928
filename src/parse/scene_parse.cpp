// Scene JSON -> SceneDesc. Reads fields only; files are loaded later.
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/hash.h"
#include "parse/scene_json.h"
#include "parse/auto_method.h"
#include "parse/frames.h"
#include "parse/json_locate.h"
#include "parse/json_reader.h"
#include "parse/scene_desc.h"
#include "parse/settings_parse.h"

namespace vdbmarch {

namespace {

// Offset of the start of the token that nlohmann's parser rejected (its
// `byte` is one past the last character it read).
size_t rejectedToken(const std::string& text, size_t byte) {
    size_t pos = std::min(byte > 0 ? byte - 1 : 0, text.empty() ? 0 : text.size() - 1);
    auto isWordChar = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '+' || c == '-'; };
    if (!text.empty() && text[pos] == '"') {
        // Back to the opening quote of a string token (skipping escaped quotes).
        size_t q = pos;
        while (q > 0) {
            --q;
            if (text[q] == '"' && (q == 0 || text[q - 1] != '\\')) break;
        }
        if (text[q] == '"') pos = q;
    } else if (!text.empty() && isWordChar(text[pos])) {
        while (pos > 0 && isWordChar(text[pos - 1])) --pos;
    }
    return pos;
}

Mat4 parseTransform(const JsonReader& r) {
    if (r.has("matrix")) {
        r.allowOnly({"matrix"});
        const Json& m = r.raw("matrix");
        if (!m.is_array() || m.size() != 16) r.fail("matrix", str("must be 16 numbers (row-major), got ", jsonExcerpt(m)));
        Mat4 out{};
        for (int i = 0; i < 16; ++i) {
            if (!m[i].is_number()) r.fail("matrix", str("element ", i, " is not a number: ", jsonExcerpt(m[i])));
            double v = m[i].get<double>();
            if (!std::isfinite(v)) r.fail("matrix", str("element ", i, " is not finite"));
            out.m[i / 4][i % 4] = v;
        }
        if (out.m[3][0] != 0 || out.m[3][1] != 0 || out.m[3][2] != 0 || out.m[3][3] != 1)
            r.fail("matrix", "must be affine: the last row must be 0 0 0 1");
        out.inverse(r.keyPath("matrix").c_str());  // throws when singular
        return out;
    }
    r.allowOnly({"translate", "rotate", "scale"});
    Mat4 s = Mat4::identity(), rot = Mat4::identity(), t = Mat4::identity();
    if (r.has("scale")) {
        const Json& v = r.raw("scale");
        Vec3 sc = v.is_number() ? Vec3(v.get<float>()) : r.vec3("scale");
        if (!std::isfinite(sc.x) || sc.x == 0 || sc.y == 0 || sc.z == 0)
            r.fail("scale", str("must be non-zero and finite, got ", jsonExcerpt(v)));
        s = Mat4::scale(sc);
    }
    if (r.has("rotate")) {
        const Json& v = r.raw("rotate");
        if (!v.is_array() || v.size() != 4)
            r.fail("rotate", str("must be [axis_x, axis_y, axis_z, angle_deg], got ", jsonExcerpt(v)));
        for (int i = 0; i < 4; ++i)
            if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
                r.fail("rotate", str("must be 4 finite numbers, got ", jsonExcerpt(v)));
        Vec3 axis(v[0].get<float>(), v[1].get<float>(), v[2].get<float>());
        if (length(axis) == 0) r.fail("rotate", "axis must be non-zero");
        rot = Mat4::rotate(axis, v[3].get<double>());
    }
    if (r.has("translate")) t = Mat4::translate(r.vec3("translate"));
    return t * rot * s;  // scale, then rotate, then translate
}

Mat4 optionalTransform(const JsonReader& r) {
    return r.has("transform") ? parseTransform(r.object("transform")) : Mat4::identity();
}

CameraDesc parseCamera(const JsonReader& r) {
    r.allowOnly({"type", "position", "look_at", "up", "fov_deg", "width_world", "resolution"});
    CameraDesc c;
    std::string type = r.choice("type", "perspective", {"perspective", "orthographic"});
    c.type = type == "perspective" ? CameraDesc::Type::Perspective : CameraDesc::Type::Orthographic;
    c.position = r.vec3("position", c.position);
    c.lookAt = r.vec3("look_at", c.lookAt);
    c.up = r.vec3("up", c.up);
    Vec3 view = c.lookAt - c.position;
    if (!(length(view) > 0))
        r.fail("look_at", str("equals camera.position (", c.position.x, ", ", c.position.y, ", ", c.position.z,
                              "): the camera has no viewing direction"));
    if (!(length(c.up) > 0)) r.fail("up", str("must be a non-zero vector, got ", jsonExcerpt(r.raw("up"))));
    if (length(cross(normalize(view), normalize(c.up))) < 1e-6f)
        r.fail("up", str(jsonExcerpt(r.raw("up")), " is parallel to the viewing direction (look_at - position = [",
                         view.x, ", ", view.y, ", ", view.z, "])"));
    c.fovDeg = float(r.number("fov_deg", c.fovDeg));
    if (!(c.fovDeg > 0 && c.fovDeg < 180)) r.fail("fov_deg", str("must be in (0, 180) degrees, got ", c.fovDeg));
    c.widthWorld = float(r.positive("width_world", c.widthWorld));
    if (r.has("resolution")) {
        const Json& v = r.raw("resolution");
        if (!v.is_array() || v.size() != 2 || !v[0].is_number_integer() || !v[1].is_number_integer())
            r.fail("resolution", str("must be [width, height] in whole pixels, got ", jsonExcerpt(v)));
        long long w = v[0].get<long long>(), h = v[1].get<long long>();
        if (w < 1 || h < 1) r.fail("resolution", str("must be at least 1x1, got ", w, "x", h));
        if (w > 32768 || h > 32768 || w * h > (1LL << 28))
            r.fail("resolution", str(w, "x", h, " is too large (at most 32768 per side and 2^28 pixels)"));
        c.width = int(w);
        c.height = int(h);
    }
    return c;
}

LightDesc parseLight(const JsonReader& r) {
    LightDesc l;
    std::string type = r.choice("type", "", {"point", "spot", "directional", "collimated_quad", "sphere"});
    if (type == "point") {
        r.allowOnly({"type", "position", "intensity"});
        l.type = LightDesc::Type::Point;
        l.position = r.vec3("position");
        l.intensity = r.nonNegativeColor("intensity", Vec3(1));
    } else if (type == "spot") {
        r.allowOnly({"type", "position", "direction", "intensity", "cone_deg", "falloff_deg"});
        l.type = LightDesc::Type::Spot;
        l.position = r.vec3("position");
        l.direction = r.unitDirection("direction");
        l.intensity = r.nonNegativeColor("intensity", Vec3(1));
        l.coneDeg = float(r.number("cone_deg", 30));
        if (!(l.coneDeg > 0 && l.coneDeg <= 180)) r.fail("cone_deg", str("must be in (0, 180], got ", l.coneDeg));
        l.falloffDeg = float(r.number("falloff_deg", std::min(5.f, l.coneDeg)));
        if (!(l.falloffDeg >= 0 && l.falloffDeg <= l.coneDeg))
            r.fail("falloff_deg", str("must be in [0, cone_deg = ", l.coneDeg, "], got ", l.falloffDeg));
    } else if (type == "directional") {
        r.allowOnly({"type", "direction", "irradiance"});
        l.type = LightDesc::Type::Directional;
        l.direction = r.unitDirection("direction");
        l.irradiance = r.nonNegativeColor("irradiance", Vec3(1));
    } else if (type == "collimated_quad") {
        r.allowOnly({"type", "center", "u", "v", "direction", "irradiance"});
        l.type = LightDesc::Type::CollimatedQuad;
        l.center = r.vec3("center");
        l.u = r.vec3("u");
        l.v = r.vec3("v");
        if (!(length(cross(l.u, l.v)) > 0)) r.fail("v", "u and v must be non-zero and not parallel");
        l.direction = r.unitDirection("direction");
        if (std::fabs(dot(normalize(cross(l.u, l.v)), l.direction)) < 1e-6f)
            r.fail("direction", "lies in the plane of the quad: no light would leave it");
        l.irradiance = r.nonNegativeColor("irradiance", Vec3(1));
    } else {
        r.allowOnly({"type", "position", "radius", "power"});
        l.type = LightDesc::Type::Sphere;
        l.position = r.vec3("position");
        l.radius = float(r.positive("radius", 1));
        l.power = r.nonNegativeColor("power", Vec3(1));
    }
    return l;
}

void parseCoefficients(const JsonReader& r, MediumDesc& m) {
    m.sigma_a = r.nonNegativeColor("sigma_a", Vec3(0));
    m.sigma_s = r.nonNegativeColor("sigma_s", Vec3(1));
    m.g = float(r.number("g", 0));
    if (!(std::fabs(m.g) < 1))
        r.fail("g", str("the Henyey-Greenstein parameter must satisfy |g| < 1, got ", m.g));
}

MediumDesc parseMedium(const JsonReader& r, size_t index) {
    MediumDesc m;
    std::string type = r.choice("type", "", {"homogeneous", "vdb"});
    m.name = r.string("name", str("medium", index));
    if (m.name.empty()) r.fail("name", "must not be empty");
    if (type == "homogeneous") {
        r.allowOnly({"name", "type", "sigma_a", "sigma_s", "g", "bounds"});
        m.type = MediumDesc::Type::Homogeneous;
        parseCoefficients(r, m);
        if (r.has("bounds")) {
            JsonReader b = r.object("bounds");
            b.allowOnly({"min", "max"});
            m.hasBounds = true;
            m.bounds.lo = b.vec3("min");
            m.bounds.hi = b.vec3("max");
            if (!(m.bounds.lo.x < m.bounds.hi.x && m.bounds.lo.y < m.bounds.hi.y && m.bounds.lo.z < m.bounds.hi.z))
                b.fail("max", "must be greater than min on every axis");
        }
    } else {
        r.allowOnly({"name", "type", "file", "grid", "density_scale", "sigma_a", "sigma_s", "g", "emission", "transform"});
        m.type = MediumDesc::Type::Vdb;
        m.file = r.string("file");
        m.grid = r.string("grid", "density");
        m.densityScale = float(r.numberIn("density_scale", 1, 0, 1e30));
        parseCoefficients(r, m);
        if (r.has("emission")) {
            JsonReader e = r.object("emission");
            e.allowOnly({"grid", "scale", "color", "blackbody", "intensity", "temperature_scale", "temperature_offset"});
            m.hasEmission = true;
            m.emissionGrid = e.string("grid", "temperature");
            m.emissionColor = e.nonNegativeColor("color", Vec3(1));
            m.blackbody = e.boolean("blackbody", false);
            // Each mode refuses the other's keys: "scale" of a temperature grid
            // would be ambiguous (radiance or Kelvin?).
            if (m.blackbody && e.has("scale"))
                e.fail("scale", "is not used with blackbody emission: use intensity (radiance) or "
                                "temperature_scale (grid value to Kelvin)");
            for (const char* k : {"intensity", "temperature_scale", "temperature_offset"})
                if (!m.blackbody && e.has(k)) e.fail(k, "is used only with \"blackbody\": true");
            if (m.blackbody) {
                m.emissionScale = float(e.numberIn("intensity", 1, 0, 1e30));
                m.temperatureScale = float(e.numberIn("temperature_scale", 1, 0, 1e9));
                m.temperatureOffset = float(e.numberIn("temperature_offset", 0, -1e9, 1e9));
            } else {
                m.emissionScale = float(e.numberIn("scale", 1, 0, 1e30));
            }
        }
        m.transform = optionalTransform(r);
    }
    return m;
}

SurfaceDesc parseSurface(const JsonReader& r) {
    SurfaceDesc s;
    r.allowOnly({"shape", "file", "grid", "isovalue", "transform", "material", "interior", "exterior",
                 "smooth_normals"});
    std::string shape = r.choice("shape", "", {"sphere", "box", "mesh", "vdb_isosurface"});
    if (shape == "sphere") s.shape = SurfaceDesc::Shape::Sphere;
    else if (shape == "box") s.shape = SurfaceDesc::Shape::Box;
    else if (shape == "mesh") s.shape = SurfaceDesc::Shape::Mesh;
    else s.shape = SurfaceDesc::Shape::VdbIsosurface;
    if (s.shape == SurfaceDesc::Shape::Mesh || s.shape == SurfaceDesc::Shape::VdbIsosurface) {
        s.file = r.string("file");
    } else if (r.has("file")) {
        r.fail("file", str("is only used by shape \"mesh\" or \"vdb_isosurface\", not \"", shape, "\""));
    }
    if (s.shape == SurfaceDesc::Shape::VdbIsosurface) {
        s.grid = r.string("grid", "density");
        s.isovalue = float(r.number("isovalue", 0.5));
    } else if (r.has("grid") || r.has("isovalue")) {
        r.fail(r.has("grid") ? "grid" : "isovalue", "is only used by shape \"vdb_isosurface\"");
    }
    s.transform = optionalTransform(r);
    if (r.has("material")) {
        JsonReader mr = r.object("material");
        std::string type = mr.choice("type", "dielectric", {"dielectric", "diffuse", "interface"});
        if (type == "dielectric") {
            mr.allowOnly({"type", "ior"});
            s.material.type = MaterialDesc::Type::Dielectric;
            s.material.ior = float(mr.numberIn("ior", 1.5, 1e-3, 100));
        } else if (type == "diffuse") {
            mr.allowOnly({"type", "albedo"});
            s.material.type = MaterialDesc::Type::Diffuse;
            s.material.albedo = mr.nonNegativeColor("albedo", Vec3(0.5f));
            if (maxComponent(s.material.albedo) > 1)
                mr.fail("albedo", "must be at most 1 per channel (energy conservation)");
        } else {
            mr.allowOnly({"type"});
            s.material.type = MaterialDesc::Type::Interface;
        }
    }
    bool meshLike = s.shape == SurfaceDesc::Shape::Mesh || s.shape == SurfaceDesc::Shape::VdbIsosurface;
    if (r.has("smooth_normals") && !meshLike)
        r.fail("smooth_normals", "is only used by shape \"mesh\" or \"vdb_isosurface\"");
    s.smoothNormals = r.boolean("smooth_normals", s.shape == SurfaceDesc::Shape::VdbIsosurface);
    s.interior = r.string("interior", "");
    s.exterior = r.string("exterior", "");
    return s;
}

// The document with the frame token of its file paths (media[i].file,
// surfaces[i].file, environment.file) replaced by `frame`; without a frame, a
// path holding the token is an error naming the key and the value. Values of
// the wrong type are left for the parser to report.
Json withFramePaths(const Json& doc, const std::string& file, std::optional<int> frame) {
    Json out = doc;
    auto visit = [&](Json& node, const std::string& keyPath) {
        if (!node.is_object() || !node.contains("file") || !node["file"].is_string()) return;
        Json& value = node["file"];
        const std::string path = value.get<std::string>();
        if (!hasFrameToken(path)) return;
        if (!frame)
            throw SceneKeyError(file, keyPath,
                                str(keyPath, ": \"", path, "\" holds the frame token (a run of '#'): render it with "
                                             "--frames (e.g. --frames 1-100) to replace the token by each frame's number"));
        value = substituteFrame(path, *frame);
    };
    if (!out.is_object()) return out;
    for (const char* list : {"media", "surfaces"}) {
        if (!out.contains(list) || !out[list].is_array()) continue;
        Json& items = out[list];
        for (size_t i = 0; i < items.size(); ++i) visit(items[i], str(list, "[", i, "].file"));
    }
    if (out.contains("environment")) visit(out["environment"], "environment.file");
    return out;
}

}  // namespace

std::string sceneHash(const SceneDesc& desc) {
    Json j = Json::parse(desc.jsonText);
    j.erase("camera");
    j.erase("photons");
    j.erase("cache");
    j.erase("render");
    j.erase("experiments");
    j["max_depth"] = desc.render.maxDepth;
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a64(j.dump())));
    return buf;
}

std::string prettySceneJson(const SceneDesc& desc, int indent) { return Json::parse(desc.jsonText).dump(indent); }

std::string resolvePath(const std::string& baseDir, const std::string& path) {
    if (path.empty() || path[0] == '/' || baseDir.empty()) return path;
    return baseDir + "/" + path;
}

std::vector<std::pair<std::string, std::string>> sceneFilePaths(const SceneDesc& desc) {
    std::vector<std::pair<std::string, std::string>> out;
    for (size_t i = 0; i < desc.media.size(); ++i)
        if (desc.media[i].type == MediumDesc::Type::Vdb) out.emplace_back(str("media[", i, "].file"), desc.media[i].file);
    for (size_t i = 0; i < desc.surfaces.size(); ++i)
        if (!desc.surfaces[i].file.empty()) out.emplace_back(str("surfaces[", i, "].file"), desc.surfaces[i].file);
    if (!desc.environment.file.empty()) out.emplace_back("environment.file", desc.environment.file);
    return out;
}

SceneDesc parseSceneJson(const Json& input, const std::string& file, std::optional<int> frame) {
    // The frame's own paths everywhere, the recorded document included: a
    // frame's scene is the scene that names its files directly.
    const Json doc = withFramePaths(input, file, frame);
    SceneDesc scene;
    scene.file = file;
    scene.frame = frame;
    size_t slash = file.find_last_of('/');
    scene.baseDir = slash == std::string::npos ? "." : file.substr(0, slash == 0 ? 1 : slash);
    scene.jsonText = doc.dump();
    JsonReader root(doc, file, "");
    root.allowOnly({"camera", "lights", "media", "surfaces", "background", "environment", "render", "photons", "cache",
                    "experiments"});
    if (root.has("camera")) scene.camera = parseCamera(root.object("camera"));
    auto listOf = [&](const char* key) -> const Json& {
        const Json& v = root.raw(key);
        if (!v.is_array()) root.fail(key, str("must be a list, got ", jsonExcerpt(v)));
        return v;
    };
    if (root.has("lights")) {
        const Json& v = listOf("lights");
        for (size_t i = 0; i < v.size(); ++i) scene.lights.push_back(parseLight(JsonReader(v[i], file, root.keyPath("lights", i))));
    }
    if (root.has("media")) {
        const Json& v = listOf("media");
        for (size_t i = 0; i < v.size(); ++i) {
            JsonReader r(v[i], file, root.keyPath("media", i));
            MediumDesc m = parseMedium(r, i);
            for (const auto& other : scene.media)
                if (other.name == m.name) r.fail("name", str("\"", m.name, "\" is used by two media"));
            if (m.type == MediumDesc::Type::Vdb) m.file = resolvePath(scene.baseDir, m.file);
            scene.media.push_back(m);
        }
    }
    if (root.has("surfaces")) {
        const Json& v = listOf("surfaces");
        for (size_t i = 0; i < v.size(); ++i) {
            JsonReader r(v[i], file, root.keyPath("surfaces", i));
            SurfaceDesc s = parseSurface(r);
            std::vector<std::string> names;
            for (const auto& m : scene.media) names.push_back(m.name);
            for (const char* side : {"interior", "exterior"}) {
                const std::string& n = std::string(side) == "interior" ? s.interior : s.exterior;
                if (n.empty()) continue;
                bool found = false;
                for (const auto& m : names) found = found || m == n;
                if (!found) {
                    std::string msg = str("names medium \"", n, "\", which is not in media");
                    std::string near = nearestKey(n, names);
                    if (!near.empty()) msg += str(" (did you mean \"", near, "\"?)");
                    r.fail(side, msg);
                }
            }
            if (!s.file.empty()) s.file = resolvePath(scene.baseDir, s.file);
            scene.surfaces.push_back(s);
        }
    }
    scene.background = root.nonNegativeColor("background", Vec3(0));
    if (root.has("environment")) {
        JsonReader e = root.object("environment");
        e.allowOnly({"file", "scale", "rotation"});
        const std::string file = e.string("file");
        if (file.empty()) e.fail("file", "must name a lat-long EXR file");
        scene.environment.file = resolvePath(scene.baseDir, file);
        scene.environment.scale = float(e.numberIn("scale", 1, 0, 1e30));
        scene.environment.rotationDeg = float(e.numberIn("rotation", 0, -36000, 36000));
        if (!isBlack(scene.background))
            root.fail("environment", "cannot be given together with a non-black background: the map is the background");
    }
    if (root.has("render")) scene.render = parseRender(root.object("render"));
    if (root.has("photons")) scene.photons = parsePhotons(root.object("photons"));
    if (root.has("cache")) scene.cache = parseCache(root.object("cache"));
    if (root.has("experiments")) scene.experiments = parseExperiments(root.object("experiments"));
    if (scene.render.methodAuto) scene.render.method = chooseMethod(scene, scene.render.methodReason);
    return scene;
}

namespace {

// The keys of a --set assignment's path, "a.b.0.c" -> {a, b, 0, c} (the one
// place that splits it: applying the override and naming the key it
// replaced both use it).
std::vector<std::string> overrideKeys(const std::string& assignment) {
    std::vector<std::string> parts;
    std::stringstream ss(assignment.substr(0, assignment.find('=')));
    for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
    return parts;
}

}  // namespace

void applyOverride(Json& doc, const std::string& assignment) {
    size_t eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0)
        throw InputError(str("--set \"", assignment, "\": expected key.path=value"));
    const std::string valueText = assignment.substr(eq + 1);
    Json value;
    try {
        value = Json::parse(valueText);
    } catch (const Json::exception&) {
        value = valueText;  // bare words are strings
    }
    Json* node = &doc;
    const std::vector<std::string> parts = overrideKeys(assignment);
    for (size_t i = 0; i < parts.size(); ++i) {
        const std::string& p = parts[i];
        if (p.empty()) throw InputError(str("--set \"", assignment, "\": empty key in path"));
        bool last = i + 1 == parts.size();
        if (node->is_array()) {
            char* end = nullptr;
            long idx = std::strtol(p.c_str(), &end, 10);
            if (*end != 0 || idx < 0 || size_t(idx) >= node->size())
                throw InputError(str("--set \"", assignment, "\": \"", p, "\" is not a valid index (list has ",
                                     node->size(), " items)"));
            node = &(*node)[size_t(idx)];
        } else {
            if (node->is_null()) *node = Json::object();
            if (!node->is_object())
                throw InputError(str("--set \"", assignment, "\": cannot descend into \"", p, "\""));
            node = &(*node)[p];
        }
        if (last) *node = value;
    }
}

SceneDesc parseSceneText(const std::string& text, const std::string& file, const std::vector<std::string>& overrides,
                         std::optional<int> frame) {
    Json doc;
    try {
        doc = Json::parse(text);
    } catch (const Json::parse_error& e) {
        const size_t offset = rejectedToken(text, e.byte);
        size_t line, col;
        lineAndColumn(text, offset, line, col);
        std::string what = e.what();
        size_t pos = what.find("parse error");
        std::string detail = pos == std::string::npos ? what : what.substr(pos);
        size_t colon = detail.find(": ");
        if (colon != std::string::npos) detail = detail.substr(colon + 2);
        throw InputError(str(file, ":", line, ":", col, ": malformed JSON: ", detail, caretExcerpt(text, offset)));
    } catch (const Json::exception& e) {
        // Not a syntax error, and without a position: a number too large for
        // a double (found by fuzzing: "1E400" is out_of_range, not parse_error).
        std::string what = e.what();
        size_t close = what.find("] ");
        throw InputError(str(file, ": malformed JSON: ", close == std::string::npos ? what : what.substr(close + 2)));
    }
    for (const auto& o : overrides) applyOverride(doc, o);
    try {
        return parseSceneJson(doc, file, frame);
    } catch (const SceneKeyError& e) {
        // Point at the key in the file, unless an override replaced it (then
        // the bad value is not in the text).
        for (const auto& o : overrides) {
            std::string asKeyPath;
            for (const std::string& part : overrideKeys(o)) {
                bool index = !part.empty() && part.find_first_not_of("0123456789") == std::string::npos;
                asKeyPath += index ? "[" + part + "]" : (asKeyPath.empty() ? "" : ".") + part;
            }
            if (e.keyPath.compare(0, asKeyPath.size(), asKeyPath) == 0) throw;
        }
        size_t offset = locateJsonPath(text, e.keyPath);
        if (offset == std::string::npos) throw;
        size_t line, col;
        lineAndColumn(text, offset, line, col);
        throw InputError(str(file, ":", line, ":", col, ": ", e.detail, caretExcerpt(text, offset)));
    }
}

SceneDesc loadSceneFile(const std::string& path, const std::vector<std::string>& overrides,
                        std::optional<int> frame) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) throw IoError(str(path, ": cannot open scene file: ", std::strerror(errno)));
    if (S_ISDIR(st.st_mode)) throw IoError(str(path, ": is a directory, not a scene file"));
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(str(path, ": cannot open scene file: ", std::strerror(errno)));
    std::stringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw IoError(str(path, ": cannot read scene file: ", std::strerror(errno)));
    return parseSceneText(ss.str(), path, overrides, frame);
}

}  // namespace vdbmarch
