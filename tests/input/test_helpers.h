// Helpers for the bad-input tests: a private temporary directory, small file
// utilities, a runner for the vdbmarch command that captures stdout/stderr,
// checks on error messages, and generators of tiny VDB fixtures (written at
// test run time, never committed).
#pragma once

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "core/error.h"

namespace vdbmarch_test {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// Files

inline void writeText(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    ASSERT_TRUE(out.good()) << "cannot write test file " << path;
}

inline std::string readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

inline std::set<std::string> listDir(const std::string& dir) {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
    return names;
}

// Names in `dir` that look like AtomicFile temporaries (".<name>.tmp-<pid>-<n>").
inline std::vector<std::string> tempLeftovers(const std::string& dir) {
    std::vector<std::string> out;
    for (const auto& n : listDir(dir))
        if (!n.empty() && n[0] == '.' && n.find(".tmp-") != std::string::npos) out.push_back(n);
    return out;
}

// A fresh directory per test, removed afterwards (kept when VDBMARCH_KEEP_TEST_DIRS is set).
class TempDir {
public:
    TempDir() {
        std::string pattern = (fs::path(::testing::TempDir()) / "vdbmarch_badinput_XXXXXX").string();
        std::vector<char> buf(pattern.begin(), pattern.end());
        buf.push_back('\0');
        if (!mkdtemp(buf.data())) throw std::runtime_error(std::string("mkdtemp: ") + std::strerror(errno));
        mPath = buf.data();
    }
    ~TempDir() {
        if (std::getenv("VDBMARCH_KEEP_TEST_DIRS")) return;  // for debugging a failure
        std::error_code ec;
        fs::remove_all(mPath, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::string& path() const { return mPath; }
    std::string operator/(const std::string& name) const { return (fs::path(mPath) / name).string(); }

private:
    std::string mPath;
};

// ---------------------------------------------------------------------------
// The command line tool

struct CliResult {
    int exitCode = -1;  // -1: did not exit normally (signal)
    std::string out, err;
    double seconds = 0;
};

inline std::string shellQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) {
        if (c == '\'') q += "'\\''";
        else q += c;
    }
    return q + "'";
}

// Runs `vdbmarch args...` in `cwd` (under `timeout`, so a product bug cannot
// hang the suite). stdout and stderr are captured into files in `captureDir`,
// which should not be the directory whose contents a test inspects.
inline CliResult runCli(const std::vector<std::string>& args, const std::string& cwd, const std::string& captureDir,
                        int timeoutSeconds = 60) {
    const std::string outFile = (fs::path(captureDir) / "cli_stdout.txt").string();
    const std::string errFile = (fs::path(captureDir) / "cli_stderr.txt").string();
    std::string cmd = "cd " + shellQuote(cwd) + " && timeout " + std::to_string(timeoutSeconds) + " " +
                      shellQuote(VDBMARCH_BINARY);
    for (const auto& a : args) cmd += " " + shellQuote(a);
    cmd += " >" + shellQuote(outFile) + " 2>" + shellQuote(errFile) + " </dev/null";
    auto t0 = std::chrono::steady_clock::now();
    int status = std::system(cmd.c_str());
    CliResult r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (status != -1 && WIFEXITED(status)) r.exitCode = WEXITSTATUS(status);
    r.out = readBytes(outFile);
    r.err = readBytes(errFile);
    return r;
}

inline int countOccurrences(const std::string& hay, const std::string& needle) {
    int n = 0;
    for (size_t p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + needle.size())) ++n;
    return n;
}

// ---------------------------------------------------------------------------
// Error messages

// Runs `f`, which must throw exactly an `E`; returns its message. Any other
// outcome is a test failure (and an empty message, so later checks fail too).
template <typename E, typename F>
std::string errorOf(F&& f) {
    try {
        f();
    } catch (const std::exception& e) {
        if (dynamic_cast<const E*>(&e)) return e.what();
        const char* kind = dynamic_cast<const vdbmarch::InputError*>(&e) ? "InputError"
                           : dynamic_cast<const vdbmarch::IoError*>(&e) ? "IoError"
                                                                         : "another std::exception";
        ADD_FAILURE() << "wrong error type: got " << kind << ": " << e.what();
        return "";
    } catch (...) {
        ADD_FAILURE() << "expected a vdbmarch error, got a non-std exception";
        return "";
    }
    ADD_FAILURE() << "expected an exception, none was thrown";
    return "";
}

#define EXPECT_CONTAINS(hay, needle)                                                                   \
    EXPECT_NE(std::string(hay).find(needle), std::string::npos)                                        \
        << "expected to find  [" << (needle) << "]\nin the message   [" << (hay) << "]"

#define EXPECT_NOT_CONTAINS(hay, needle)                                                               \
    EXPECT_EQ(std::string(hay).find(needle), std::string::npos)                                        \
        << "did not expect    [" << (needle) << "]\nin the message   [" << (hay) << "]"

// True when `msg` shows the vector (x, y, z) in any of the usual spellings:
// JSON "[0,0,2]", "[0, 0, 2]" or "(0, 0, 2)" / "0, 0, 2".
inline bool mentionsVec3(const std::string& msg, const std::string& x, const std::string& y, const std::string& z) {
    for (const std::string& form : {"[" + x + "," + y + "," + z + "]", x + ", " + y + ", " + z, x + " " + y + " " + z})
        if (msg.find(form) != std::string::npos) return true;
    return false;
}

// ---------------------------------------------------------------------------
// VDB fixtures

// Fixture geometry: voxel size 0.25, a 4x4x4 block of voxels at index
// [-2, 1]^3, i.e. a cube of world edge 1 centred near the origin.
constexpr double kVoxel = 0.25;
constexpr int kBlockLo = -2, kBlockHi = 1;
constexpr int kBlockVoxels = 64;

// The values planted in grid "bad": 2 NaN, +Inf, -Inf and 2 negatives.
constexpr int kBadValues = 6;

inline openvdb::FloatGrid::Ptr makeBlockGrid(const std::string& name, float value) {
    auto g = openvdb::FloatGrid::create(0.f);
    g->setName(name);
    g->setTransform(openvdb::math::Transform::createLinearTransform(kVoxel));
    g->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto acc = g->getAccessor();
    for (int x = kBlockLo; x <= kBlockHi; ++x)
        for (int y = kBlockLo; y <= kBlockHi; ++y)
            for (int z = kBlockLo; z <= kBlockHi; ++z) acc.setValueOn(openvdb::Coord(x, y, z), value);
    return g;
}

// Writes into `dir`:
//   grids.vdb      density (float, 64 voxels of 1), vel (vec3s), bad (float with
//                  NaN/Inf/negative values among 58 good ones), empty (float, no voxels)
//   empty_only.vdb density (float, no active voxels)
//   vel_only.vdb   vel (vec3s) only: no scalar grid at all
//   not_a_vdb.vdb  a text file
inline void writeVdbFixtures(const std::string& dir) {
    openvdb::initialize();
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();

    auto density = makeBlockGrid("density", 1.f);

    auto vel = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.f));
    vel->setName("vel");
    vel->setTransform(openvdb::math::Transform::createLinearTransform(kVoxel));
    {
        auto acc = vel->getAccessor();
        for (int x = 0; x < 3; ++x) acc.setValueOn(openvdb::Coord(x, 0, 0), openvdb::Vec3s(1.f, 0.f, 0.f));
    }

    auto bad = makeBlockGrid("bad", 1.f);
    {
        auto acc = bad->getAccessor();
        acc.setValueOn(openvdb::Coord(-2, -2, -2), nan);
        acc.setValueOn(openvdb::Coord(1, 1, 1), nan);
        acc.setValueOn(openvdb::Coord(0, 0, 0), inf);
        acc.setValueOn(openvdb::Coord(-1, 0, 0), -inf);
        acc.setValueOn(openvdb::Coord(0, -1, 0), -0.5f);
        acc.setValueOn(openvdb::Coord(0, 0, -1), -3.f);
    }

    auto empty = openvdb::FloatGrid::create(0.f);
    empty->setName("empty");
    empty->setTransform(openvdb::math::Transform::createLinearTransform(kVoxel));

    {
        openvdb::GridPtrVec grids{density, vel, bad, empty};
        openvdb::io::File f((fs::path(dir) / "grids.vdb").string());
        f.write(grids);
        f.close();
    }
    {
        auto e = openvdb::FloatGrid::create(0.f);
        e->setName("density");
        e->setTransform(openvdb::math::Transform::createLinearTransform(kVoxel));
        openvdb::GridPtrVec grids{e};
        openvdb::io::File f((fs::path(dir) / "empty_only.vdb").string());
        f.write(grids);
        f.close();
    }
    {
        openvdb::GridPtrVec grids{vel};
        openvdb::io::File f((fs::path(dir) / "vel_only.vdb").string());
        f.write(grids);
        f.close();
    }
    writeText((fs::path(dir) / "not_a_vdb.vdb").string(), "this is a text file, not an OpenVDB volume\n");
}

}  // namespace vdbmarch_test
