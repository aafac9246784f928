// What the tests share, in one namespace (vdbmarch::test): temporary folders
// that remove themselves, small file utilities, a runner for the vdbmarch
// command, checks on error messages, statistics (chi-square, standard
// errors), image checks, scenes from JSON text, VDB fixtures written at test
// run time (never committed), the bad-input fixture, light descriptions, and
// the method list that method-parameterised suites run over.
//
// Include it as "support/support.h" (tests/ is on the test targets' include
// path). OpenVDB stays out of this header: the fixtures that need it are
// written by support.cpp.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <ostream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/math.h"
#include "core/error.h"
#include "image/image.h"
#include "estimators/estimator.h"
#include "parse/method.h"
#include "parse/scene_desc.h"
#include "render/render.h"
#include "scene/lights.h"
#include "scene/environment.h"
#include "scene/scene.h"

namespace vdbmarch {

// Parameterised tests print a Method by its name (gtest finds this by ADL).
inline void PrintTo(Method m, std::ostream* os) { *os << methodName(m); }

namespace test {

namespace fs = std::filesystem;

using ::vdbmarch::PiD;

// ---------------------------------------------------------------------------
// Temporary folders and files

// A fresh folder "vdbmarch_<label>_XXXXXX" under the system temp dir, removed
// with everything in it when the object goes (kept when the environment
// variable VDBMARCH_KEEP_TEST_DIRS is set, to look at after a failure).
class TempDir {
public:
    explicit TempDir(const std::string& label = "test");
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    const std::string& path() const { return mPath; }
    // The path of `name` inside the folder.
    std::string operator/(const std::string& name) const;
    // Writes `bytes` to `name` inside the folder; returns its path.
    std::string write(const std::string& name, const std::string& bytes) const;

private:
    std::string mPath;
};

// Writes `bytes` to `path` (binary); a failed write is a test failure.
void writeText(const std::string& path, const std::string& bytes);
// The whole file ("" when it cannot be read).
std::string readBytes(const std::string& path);
// Names of the entries of `dir`.
std::set<std::string> listDir(const std::string& dir);
// Names in `dir` that look like AtomicFile temporaries (".<name>.tmp-<pid>-<n>").
std::vector<std::string> tempLeftovers(const std::string& dir);

// ---------------------------------------------------------------------------
// The command line tool

struct CliResult {
    int exitCode = -1;  // -1: did not exit normally (signal)
    std::string out, err;
    double seconds = 0;
};

std::string shellQuote(const std::string& s);

// The vdbmarch executable the tests run (shell-quoted use: shellQuote).
std::string vdbmarchBinary();

// Runs `vdbmarch args...` in `cwd` (under `timeout`, so a product bug cannot
// hang the suite). stdout and stderr are captured into files in `captureDir`,
// which should not be the directory whose contents a test inspects.
CliResult runCli(const std::vector<std::string>& args, const std::string& cwd, const std::string& captureDir,
                 int timeoutSeconds = 60);

// Runs the shell command line `command` in `cwd` the same way (under
// `timeout`, output captured in `captureDir`): for other tools (vdb_print, blender).
CliResult runShell(const std::string& command, const std::string& cwd, const std::string& captureDir,
                   int timeoutSeconds = 60);

// True when `program` is an executable on PATH (tests of optional tools skip without it).
bool onPath(const std::string& program);

int countOccurrences(const std::string& hay, const std::string& needle);

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
        const char* kind = dynamic_cast<const InputError*>(&e) ? "InputError"
                           : dynamic_cast<const IoError*>(&e) ? "IoError"
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

// `f` throws exactly an `E` whose message contains every needle.
template <typename E, typename F>
void expectErrorContaining(F&& f, std::initializer_list<std::string> needles) {
    const std::string msg = errorOf<E>(std::forward<F>(f));
    for (const std::string& n : needles) EXPECT_CONTAINS(msg, n);
}

// True when `msg` shows the vector (x, y, z) in any of the usual spellings:
// JSON "[0,0,2]", "[0, 0, 2]" or "(0, 0, 2)" / "0, 0, 2".
bool mentionsVec3(const std::string& msg, const std::string& x, const std::string& y, const std::string& z);
// True when `msg` contains `number` as a whole token (not part of a longer number).
bool hasNumberToken(const std::string& msg, const std::string& number);

// A 20-triangle icosahedron of circumradius 1 / 1.902 (about 0.53) about
// the origin, written to `path` as OBJ: a small glass mesh for tests.
void writeIcosahedron(const std::string& path);

// The glass ball of the paper's figure 4 (vdb_samples/scenes/fig4_caustic*.json):
// radius 0.45 at (0, 0.75, 0), n = 1.5.
GlassSphere figure4Ball();

// A furnace: a uniform background of radiance 1 and white fog (albedo 1)
// around two lossless glass objects (a sphere, ior 1.5; a box, ior 2.4),
// 16x16 at 64 spp with `method`; every pixel's expectation is 1.
std::unique_ptr<Scene> glassInWhiteFog(const std::string& method, bool glassSplitting);

// ---------------------------------------------------------------------------
// Statistics

// Upper-tail probability of the chi-square distribution (regularised
// incomplete gamma Q(k/2, x/2)) by series / continued fraction.
double chiSquareQ(double x, double dof);

struct ChiSquare {
    double chi2 = 0;
    int dof = -1;  // pools - 1
    double p() const { return chiSquareQ(chi2, dof); }
};

// Pearson's statistic of observed against expected counts, adjacent bins
// pooled until the expected count reaches `minExpected` (the last pool takes
// what is left). A pool expected to be empty adds no degree of freedom, and
// infinity if it was not empty.
ChiSquare pooledChiSquare(const std::vector<double>& observed, const std::vector<double>& expected,
                          double minExpected);

// Mean, variance and standard error of the mean of a sample.
class SampleStats {
public:
    void add(double v) {
        mSum += v;
        mSum2 += v * v;
        ++mCount;
    }
    size_t count() const { return mCount; }
    double mean() const { return mSum / double(mCount); }
    // Unbiased sample variance.
    double variance() const {
        const double m = mean();
        return std::max(0.0, mSum2 / double(mCount) - m * m) * double(mCount) / double(mCount - 1);
    }
    double stdError() const { return std::sqrt(variance() / double(mCount)); }

private:
    double mSum = 0, mSum2 = 0;
    size_t mCount = 0;
};

struct ChannelStats {
    double mean = 0, stdError = 0;
};

// Mean and standard error over pixels of one channel (0-2 colour, 3 alpha).
ChannelStats pixelStats(const Image& img, int channel);

// Two unbiased renders of the same scene agree: the paired per-pixel
// differences have zero mean over the image and over each quadrant, per
// colour channel, within 4 standard errors. `what` names the case.
void expectPairedAgreement(const Image& a, const Image& b, const std::string& what);

// The mean over pixels and colour channels of the squared difference of two
// renders (of two seeds: twice each one's variance).
double pairMse(const Image& a, const Image& b);

// A sample scene rendered with `overrides`, the boolean render setting
// `toggle` (e.g. "experiments.sphere_caustics") set to `on`, and render.seed.
Image renderSampleToggled(const std::string& sample, std::vector<std::string> overrides, const std::string& toggle,
                          bool on, int seed);

// Overrides of vdb_samples/cloud_sky.json for the unbiasedness checks of the
// path tracer's samplers: a 32x24 view, max_depth 6, the sky at 0.3, a point
// light inside the cloud, a spot and a sphere light, and a glass ball in
// front of it.
std::vector<std::string> cloudSkyWithLightsAndGlass();

// ---------------------------------------------------------------------------
// Images

bool allFinite(const Image& img);
// True when the two hold the same floats, bit for bit.
bool sameBits(const std::vector<float>& a, const std::vector<float>& b);
float maxAlpha(const Image& img);
// Every pixel shows exactly `bg` with alpha 0 (nothing in front of it).
void expectBackgroundEverywhere(const Image& img, const Color& bg, float tol = 1e-6f);
// Every value of the image is finite and no sample was dropped as non-finite.
void expectAllFinite(const RenderResult& r);

// ---------------------------------------------------------------------------
// Scenes

// A scene from JSON text; `file` names it in messages and resolves relative
// paths (tests give absolute ones).
std::unique_ptr<Scene> sceneFromJson(const std::string& json, const std::string& file = "scene.json");

// The scenes of vdb_samples/ ("cloud.json", "glass.json").
std::string samplePath(const std::string& name);
// Irradiance (red channel) that `env`, a width x height map turned by
// rotationDeg about +Y, gives a surface with normal n: the sum over
// sub x sub sub-texels of L cos dOmega, an independent quadrature of what
// light sampling and photon emission estimate.
double environmentIrradianceByQuadrature(const Environment& env, const Vec3& n, float rotationDeg, int sub = 8);

// A file or folder of the source tree, e.g. "tests/image/fuzz_findings".
std::string sourcePath(const std::string& relative);
// A file of shared/assets next to the checkout (the test skips without it).
std::string assetPath(const std::string& name);

// Replaces every "@KEY@" in `text`.
std::string subst(std::string text, const std::vector<std::pair<std::string, std::string>>& pairs);

// ---------------------------------------------------------------------------
// VDB fixtures

// A voxel index; one number stands for all three.
struct Index3 {
    Index3(int c) : x(c), y(c), z(c) {}  // NOLINT: implicit on purpose
    Index3(int x, int y, int z) : x(x), y(y), z(z) {}
    int x, y, z;
};

// Writes a float fog grid named `name` with value `v` in the index box
// [lo, hi] (inclusive), voxel size h, plus active voxels of value `v` at
// `extra`, to `path`; returns `path`.
std::string writeBoxGrid(const std::string& path, const Index3& lo, const Index3& hi, float v, double h,
                  const char* name = "density", const std::vector<Index3>& extra = {});

// A 20^3-voxel density box of 1 (voxel 0.05) inside a larger `temperature`
// box of 1, so L_e is constant wherever the density is non-zero. Returns `path`.
std::string writeEmissiveBox(const std::string& path);
// The same for a density box [lo, hi] (voxel h) inside a temperature box
// `margin` voxels larger on every side.
std::string writeEmissiveBox(const std::string& path, const Index3& lo, const Index3& hi, int margin, double h);

// The same with a temperature rising along x: t0 + dt x (i - lo.x + margin)
// at index (i, j, k) of the temperature box.
std::string writeTemperatureRamp(const std::string& path, const Index3& lo, const Index3& hi, int margin, double h,
                                 float t0, float dt);

// Fixture geometry of writeVdbFixtures: voxel size 0.25, a 4x4x4 block of
// voxels at index [-2, 1]^3, i.e. a cube of world edge 1 centred near the origin.
constexpr double kVoxel = 0.25;
constexpr int kBlockLo = -2, kBlockHi = 1;
constexpr int kBlockVoxels = 64;
// The values planted in grid "bad": 2 NaN, +Inf, -Inf and 2 negatives.
constexpr int kBadValues = 6;

// Writes into `dir`:
//   grids.vdb      density (float, 64 voxels of 1), vel (vec3s), bad (float with
//                  NaN/Inf/negative values among 58 good ones), empty (float, no voxels)
//   empty_only.vdb density (float, no active voxels)
//   vel_only.vdb   vel (vec3s) only: no scalar grid at all
//   not_a_vdb.vdb  a text file
void writeVdbFixtures(const std::string& dir);

// ---------------------------------------------------------------------------
// Bad input: a work folder with the VDB fixtures, scenes written into it, and
// the command run there. Every test gets its own folder; warnings are quiet.

// A VDB medium seen by an 8x8 camera; @GRID@ and @FILE@ are filled in.
extern const char* const kVdbScene;
// A homogeneous medium; @MEDIUM@ (extra medium keys) and @CAMERA@ (extra camera keys) are filled in.
extern const char* const kHomogeneousScene;

std::string vdbScene(const std::string& grid, const std::string& file = "grids.vdb");
std::string homogeneousScene(const std::string& mediumExtra = "", const std::string& cameraExtra = "");

class BadInput : public ::testing::Test {
protected:
    void SetUp() override;
    void TearDown() override;

    std::string work(const std::string& name) const { return (fs::path(mWork) / name).string(); }
    // Writes a scene file into the work directory and returns its path.
    std::string scene(const std::string& name, const std::string& text) const;
    CliResult cli(const std::vector<std::string>& args, int timeoutSeconds = 60) const;
    // The command failed the documented way: exit 1 and one "vdbmarch: error:" line naming every needle.
    static void expectCliError(const CliResult& r, const std::vector<std::string>& needles);

    TempDir mRoot{"badinput"};
    std::string mWork;
};

// ---------------------------------------------------------------------------
// Lights

LightDesc pointLight(const Vec3& p, const Color& intensity);
LightDesc spotLight(const Vec3& p, const Vec3& dir, float coneDeg, float falloffDeg, const Color& intensity);
LightDesc directionalLight(const Vec3& dir, const Color& irradiance);
LightDesc quadLight(const Vec3& c, const Vec3& u, const Vec3& v, const Vec3& dir, const Color& irradiance);
LightDesc sphereLight(const Vec3& p, float radius, const Color& power);

// ---------------------------------------------------------------------------
// Methods

// Test names for suites over `::testing::ValuesIn(estimatorMethods())`.
std::string methodParamName(const ::testing::TestParamInfo<Method>& info);
// The --set override that selects `m`: render.method="<name>".
std::string methodOverride(Method m);

}  // namespace test
}  // namespace vdbmarch
