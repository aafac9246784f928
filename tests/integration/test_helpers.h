// Shared helpers for integration tests: scenes from JSON strings, small VDB
// fixtures written at test time, and image statistics.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "image/image.h"
#include "render/render.h"
#include "scene/scene.h"

namespace vdbmarch::testing {

inline std::string tempDir() {
    static std::string dir = [] {
        std::string tmpl = ::testing::TempDir() + "vdbmarch_it_XXXXXX";
        std::vector<char> buf(tmpl.begin(), tmpl.end());
        buf.push_back(0);
        return std::string(mkdtemp(buf.data()));
    }();
    return dir;
}

// A float fog grid named `name` with value `v` in the index box [lo, hi]
// (inclusive), voxel size h.
inline openvdb::FloatGrid::Ptr makeBoxGrid(const openvdb::Coord& lo, const openvdb::Coord& hi, float v, double h,
                                           const char* name = "density") {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(0.f);
    grid->setName(name);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->denseFill(openvdb::CoordBBox(lo, hi), v, true);
    return grid;
}

inline void writeBoxGrid(const std::string& path, const openvdb::Coord& lo, const openvdb::Coord& hi, float v,
                         double h, const char* name = "density") {
    openvdb::io::File(path).write({makeBoxGrid(lo, hi, v, h, name)});
}

// A 20^3-voxel density box of 1 (voxel 0.05) inside a larger `temperature`
// box of 1, so L_e is constant wherever the density is non-zero.
inline void writeEmissiveBox(const std::string& path) {
    openvdb::io::File(path).write({makeBoxGrid(openvdb::Coord(0), openvdb::Coord(19), 1.f, 0.05),
                                   makeBoxGrid(openvdb::Coord(-4), openvdb::Coord(24), 1.f, 0.05, "temperature")});
}

inline std::unique_ptr<Scene> sceneFromJson(const std::string& json) {
    return buildScene(parseSceneText(json, tempDir() + "/scene.json"));
}

struct ChannelStats {
    double mean = 0, stdError = 0;
};

// Mean and standard error over pixels of one channel (0-2 colour, 3 alpha).
inline ChannelStats pixelStats(const Image& img, int channel) {
    double s = 0, s2 = 0;
    size_t n = size_t(img.width) * size_t(img.height);
    for (size_t i = 0; i < n; ++i) {
        double v = img.rgba[4 * i + size_t(channel)];
        s += v;
        s2 += v * v;
    }
    ChannelStats c;
    c.mean = s / double(n);
    double var = std::max(0.0, s2 / double(n) - c.mean * c.mean) * double(n) / double(n - 1);
    c.stdError = std::sqrt(var / double(n));
    return c;
}

}  // namespace vdbmarch::testing
