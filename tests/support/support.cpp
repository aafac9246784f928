#include "support/support.h"

#include "image/metrics.h"

#include <sys/wait.h>

#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>
#include <stdexcept>

#include <openvdb/openvdb.h>

#include "volume/medium.h"

namespace vdbmarch::test {

// ---------------------------------------------------------------------------
// Temporary folders and files

TempDir::TempDir(const std::string& label) {
    std::string pattern = (fs::temp_directory_path() / ("vdbmarch_" + label + "_XXXXXX")).string();
    std::vector<char> buf(pattern.begin(), pattern.end());
    buf.push_back('\0');
    if (!mkdtemp(buf.data())) throw std::runtime_error(std::string("mkdtemp ") + pattern + ": " + std::strerror(errno));
    mPath = buf.data();
}

TempDir::~TempDir() {
    if (std::getenv("VDBMARCH_KEEP_TEST_DIRS")) return;  // for debugging a failure
    std::error_code ec;
    fs::remove_all(mPath, ec);
}

std::string TempDir::operator/(const std::string& name) const { return (fs::path(mPath) / name).string(); }

std::string TempDir::write(const std::string& name, const std::string& bytes) const {
    const std::string p = *this / name;
    writeText(p, bytes);
    return p;
}

void writeText(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    out.close();
    EXPECT_TRUE(out.good()) << "cannot write test file " << path;
}

std::string readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::set<std::string> listDir(const std::string& dir) {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
    return names;
}

std::vector<std::string> tempLeftovers(const std::string& dir) {
    std::vector<std::string> out;
    for (const auto& n : listDir(dir))
        if (!n.empty() && n[0] == '.' && n.find(".tmp-") != std::string::npos) out.push_back(n);
    return out;
}

// ---------------------------------------------------------------------------
// The command line tool

std::string shellQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) {
        if (c == '\'') q += "'\\''";
        else q += c;
    }
    return q + "'";
}

std::string vdbmarchBinary() { return VDBMARCH_BINARY; }

CliResult runCli(const std::vector<std::string>& args, const std::string& cwd, const std::string& captureDir,
                 int timeoutSeconds) {
    std::string cmd = shellQuote(VDBMARCH_BINARY);
    for (const auto& a : args) cmd += " " + shellQuote(a);
    return runShell(cmd, cwd, captureDir, timeoutSeconds);
}

CliResult runShell(const std::string& command, const std::string& cwd, const std::string& captureDir,
                   int timeoutSeconds) {
    const std::string outFile = (fs::path(captureDir) / "cli_stdout.txt").string();
    const std::string errFile = (fs::path(captureDir) / "cli_stderr.txt").string();
    std::string cmd = "cd " + shellQuote(cwd) + " && timeout " + std::to_string(timeoutSeconds) + " " + command;
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

bool onPath(const std::string& program) {
    return std::system(("command -v " + shellQuote(program) + " >/dev/null 2>&1").c_str()) == 0;
}

int countOccurrences(const std::string& hay, const std::string& needle) {
    int n = 0;
    for (size_t p = hay.find(needle); p != std::string::npos; p = hay.find(needle, p + needle.size())) ++n;
    return n;
}

// ---------------------------------------------------------------------------
// Error messages

bool mentionsVec3(const std::string& msg, const std::string& x, const std::string& y, const std::string& z) {
    for (const std::string& form : {"[" + x + "," + y + "," + z + "]", x + ", " + y + ", " + z, x + " " + y + " " + z})
        if (msg.find(form) != std::string::npos) return true;
    return false;
}

bool hasNumberToken(const std::string& msg, const std::string& number) {
    std::regex re("(^|[^0-9.])" + std::regex_replace(number, std::regex(R"([.+\-])"), R"(\$&)") + "([^0-9]|$)");
    return std::regex_search(msg, re);
}

// ---------------------------------------------------------------------------
// Statistics

double chiSquareQ(double x, double dof) {
    double a = dof / 2, xx = x / 2;
    if (xx <= 0) return 1;
    double gln = std::lgamma(a);
    if (xx < a + 1) {
        double sum = 1 / a, del = sum, ap = a;
        for (int n = 0; n < 1000; ++n) {
            ap += 1;
            del *= xx / ap;
            sum += del;
            if (std::fabs(del) < std::fabs(sum) * 1e-14) break;
        }
        return 1 - sum * std::exp(-xx + a * std::log(xx) - gln);
    }
    double b = xx + 1 - a, c = 1e300, d = 1 / b, h = d;
    for (int i = 1; i < 1000; ++i) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::fabs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (std::fabs(c) < 1e-300) c = 1e-300;
        d = 1 / d;
        double del = d * c;
        h *= del;
        if (std::fabs(del - 1) < 1e-14) break;
    }
    return std::exp(-xx + a * std::log(xx) - gln) * h;
}

ChiSquare pooledChiSquare(const std::vector<double>& observed, const std::vector<double>& expected,
                          double minExpected) {
    ChiSquare r;
    double accO = 0, accE = 0;
    for (size_t b = 0; b < expected.size(); ++b) {
        accO += observed[b];
        accE += expected[b];
        if (accE >= minExpected || b + 1 == expected.size()) {
            if (accE > 0) {
                r.chi2 += (accO - accE) * (accO - accE) / accE;
                ++r.dof;
            } else if (accO > 0) {
                r.chi2 = std::numeric_limits<double>::infinity();  // samples where none can fall
            }
            accO = accE = 0;
        }
    }
    return r;
}

ChannelStats pixelStats(const Image& img, int channel) {
    SampleStats s;
    const size_t n = size_t(img.width) * size_t(img.height);
    for (size_t i = 0; i < n; ++i) s.add(img.rgba[4 * i + size_t(channel)]);
    return {s.mean(), s.stdError()};
}

double pairMse(const Image& a, const Image& b) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    double sum = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const double d = double(a.rgb(x, y)[c]) - double(b.rgb(x, y)[c]);
                sum += d * d;
            }
    return sum / (3.0 * a.width * a.height);
}

Image renderSampleToggled(const std::string& sample, std::vector<std::string> overrides, const std::string& toggle,
                          bool on, int seed) {
    overrides.push_back(toggle + (on ? "=true" : "=false"));
    overrides.push_back("render.seed=" + std::to_string(seed));
    return renderImage(*buildScene(loadSceneFile(samplePath(sample), overrides))).image;
}

void expectPairedAgreement(const Image& a, const Image& b, const std::string& what) {
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    const PairedAgreement p = pairedAgreement(b, a);
    for (int q = 0; q < PairedAgreement::Regions; ++q)
        for (int c = 0; c < 3; ++c)
            EXPECT_LE(std::abs(p.z[q][c]), 4.0) << what << " region " << q << " channel " << c;
}

std::vector<std::string> cloudSkyWithLightsAndGlass() {
    return {"camera.resolution=[32,24]", "render.max_depth=6", "environment.scale=0.3",
            R"(lights=[{"type": "point", "position": [0.05, 0.2, 0.0], "intensity": 0.6},
                       {"type": "spot", "position": [-1.2, 1.2, 0.5], "direction": [1, -0.9, -0.3], "cone_deg": 12,
                        "falloff_deg": 4, "intensity": 6},
                       {"type": "sphere", "position": [0.6, 0.7, -0.4], "radius": 0.05, "power": 8}])",
            R"(surfaces=[{"shape": "sphere", "transform": {"scale": 0.3, "translate": [0.6, 0.45, 1.2]},
                          "material": {"type": "dielectric", "ior": 1.5}}])"};
}

// ---------------------------------------------------------------------------
// Images

bool allFinite(const Image& img) {
    for (float v : img.rgba)
        if (!std::isfinite(v)) return false;
    return true;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

float maxAlpha(const Image& img) {
    float a = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) a = std::max(a, img.alpha(x, y));
    return a;
}

void expectBackgroundEverywhere(const Image& img, const Color& bg, float tol) {
    ASSERT_FALSE(img.empty());
    int bad = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            Color c = img.rgb(x, y);
            bool ok = std::fabs(c.x - bg.x) <= tol && std::fabs(c.y - bg.y) <= tol && std::fabs(c.z - bg.z) <= tol &&
                      img.alpha(x, y) == 0.f;
            if (!ok && bad++ < 3)
                ADD_FAILURE() << "pixel (" << x << ", " << y << ") = (" << c.x << ", " << c.y << ", " << c.z
                              << ", a=" << img.alpha(x, y) << "), expected background (" << bg.x << ", " << bg.y
                              << ", " << bg.z << ", a=0)";
        }
    EXPECT_EQ(bad, 0) << "pixels that are not the background";
}

void expectAllFinite(const RenderResult& r) {
    for (float v : r.image.rgba) ASSERT_TRUE(std::isfinite(v));
    EXPECT_EQ(r.counters.nonFiniteSamples, 0u);
}

// ---------------------------------------------------------------------------
// Scenes

std::unique_ptr<Scene> sceneFromJson(const std::string& json, const std::string& file) {
    return buildScene(parseSceneText(json, file));
}

std::string samplePath(const std::string& name) { return std::string(VDBMARCH_SOURCE_DIR) + "/vdb_samples/" + name; }
double environmentIrradianceByQuadrature(const Environment& env, const Vec3& n, float rotationDeg, int sub) {
    const double pi = 3.14159265358979323846, a = double(rotationDeg) * pi / 180;
    const int w = env.width() * sub, h = env.height() * sub;
    double sum = 0;
    for (int y = 0; y < h; ++y) {
        const double dOmega = 2 * pi / w * (std::cos(pi * y / h) - std::cos(pi * (y + 1) / h));
        for (int x = 0; x < w; ++x) {
            const Vec3 l = Environment::uvToDirection((x + 0.5f) / float(w), (y + 0.5f) / float(h));
            const Vec3 d(float(std::cos(a) * l.x + std::sin(a) * l.z), l.y, float(-std::sin(a) * l.x + std::cos(a) * l.z));
            sum += double(env.radiance(d).x) * std::max(0.0, double(dot(d, n))) * dOmega;
        }
    }
    return sum;
}

std::string sourcePath(const std::string& relative) { return std::string(VDBMARCH_SOURCE_DIR) + "/" + relative; }

std::string assetPath(const std::string& name) {
    return std::string(VDBMARCH_SOURCE_DIR) + "/../shared/assets/" + name;
}

std::string subst(std::string text, const std::vector<std::pair<std::string, std::string>>& pairs) {
    for (const auto& [key, value] : pairs) {
        const std::string k = "@" + key + "@";
        for (size_t p = text.find(k); p != std::string::npos; p = text.find(k, p + value.size()))
            text.replace(p, k.size(), value);
    }
    return text;
}

// ---------------------------------------------------------------------------
// VDB fixtures

namespace {

openvdb::Coord coord(const Index3& i) { return openvdb::Coord(i.x, i.y, i.z); }

openvdb::math::Transform::Ptr voxelTransform(double h) { return openvdb::math::Transform::createLinearTransform(h); }

openvdb::FloatGrid::Ptr boxGrid(const Index3& lo, const Index3& hi, float v, double h, const char* name) {
    initOpenVdb();
    auto grid = openvdb::FloatGrid::create(0.f);
    grid->setName(name);
    grid->setTransform(voxelTransform(h));
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->denseFill(openvdb::CoordBBox(coord(lo), coord(hi)), v, true);
    return grid;
}

void writeGrids(const std::string& path, openvdb::GridPtrVec grids) {
    openvdb::io::File f(path);
    f.write(grids);
    f.close();
}

openvdb::FloatGrid::Ptr blockGrid(const std::string& name, float value) {
    auto g = openvdb::FloatGrid::create(0.f);
    g->setName(name);
    g->setTransform(voxelTransform(kVoxel));
    g->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto acc = g->getAccessor();
    for (int x = kBlockLo; x <= kBlockHi; ++x)
        for (int y = kBlockLo; y <= kBlockHi; ++y)
            for (int z = kBlockLo; z <= kBlockHi; ++z) acc.setValueOn(openvdb::Coord(x, y, z), value);
    return g;
}

openvdb::FloatGrid::Ptr emptyGrid(const std::string& name) {
    auto g = openvdb::FloatGrid::create(0.f);
    g->setName(name);
    g->setTransform(voxelTransform(kVoxel));
    return g;
}

}  // namespace

std::string writeBoxGrid(const std::string& path, const Index3& lo, const Index3& hi, float v, double h,
                         const char* name, const std::vector<Index3>& extra) {
    auto grid = boxGrid(lo, hi, v, h, name);
    for (const Index3& i : extra) grid->tree().setValue(coord(i), v);
    writeGrids(path, {grid});
    return path;
}

std::string writeEmissiveBox(const std::string& path) { return writeEmissiveBox(path, 0, 19, 4, 0.05); }

std::string writeEmissiveBox(const std::string& path, const Index3& lo, const Index3& hi, int margin, double h) {
    const Index3 tlo(lo.x - margin, lo.y - margin, lo.z - margin), thi(hi.x + margin, hi.y + margin, hi.z + margin);
    writeGrids(path, {boxGrid(lo, hi, 1.f, h, "density"), boxGrid(tlo, thi, 1.f, h, "temperature")});
    return path;
}

std::string writeTemperatureRamp(const std::string& path, const Index3& lo, const Index3& hi, int margin, double h,
                                 float t0, float dt) {
    auto temperature = boxGrid(Index3(lo.x - margin, lo.y - margin, lo.z - margin),
                               Index3(hi.x + margin, hi.y + margin, hi.z + margin), 1.f, h, "temperature");
    for (auto it = temperature->tree().beginValueOn(); it; ++it)
        it.setValue(t0 + dt * float(it.getCoord().x() - lo.x + margin));
    writeGrids(path, {boxGrid(lo, hi, 1.f, h, "density"), temperature});
    return path;
}

void writeVdbFixtures(const std::string& dir) {
    initOpenVdb();
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();

    auto density = blockGrid("density", 1.f);

    auto vel = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.f));
    vel->setName("vel");
    vel->setTransform(voxelTransform(kVoxel));
    {
        auto acc = vel->getAccessor();
        for (int x = 0; x < 3; ++x) acc.setValueOn(openvdb::Coord(x, 0, 0), openvdb::Vec3s(1.f, 0.f, 0.f));
    }

    auto bad = blockGrid("bad", 1.f);
    {
        auto acc = bad->getAccessor();
        acc.setValueOn(openvdb::Coord(-2, -2, -2), nan);
        acc.setValueOn(openvdb::Coord(1, 1, 1), nan);
        acc.setValueOn(openvdb::Coord(0, 0, 0), inf);
        acc.setValueOn(openvdb::Coord(-1, 0, 0), -inf);
        acc.setValueOn(openvdb::Coord(0, -1, 0), -0.5f);
        acc.setValueOn(openvdb::Coord(0, 0, -1), -3.f);
    }

    writeGrids((fs::path(dir) / "grids.vdb").string(), {density, vel, bad, emptyGrid("empty")});
    writeGrids((fs::path(dir) / "empty_only.vdb").string(), {emptyGrid("density")});
    writeGrids((fs::path(dir) / "vel_only.vdb").string(), {vel});
    writeText((fs::path(dir) / "not_a_vdb.vdb").string(), "this is a text file, not an OpenVDB volume\n");
}

// ---------------------------------------------------------------------------
// Bad input

const char* const kVdbScene = R"({
  "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_deg": 40, "resolution": [8, 8]},
  "lights": [{"type": "directional", "direction": [0.3, -1, -0.2], "irradiance": 2}],
  "media": [{"name": "smoke", "type": "vdb", "file": "@FILE@", "grid": "@GRID@", "sigma_a": 0.5, "sigma_s": 2}],
  "background": [0.25, 0.5, 0.75],
  "render": {"spp": 1, "seed": 7}
}
)";

const char* const kHomogeneousScene = R"({
  "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "resolution": [8, 8]@CAMERA@},
  "media": [{"name": "fog", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 0.5@MEDIUM@,
             "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
  "render": {"spp": 1}
}
)";

std::string vdbScene(const std::string& grid, const std::string& file) {
    return subst(kVdbScene, {{"GRID", grid}, {"FILE", file}});
}

std::string homogeneousScene(const std::string& mediumExtra, const std::string& cameraExtra) {
    return subst(kHomogeneousScene, {{"MEDIUM", mediumExtra}, {"CAMERA", cameraExtra}});
}

void BadInput::SetUp() {
    setWarningsQuiet(true);
    mWork = mRoot / "work";
    fs::create_directory(mWork);
    writeVdbFixtures(mWork);
}

void BadInput::TearDown() { setWarningsQuiet(false); }

std::string BadInput::scene(const std::string& name, const std::string& text) const {
    std::string p = work(name);
    writeText(p, text);
    return p;
}

CliResult BadInput::cli(const std::vector<std::string>& args, int timeoutSeconds) const {
    return runCli(args, mWork, mRoot.path(), timeoutSeconds);
}

void BadInput::expectCliError(const CliResult& r, const std::vector<std::string>& needles) {
    EXPECT_EQ(r.exitCode, 1) << "stderr: " << r.err;
    EXPECT_EQ(r.err.rfind("vdbmarch: error: ", 0), 0u) << "stderr: " << r.err;
    EXPECT_EQ(countOccurrences(r.err, "vdbmarch: error: "), 1) << "stderr: " << r.err;
    for (const auto& n : needles) EXPECT_CONTAINS(r.err, n);
}

// ---------------------------------------------------------------------------
// Lights

LightDesc pointLight(const Vec3& p, const Color& intensity) {
    LightDesc d;
    d.type = LightDesc::Type::Point;
    d.position = p;
    d.intensity = intensity;
    return d;
}

LightDesc spotLight(const Vec3& p, const Vec3& dir, float coneDeg, float falloffDeg, const Color& intensity) {
    LightDesc d;
    d.type = LightDesc::Type::Spot;
    d.position = p;
    d.direction = normalize(dir);
    d.coneDeg = coneDeg;
    d.falloffDeg = falloffDeg;
    d.intensity = intensity;
    return d;
}

LightDesc directionalLight(const Vec3& dir, const Color& irradiance) {
    LightDesc d;
    d.type = LightDesc::Type::Directional;
    d.direction = normalize(dir);
    d.irradiance = irradiance;
    return d;
}

LightDesc quadLight(const Vec3& c, const Vec3& u, const Vec3& v, const Vec3& dir, const Color& irradiance) {
    LightDesc d;
    d.type = LightDesc::Type::CollimatedQuad;
    d.center = c;
    d.u = u;
    d.v = v;
    d.direction = normalize(dir);
    d.irradiance = irradiance;
    return d;
}

LightDesc sphereLight(const Vec3& p, float radius, const Color& power) {
    LightDesc d;
    d.type = LightDesc::Type::Sphere;
    d.position = p;
    d.radius = radius;
    d.power = power;
    return d;
}

// ---------------------------------------------------------------------------
// Methods

std::string methodParamName(const ::testing::TestParamInfo<Method>& info) { return methodName(info.param); }

std::string methodOverride(Method m) { return str("render.method=\"", methodName(m), "\""); }

void writeIcosahedron(const std::string& path) {
    const float t = (1 + std::sqrt(5.f)) / 2;
    const float v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    const int f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                          {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                          {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    std::ofstream out(path);
    for (const auto& p : v) out << "v " << p[0] / 1.902f << " " << p[1] / 1.902f << " " << p[2] / 1.902f << "\n";
    for (const auto& t3 : f) out << "f " << t3[0] + 1 << " " << t3[1] + 1 << " " << t3[2] + 1 << "\n";
}

GlassSphere figure4Ball() {
    GlassSphere s;
    s.center = Vec3(0.f, 0.75f, 0.f);
    s.radius = 0.45f;
    s.ior = 1.5f;
    return s;
}

std::unique_ptr<Scene> glassInWhiteFog(const std::string& method, bool glassSplitting) {
    return sceneFromJson(str(R"({"camera": {"position": [0.3, 0.4, 4], "look_at": [0, 0, 0], "fov_deg": 45,
        "resolution": [16, 16]},
        "media": [{"name": "fog", "type": "homogeneous", "sigma_a": 0, "sigma_s": 0.8,
                   "bounds": {"min": [-2, -2, -2], "max": [2, 2, 2]}}],
        "surfaces": [{"shape": "sphere", "transform": {"scale": [1, 0.7, 0.9]}, "material": {"type": "dielectric", "ior": 1.5}},
                     {"shape": "box", "transform": {"scale": 0.8, "rotate": [1, 1, 0, 30], "translate": [0.6, 0.3, 1]},
                      "material": {"type": "dielectric", "ior": 2.4}}],
        "background": [1, 1, 1], "photons": {"count": 20000},
        "render": {"method": ")", method, R"(", "spp": 64, "max_depth": 1000, "max_surface_bounces": 1000, "seed": 5},
        "experiments": {"glass_splitting": )", glassSplitting ? "true" : "false", "}}"));
}

}  // namespace vdbmarch::test
