// The radiance cache: eq. 27 at the cell centres equals the photon map's
// eq. 4 with the truncated Legendre series of the phase function; the grid
// rule; the adaptive hierarchy's lookups; isotropic and non-scattering
// media; and the .vdb file: round trip, and clear errors for truncated,
// corrupted, foreign and other-scene files.
#include <gtest/gtest.h>

#include <cmath>

#include <openvdb/openvdb.h>

#include "cache/cache_build.h"
#include "cache/sh.h"
#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "illumination/bake.h"
#include "support/support.h"
#include "transport/phase.h"

namespace vdbmarch {
namespace {

using namespace test;

std::string spotScene(float g, bool adaptive) {
    return str(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
        "lights": [{"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "intensity": [20, 20, 20],
                    "cone_deg": 8, "falloff_deg": 2}],
        "media": [{"name": "m", "type": "homogeneous", "sigma_a": [0.1, 0.1, 0.1], "sigma_s": [1, 1, 1],
                   "g": )", g, R"(, "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
        "photons": {"count": 60000, "k": 40},
        "cache": {"sh_order": 3, "quality": 1, "adaptive": )", adaptive ? "true" : "false", R"(},
        "render": {"max_depth": 2, "seed": 1}})");
}

BakeResult bake(const Scene& s) { return bakeRadianceCache(s, s.desc.photons, s.desc.cache); }

TEST(RadianceCache, CoefficientsAreEq27OfTheNearestPhotons) {
    auto scene = sceneFromJson(spotScene(0.7f, false));
    BakeResult r = bake(*scene);
    const RadianceCache& c = r.cache;
    ASSERT_EQ(c.info.shOrder, 3);
    ASSERT_GT(c.cells.size(), 100u);
    const int K = c.info.shOrder;
    const float g = 0.7f;
    // Truncated Legendre series of HG: what eq. 27 keeps of the phase function.
    auto truncated = [&](float cosTheta) {
        double P[MaxShOrder + 1];
        legendrePolynomials(K, cosTheta, P);
        double p = 0;
        for (int l = 0; l <= K; ++l) p += (2 * l + 1) / (4 * M_PI) * std::pow(g, l) * P[l];
        return Color(float(p));
    };
    float Y[shCount(MaxShOrder)];
    Rng rng(3);
    int checked = 0;
    for (size_t cell = 0; cell < c.cells.size(); cell += c.cells.size() / 40) {
        Vec3 wo = sampleUniformSphere(rng.uniform(), rng.uniform());
        evalSh(K, wo, Y);
        float cached = evalShSum(c.coefficientCount(), c.cellCoefficients(cell), Y);
        float direct = average(r.photons->estimateLi(c.cellCenter(c.cells[cell]), wo, size_t(c.info.k), truncated));
        // Float rounding relative to the largest the sum can be: the
        // truncated phase is at most sum_l (2l+1) g^l / (4 pi) < 1, so each
        // term is below 4 pi times the cell's mean f_00 Y_00.
        float bound = 4 * Pi * c.cellCoefficients(cell)[0] * 0.2820948f;
        EXPECT_NEAR(cached, direct, 1e-5f * bound) << "cell " << cell;
        ++checked;
    }
    EXPECT_GE(checked, 40);
}

TEST(RadianceCache, OverlappingMediaProjectTheirMixturesLegendreWeights) {
    // Two media with different g fill the same box: the phase at a point is
    // the sigma_s-weighted mixture, whose eq. 26 weights are
    // sum_i w_i g_i^l, not the powers of its mean g. The expected truncated
    // series takes w'_l = 2 pi Int p(u) P_l(u) du of the mixture by
    // quadrature, independently of the code under test.
    auto scene = sceneFromJson(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
        "lights": [{"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "intensity": [20, 20, 20],
                    "cone_deg": 12, "falloff_deg": 2}],
        "media": [{"name": "fwd", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 1.0, "g": 0.8,
                   "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}},
                  {"name": "back", "type": "homogeneous", "sigma_a": 0.1, "sigma_s": 0.6, "g": -0.3,
                   "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}],
        "photons": {"count": 60000, "k": 40},
        "cache": {"sh_order": 3, "quality": 1},
        "render": {"max_depth": 2, "seed": 1}})");
    BakeResult r = bake(*scene);
    const RadianceCache& c = r.cache;
    ASSERT_EQ(c.info.shOrder, 3);
    const int K = c.info.shOrder;
    auto mixture = [](double u) { return (1.0 * hgPhase(float(u), 0.8f) + 0.6 * hgPhase(float(u), -0.3f)) / 1.6; };
    double w[MaxShOrder + 1];
    for (int l = 0; l <= K; ++l) {
        const int n = 200000;  // composite Simpson over u in [-1, 1]
        double sum = 0, P[MaxShOrder + 1];
        for (int i = 0; i <= n; ++i) {
            const double u = -1 + 2.0 * i / n;
            legendrePolynomials(K, u, P);
            sum += (i == 0 || i == n ? 1 : (i % 2 ? 4 : 2)) * mixture(u) * P[l];
        }
        w[l] = 2 * M_PI * sum * (2.0 / n) / 3;
    }
    ASSERT_GT(std::fabs(w[2] - w[1] * w[1]), 0.1);  // the mean g's powers are far off
    auto truncated = [&](float cosTheta) {
        double P[MaxShOrder + 1];
        legendrePolynomials(K, cosTheta, P);
        double p = 0;
        for (int l = 0; l <= K; ++l) p += (2 * l + 1) / (4 * M_PI) * w[l] * P[l];
        return Color(float(p));
    };
    float Y[shCount(MaxShOrder)];
    Rng rng(5);
    int checked = 0;
    for (size_t cell = 0; cell < c.cells.size(); ++cell) {
        const Vec3 x = c.cellCenter(c.cells[cell]);
        if (!(std::fabs(x.x) < 1 && std::fabs(x.y) < 1 && std::fabs(x.z) < 1)) continue;  // centres in both media
        if (rng.uniform() > 0.1f) continue;
        Vec3 wo = sampleUniformSphere(rng.uniform(), rng.uniform());
        evalSh(K, wo, Y);
        float cached = evalShSum(c.coefficientCount(), c.cellCoefficients(cell), Y);
        float direct = average(r.photons->estimateLi(x, wo, size_t(c.info.k), truncated));
        float bound = 4 * Pi * c.cellCoefficients(cell)[0] * 0.2820948f;  // float rounding, as above
        EXPECT_NEAR(cached, direct, 2e-5f * bound + 1e-6f * std::fabs(direct)) << "cell " << cell;
        ++checked;
    }
    EXPECT_GE(checked, 30);
}

TEST(RadianceCache, UniformGridFollowsThePapersRule) {
    auto scene = sceneFromJson(spotScene(0.f, false));
    BakeResult r = bake(*scene);
    const RadianceCache& c = r.cache;
    // s = (a N / (k V))^(1/3) on the medium's volume V = 8: the cells cover
    // the box, so their count is about a N / k (up to the partial cells).
    double expected = std::cbrt(40.0 * 8 / (1.0 * double(c.info.photons)));
    EXPECT_NEAR(c.baseCell, expected, 0.15 * expected);
    double cellsPerPhoton = double(c.cells.size()) * 40 / double(c.info.photons);
    EXPECT_GT(cellsPerPhoton, 0.7);
    EXPECT_LT(cellsPerPhoton, 2.0);
}

TEST(RadianceCache, IsotropicMediaStoreOneCoefficient) {
    auto scene = sceneFromJson(spotScene(0.f, false));
    BakeResult r = bake(*scene);
    EXPECT_EQ(r.cache.info.shOrder, 0);
    EXPECT_EQ(r.cache.info.requestedOrder, 3);
    EXPECT_EQ(r.cache.coefficientCount(), 1);
    EXPECT_EQ(r.cache.coefficients.size(), r.cache.cells.size());
}

TEST(RadianceCache, NonScatteringSceneHasNothingToBake) {
    auto scene = sceneFromJson(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
        "lights": [{"type": "point", "position": [0, 3, 0], "intensity": [1, 1, 1]}],
        "media": [{"name": "m", "type": "homogeneous", "sigma_a": [1, 1, 1], "sigma_s": [0, 0, 0],
                   "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]}}]})");
    EXPECT_CONTAINS(errorOf<InputError>([&] { bake(*scene); }), "no medium scatters");
}

TEST(RadianceCache, AdaptiveCellsTileSpaceAndRefineWherePhotonsAreDense) {
    auto scene = sceneFromJson(spotScene(0.7f, true));
    BakeResult r = bake(*scene);
    const RadianceCache& c = r.cache;
    ASSERT_GT(c.levels, 2);
    EXPECT_GT(c.cellsAtLevel(c.levels - 1), 0u);  // the beam is refined to the finest level
    EXPECT_GT(c.cellsAtLevel(0), 0u);              // the dark corners stay coarse
    // Every cell is found at its own centre (no finer cell hides it), and
    // points anywhere in the medium find a cell that contains them.
    RadianceCache::Query q(c);
    for (size_t i = 0; i < c.cells.size(); ++i) ASSERT_EQ(q.find(c.cellCenter(c.cells[i])), int64_t(i));
    Rng rng(5);
    for (int i = 0; i < 20000; ++i) {
        Vec3 p(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
        int64_t cell = q.find(p);
        ASSERT_GE(cell, 0);
        const CacheCell& cc = c.cells[size_t(cell)];
        Vec3 d = p - c.cellCenter(cc);
        float h = c.cellSize(cc.level) * 0.5f * 1.0001f;
        ASSERT_TRUE(std::fabs(d.x) <= h && std::fabs(d.y) <= h && std::fabs(d.z) <= h);
    }
    // Cells on the beam axis are finer than cells in the corners.
    int64_t axis = q.find(Vec3(0, 0.5f, 0)), corner = q.find(Vec3(-0.95f, -0.95f, -0.95f));
    EXPECT_GT(c.cells[size_t(axis)].level, c.cells[size_t(corner)].level);
}

// Section 3.4 / figure 4: where strong radiance fills a small region, the
// adaptive cache resolves it better than a uniform cache of the same memory.
// Truth is single scattering from the spot in closed form (max_depth 1: every
// photon is direct) with the truncated Legendre phase that eq. 27 keeps, so
// the error measured is the cache's spatial error (blur and noise) alone.
// Figures for BENCHMARKS.md: VDBMARCH_VERBOSE=1 vdbmarch_accuracy_tests
// --gtest_filter='*EqualStorage*'.
struct CacheError {
    double relL2 = 0, beamRelL2 = 0;  // sqrt(sum (cached - truth)^2 / sum truth^2)
    size_t cells = 0, bytes = 0;
};

CacheError cacheError(const Scene& scene, const RadianceCache& c, float g) {
    const int K = c.info.shOrder;
    const Light& light = scene.lights[0];
    const float sigmaT = 1.1f;
    auto truth = [&](const Vec3& x, const Vec3& wo) {
        LightSample ls;
        if (!light.sample(x, 0.5f, 0.5f, ls)) return 0.0;
        float inside = (1 - x.y) / ls.wi.y;  // the path to the light leaves the box at y = 1
        double P[MaxShOrder + 1];
        legendrePolynomials(K, dot(-ls.wi, wo), P);
        double p = 0;
        for (int l = 0; l <= K; ++l) p += (2 * l + 1) / (4 * M_PI) * std::pow(g, l) * P[l];
        return p * double(average(ls.L)) * std::exp(-sigmaT * inside);
    };
    RadianceCache::Query q(c);
    float Y[shCount(MaxShOrder)];
    Rng rng(11);
    double se = 0, s2 = 0, beamSe = 0, beamS2 = 0;
    for (int i = 0; i < 200000; ++i) {
        Vec3 x(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
        Vec3 wo = sampleUniformSphere(rng.uniform(), rng.uniform());
        double t = truth(x, wo);
        int64_t cell = q.find(x);
        evalSh(K, wo, Y);
        double cached = cell < 0 ? 0.0 : evalShSum(c.coefficientCount(), c.cellCoefficients(size_t(cell)), Y);
        se += (cached - t) * (cached - t);
        s2 += t * t;
        // The beam's edge: between 0.7 and 1.3 cone radii (8 degrees) from the axis.
        float r = std::sqrt(x.x * x.x + x.z * x.z) / ((3 - x.y) * std::tan(8 * Pi / 180));
        if (r > 0.7f && r < 1.3f) {
            beamSe += (cached - t) * (cached - t);
            beamS2 += t * t;
        }
    }
    CacheError e;
    e.relL2 = std::sqrt(se / s2);
    e.beamRelL2 = std::sqrt(beamSe / beamS2);
    e.cells = c.cells.size();
    e.bytes = c.memoryBytes();
    return e;
}

// A uniform cache from the same photons whose cell count (or, with `bytes`,
// memory including the VDB index) matches `target`, by bisection on quality a.
RadianceCache matchedUniformCache(const Scene& scene, const BakeResult& r, int k, size_t target, bool bytes) {
    CacheSettings us = scene.desc.cache;
    us.adaptive = false;
    float lo = 0.01f, hi = 100.f;
    RadianceCache best;
    double bestGap = 1e30;
    for (int it = 0; it < 16; ++it) {
        us.quality = std::sqrt(lo * hi);
        RadianceCache c = buildRadianceCache(scene, *r.photons, r.paths, us, k);
        size_t size = bytes ? c.memoryBytes() : c.cells.size();
        double gap = std::fabs(std::log(double(size) / double(target)));
        if (gap < bestGap) bestGap = gap, best = std::move(c);
        (size < target ? lo : hi) = us.quality;
    }
    return best;
}

TEST(RadianceCache, AdaptiveIsMoreAccurateThanUniformAtEqualStorage) {
    const float g = 0.7f;
    std::string json = spotScene(g, true);
    json.replace(json.find("\"max_depth\": 2"), 14, "\"max_depth\": 1");
    auto scene = sceneFromJson(json);
    // VDBMARCH_VERBOSE adds a larger photon map for the benchmark table.
    std::vector<int64_t> counts{30000, 120000};
    if (std::getenv("VDBMARCH_VERBOSE")) counts.push_back(480000);
    for (int64_t photons : counts) {
        PhotonSettings ps = scene->desc.photons;
        ps.count = photons;
        BakeResult r = bakeRadianceCache(*scene, ps, scene->desc.cache);
        ASSERT_TRUE(r.cache.info.adaptive);
        ASSERT_EQ(r.directPhotons, r.photons->size());
        CacheError adaptive = cacheError(*scene, r.cache, g);
        CacheError sameCells = cacheError(*scene, matchedUniformCache(*scene, r, ps.k, adaptive.cells, false), g);
        CacheError sameBytes = cacheError(*scene, matchedUniformCache(*scene, r, ps.k, adaptive.bytes, true), g);
        EXPECT_NEAR(double(sameCells.cells), double(adaptive.cells), 0.1 * double(adaptive.cells));
        EXPECT_LT(adaptive.relL2, sameCells.relL2) << photons << " photon paths";
        EXPECT_LT(adaptive.beamRelL2, sameCells.beamRelL2) << photons << " photon paths";
        // Also when the uniform cache gets the adaptive one's whole memory,
        // the fixed cost of its five VDB index trees included.
        EXPECT_LT(adaptive.relL2, sameBytes.relL2) << photons << " photon paths";
        if (std::getenv("VDBMARCH_VERBOSE"))
            std::printf("%lld paths | adaptive: %zu cells %zu KB, rel. L2 %.3f, edge %.3f, %d levels"
                        " | uniform, same cells: %zu cells %zu KB, %.3f, edge %.3f"
                        " | uniform, same bytes: %zu cells %zu KB, %.3f, edge %.3f\n",
                        (long long)photons, adaptive.cells, adaptive.bytes / 1024, adaptive.relL2,
                        adaptive.beamRelL2, r.cache.levels, sameCells.cells, sameCells.bytes / 1024, sameCells.relL2,
                        sameCells.beamRelL2, sameBytes.cells, sameBytes.bytes / 1024, sameBytes.relL2,
                        sameBytes.beamRelL2);
    }
}

// photons.seed seeds photon tracing alone: the same cache as render.seed of
// that value, whatever render.seed is.
TEST(RadianceCache, PhotonSeedOverridesTheRenderSeed) {
    std::string a = spotScene(0.7f, false), b = a;
    a.replace(a.find("\"seed\": 1"), 9, "\"seed\": 9");
    b.replace(b.find("\"count\": 60000"), 14, "\"count\": 60000, \"seed\": 9");
    auto sa = sceneFromJson(a), sb = sceneFromJson(b);
    EXPECT_EQ(sb->desc.photons.seedFor(sb->desc.render.seed), 9u);
    BakeResult ra = bake(*sa), rb = bake(*sb), r1 = bake(*sceneFromJson(spotScene(0.7f, false)));
    ASSERT_EQ(ra.cache.coefficients.size(), rb.cache.coefficients.size());
    EXPECT_EQ(ra.cache.coefficients, rb.cache.coefficients);
    EXPECT_NE(ra.cache.coefficients, r1.cache.coefficients);
}

TEST(RadianceCacheFile, RoundTripKeepsEveryCellAndCoefficient) {
    for (bool adaptive : {false, true}) {
        auto scene = sceneFromJson(spotScene(0.7f, adaptive));
        BakeResult r = bake(*scene);
        TempDir dir("cache");
        std::string path = dir / str("roundtrip", adaptive, ".vdb");
        r.cache.save(path);
        RadianceCache back = RadianceCache::load(path);
        ASSERT_EQ(back.cells.size(), r.cache.cells.size());
        EXPECT_EQ(back.levels, r.cache.levels);
        EXPECT_EQ(back.info.sceneHash, r.cache.info.sceneHash);
        EXPECT_EQ(back.info.photons, r.cache.info.photons);
        RadianceCache::Query q(back);
        for (size_t i = 0; i < r.cache.cells.size(); ++i) {
            int64_t j = q.find(r.cache.cellCenter(r.cache.cells[i]));
            ASSERT_GE(j, 0);
            for (int k = 0; k < r.cache.coefficientCount(); ++k)
                ASSERT_EQ(back.cellCoefficients(size_t(j))[k], r.cache.cellCoefficients(i)[k]);
        }
        EXPECT_NO_THROW(checkCacheMatchesScene(back, *scene, path, false));
    }
}

void expectInputError(const std::string& path, const std::string& fragment) {
    expectErrorContaining<InputError>([&] { RadianceCache::load(path); }, {path, fragment});
}

TEST(RadianceCacheFile, RefusesAnotherScene) {
    auto scene = sceneFromJson(spotScene(0.7f, false));
    BakeResult r = bake(*scene);
    auto other = sceneFromJson(spotScene(0.5f, false));
    expectErrorContaining<InputError>([&] { checkCacheMatchesScene(r.cache, *other, "c.vdb", false); },
                                      {"another scene", "--force"});
    setWarningsQuiet(true);
    EXPECT_NO_THROW(checkCacheMatchesScene(r.cache, *other, "c.vdb", true));
    setWarningsQuiet(false);
    // The camera and render settings do not change the light field.
    std::string moved = spotScene(0.7f, false);
    moved.replace(moved.find("[0, 0, 5]"), 9, "[1, 2, 6]");
    EXPECT_NO_THROW(checkCacheMatchesScene(r.cache, *sceneFromJson(moved), "c.vdb", false));
}

TEST(RadianceCacheFile, TruncatedOrCorruptedFilesFailCleanly) {
    setWarningsQuiet(true);  // truncated files lose their checksum trailer
    auto scene = sceneFromJson(spotScene(0.7f, true));
    BakeResult r = bake(*scene);
    TempDir dir("cache");
    std::string good = dir / "good.vdb";
    r.cache.save(good);
    const std::string bytes = readBytes(good);
    ASSERT_GT(bytes.size(), 1000u);
    // Truncations at many lengths, and bytes overwritten with garbage: each
    // is an InputError naming the file (the checksum trailer catches the
    // damage before OpenVDB parses it), never a crash.
    Rng rng(11);
    for (int trial = 0; trial < 24; ++trial) {
        std::string damaged = bytes;
        if (trial < 12) {
            damaged.resize(size_t(double(bytes.size()) * (trial + 0.5) / 12.5));
        } else {
            size_t at = size_t(rng.uniform() * float(bytes.size() - 64));
            for (size_t i = 0; i < 32; ++i) damaged[at + i] = char(rng.next() & 0xff);
        }
        std::string path = dir.write(str("damaged", trial, ".vdb"), damaged);
        SCOPED_TRACE(str("trial ", trial));
        EXPECT_CONTAINS(errorOf<InputError>([&] { RadianceCache::load(path); }), path);
    }
    std::string missing = dir / "does_not_exist.vdb";
    EXPECT_THROW(RadianceCache::load(missing), IoError);
    // A VDB that is not a cache (a density grid), and a cache of another format version.
    std::string density = writeBoxGrid(dir / "density.vdb", 0, 3, 1.f, 0.1);
    expectInputError(density, "not a vdbmarch cache");
    openvdb::io::File file(good);
    file.open();
    openvdb::GridPtrVecPtr grids = file.getGrids();
    file.close();
    for (auto& g : *grids) g->insertMeta("vdbmarch_cache_version", openvdb::Int32Metadata(99));
    std::string future = dir / "future.vdb";
    openvdb::io::File(future).write(*grids);
    expectInputError(future, "version 99");
    setWarningsQuiet(false);
}

}  // namespace
}  // namespace vdbmarch
