// Free-flight sampling and shadow transmittance through a heterogeneous VDB
// grid whose optical depth has a closed form. The test writes a grid that is
// constant in index y and z and piecewise linear in x (a constant slab, a
// ramp down, an empty gap, a thin slab), so along any ray that stays inside
// the y-z extent the trilinear density is the piecewise-linear interpolant
// of the x profile, and tau(t) = k x density_scale x (h / d_x) x (F(x(t)) -
// F(x(0))), F the exact integral of that interpolant (trapezoids between
// knots, a quadratic inside a cell). Against it:
//  - delta tracking (deltaTrack, accepting a tentative collision with
//    probability sigma_t(x) / sigma_maj) puts its first real collision at
//    density sigma_t(t) exp(-tau(t)): chi-square over bins whose expected
//    counts are N (exp(-tau(a)) - exp(-tau(b))), the "no collision" outcome
//    among them with probability exp(-tau(tEnd)); and sigma_t never exceeds
//    the majorant at a tentative collision;
//  - ratio tracking and unbiased ray marching (regionTransmittance) have
//    mean exp(-tau) per colour channel within 4 standard errors, ratio
//    tracking's estimates in [0, 1]; shadowTransmittance over a distance
//    (or to infinity) agrees the same way.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "core/rng.h"
#include "support/support.h"
#include "transport/thread_context.h"
#include "transport/tracking.h"
#include "transport/transmittance.h"
#include "volume/medium.h"

namespace vdbmarch {
namespace {

using namespace test;

// Index -> world: x_w = h i + X0 (the same for y, z with their offsets).
constexpr double kH = 1.0 / 16;
const openvdb::Vec3d kOrigin(-1.5, -0.5, -0.25);
constexpr int kYLo = -8, kYHi = 15;  // y and z extent of every column
constexpr float kDensityScale = 0.75f;

// Value of the voxels at index x = i (any y, z in [kYLo, kYHi]); 0 outside.
double profile(int i) {
    if (i >= 0 && i <= 15) return 2.0;                       // two blocks of 2
    if (i >= 16 && i <= 31) return 2.0 - 0.1 * (i - 15);     // a ramp down to 0.4
    if (i >= 40 && i <= 47) return 0.5;                      // after an empty gap, a thin slab
    return 0.0;
}

// Integral of the piecewise-linear interpolant of profile() from -inf to x
// (index units): whole cells by the trapezoid rule, the last part exactly.
double cumulative(double x) {
    const int lo = -2;
    if (x <= lo) return 0;
    const int i0 = int(std::floor(x));
    double sum = 0;
    for (int i = lo; i < i0; ++i) sum += 0.5 * (profile(i) + profile(i + 1));
    const double s = x - i0, a = profile(i0), b = profile(i0 + 1);
    return sum + a * s + 0.5 * (b - a) * s * s;
}

void writeProfileGrid(const std::string& path) {
    initOpenVdb();
    auto g = openvdb::FloatGrid::create(0.f);
    g->setName("density");
    g->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto xf = openvdb::math::Transform::createLinearTransform(kH);
    xf->postTranslate(kOrigin);
    g->setTransform(xf);
    auto acc = g->getAccessor();
    for (int i = 0; i <= 47; ++i) {
        const float v = float(profile(i));
        if (v == 0) continue;
        for (int y = kYLo; y <= kYHi; ++y)
            for (int z = kYLo; z <= kYHi; ++z) acc.setValueOn(openvdb::Coord(i, y, z), v);
    }
    openvdb::io::File f(path);
    f.write({g});
    f.close();
}

// sigma_a differs per channel, so each channel has its own depth.
const char* const kScene = R"({
  "camera": {"position": [0, 0, 10], "look_at": [0, 0, 0], "resolution": [8, 8]},
  "media": [{"name": "profile", "type": "vdb", "file": "@FILE@", "density_scale": 0.75,
             "sigma_a": [0.2, 0.5, 0.05], "sigma_s": 0.6}],
  "render": {"spp": 1}
})";

struct Fixture {
    TempDir dir{"tracking"};
    std::unique_ptr<Scene> scene;
    Color k;  // sigma_t per channel
    Fixture() {
        const std::string grid = dir / "profile.vdb";
        writeProfileGrid(grid);
        scene = sceneFromJson(subst(kScene, {{"FILE", grid}}), dir / "scene.json");
        const Medium& m = *scene->media[0];
        k = m.sigma_a + m.sigma_s;
    }
};

Vec3 world(double ix, double iy, double iz) {
    return Vec3(float(kH * ix + kOrigin.x()), float(kH * iy + kOrigin.y()), float(kH * iz + kOrigin.z()));
}

// A ray given in index coordinates (the transform is a uniform scale, so
// directions are the same in world space), with its end.
struct ProfileRay {
    Ray ray;
    float tEnd;
    std::string name;
    // Index x of the world point at t.
    double x(double t) const { return (double(ray.o.x) + double(ray.d.x) * t - kOrigin.x()) / kH; }
    // Integral of the density (grid value x density_scale) over [0, t].
    double depth(double t) const {
        return kDensityScale * kH / double(ray.d.x) * (cumulative(x(t)) - cumulative(x(0)));
    }
};

std::vector<ProfileRay> profileRays() {
    std::vector<ProfileRay> rays;
    // Through everything along +x.
    rays.push_back({Ray{world(-4, 3.3, 4.6), Vec3(1, 0, 0)}, float(55 * kH), "+x, through all"});
    // Along -x, ending inside the first slab.
    rays.push_back({Ray{world(51, -2.7, 9.2), Vec3(-1, 0, 0)}, float((51 - 10.4) * kH), "-x, ending in the slab"});
    // Obliquely: y rises by 13 and z falls by 10.4 over the 52 voxels in x,
    // staying inside the columns' y-z extent; ends in the gap.
    const Vec3 d = normalize(Vec3(1, 0.25f, -0.2f));
    rays.push_back({Ray{world(-3, 0.1, 8.3), d}, float(38.5 * kH / d.x), "oblique, ending in the gap"});
    return rays;
}

TEST(Tracking, ProfileDepthHasTheClosedFormAlongTheTestRays) {
    // The closed form itself against the medium: a fine midpoint rule over
    // the medium's own density (guards the geometry of the rays above).
    Fixture f;
    ThreadContext ctx(*f.scene);
    MediumQuery& q = *ctx.queries[0];
    for (const ProfileRay& pr : profileRays()) {
        const int n = 200000;
        double sum = 0;
        for (int j = 0; j < n; ++j) sum += q.density(pr.ray.at((j + 0.5) * double(pr.tEnd) / n));
        sum *= double(pr.tEnd) / n;
        EXPECT_NEAR(sum, pr.depth(pr.tEnd), 1e-4 * pr.depth(pr.tEnd)) << pr.name;
        EXPECT_GT(pr.depth(pr.tEnd), 1.5) << pr.name;
    }
}

TEST(Tracking, DeltaTrackingFirstCollisionFollowsSigmaTTimesTransmittance) {
    Fixture f;
    ThreadContext ctx(*f.scene);
    MediumQuery& q = *ctx.queries[0];
    const int samples = 100000, bins = 60;
    int rayIndex = 0;
    for (const ProfileRay& pr : profileRays()) {
        // One channel per ray, accepted against the majorant of all channels.
        const int channel = rayIndex % 3;
        const double kc = double(f.k[channel]);
        std::vector<double> observed(bins + 1, 0), expected(bins + 1, 0);
        Rng rng(23, uint64_t(rayIndex));
        int aboveMajorant = 0;
        for (int s = 0; s < samples; ++s) {
            bool hit = false;
            float tHit = 0;
            deltaTrack(ctx, Scene::WorldRegion, pr.ray, pr.tEnd, rng, [&](const Vec3& x, float sigmaMaj) {
                const float sigmaT = float(kc) * q.density(x);
                aboveMajorant += sigmaT > sigmaMaj * (1 + 1e-5f);
                if (rng.uniform() * sigmaMaj < sigmaT) {
                    hit = true;
                    tHit = dot(x - pr.ray.o, pr.ray.d);
                    return false;
                }
                return true;
            });
            if (hit) {
                ASSERT_GE(tHit, 0.f);
                ASSERT_LE(tHit, pr.tEnd * (1 + 1e-5f));
                observed[size_t(std::min(bins - 1, int(tHit / pr.tEnd * bins)))] += 1;
            } else {
                observed[bins] += 1;
            }
        }
        for (int b = 0; b < bins; ++b) {
            const double a = double(pr.tEnd) * b / bins, c = double(pr.tEnd) * (b + 1) / bins;
            expected[size_t(b)] = samples * (std::exp(-kc * pr.depth(a)) - std::exp(-kc * pr.depth(c)));
        }
        const double pNone = std::exp(-kc * pr.depth(pr.tEnd));
        expected[bins] = samples * pNone;
        const ChiSquare chi = pooledChiSquare(observed, expected, 20);
        std::printf("[ chi2     ] %-28s chi2 %.1f dof %d p %.3f; no collision %g (expected %g)\n", pr.name.c_str(),
                    chi.chi2, chi.dof, chi.p(), observed[bins] / samples, pNone);
        EXPECT_GT(chi.p(), 1e-4) << pr.name << ": chi2 " << chi.chi2 << " dof " << chi.dof;
        EXPECT_GE(chi.dof, 30) << pr.name;
        // No collision: a binomial count.
        const double sd = std::sqrt(samples * pNone * (1 - pNone));
        EXPECT_NEAR(observed[bins], samples * pNone, 4 * sd) << pr.name;
        EXPECT_EQ(aboveMajorant, 0) << pr.name;
        ++rayIndex;
    }
}

// Spectral MIS (HeroChannel): a hero drawn uniformly decides each tentative
// collision, nulls weigh the throughput by sigma_maj - sigma_t per channel,
// and a real collision ends the flight. Every channel's throughput at the
// segment's end then has mean exp(-tau_c) (4 standard errors), though two
// of three flights follow another channel's extinction, and no channel's
// weight exceeds 3, the balance heuristic's bound.
TEST(Tracking, SpectralMisGivesEveryChannelItsTransmittanceWithWeightsAtMostThree) {
    Fixture f;
    ThreadContext ctx(*f.scene);
    MediumQuery& q = *ctx.queries[0];
    const int samples = 60000;
    int rayIndex = 0;
    for (const ProfileRay& pr : profileRays()) {
        Rng rng(31, uint64_t(rayIndex));
        SampleStats st[3];
        float largest = 0;
        for (int s = 0; s < samples; ++s) {
            HeroChannel hero;
            hero.channel = std::min(2, int(rng.uniform() * 3));
            Color beta(1);
            deltaTrack(ctx, Scene::WorldRegion, pr.ray, pr.tEnd, rng, [&](const Vec3& x, float sigmaMaj) {
                const Color sigmaT = f.k * q.density(x);
                if (rng.uniform() * sigmaMaj < sigmaT[hero.channel]) {
                    beta = Color(0);
                    return false;
                }
                hero.weigh(max(Color(sigmaMaj) - sigmaT, Color(0)), beta);
                return true;
            });
            for (int c = 0; c < 3; ++c) st[c].add(beta[c]);
            largest = std::max(largest, maxComponent(beta));
        }
        for (int c = 0; c < 3; ++c) {
            const double want = std::exp(-double(f.k[c]) * pr.depth(pr.tEnd));
            EXPECT_NEAR(st[c].mean(), want, 4 * st[c].stdError() + 1e-5) << pr.name << " channel " << c;
        }
        EXPECT_LE(largest, 3 * (1 + 1e-5f)) << pr.name;
        ++rayIndex;
    }
}

void checkEstimator(TransmittanceEstimator estimator, bool inUnitInterval) {
    Fixture f;
    ThreadContext ctx(*f.scene);
    const int samples = 40000;
    int rayIndex = 0;
    double worstZ = 0;
    for (const ProfileRay& pr : profileRays()) {
        const double depth = pr.depth(pr.tEnd);
        // Region transmittance over [0, tEnd), then the shadow-ray walk over
        // the same distance, then to infinity (the whole profile).
        for (int mode = 0; mode < 3; ++mode) {
            Rng rng(29, uint64_t(rayIndex * 3 + mode));
            SampleStats st[3];
            int outside = 0;
            for (int s = 0; s < samples; ++s) {
                Color T;
                if (mode == 0) {
                    T = regionTransmittance(ctx, Scene::WorldRegion, pr.ray, pr.tEnd, rng, estimator);
                } else {
                    T = shadowTransmittance(ctx, Scene::WorldRegion, pr.ray.o, pr.ray.d,
                                            mode == 1 ? pr.tEnd : Infinity, rng, estimator);
                }
                for (int c = 0; c < 3; ++c) {
                    st[c].add(T[c]);
                    outside += !(T[c] >= 0 && T[c] <= 1);
                }
            }
            const double d = mode == 2 ? pr.depth(1e3) : depth;
            for (int c = 0; c < 3; ++c) {
                const double want = std::exp(-double(f.k[c]) * d);
                worstZ = std::max(worstZ, std::fabs(st[c].mean() - want) / st[c].stdError());
                EXPECT_NEAR(st[c].mean(), want, 4 * st[c].stdError() + 1e-5)
                    << pr.name << " mode " << mode << " channel " << c << " optical depth " << f.k[c] * d;
                EXPECT_GT(st[c].stdError(), 0) << "a gridded medium is estimated, not integrated";
            }
            if (inUnitInterval) {
                EXPECT_EQ(outside, 0) << pr.name << " mode " << mode;
            }
        }
        ++rayIndex;
    }
    std::printf("largest |mean - exp(-tau)| / standard error: %.2f\n", worstZ);
}

TEST(Tracking, RatioTrackingTransmittanceIsUnbiasedAndInTheUnitInterval) {
    checkEstimator(TransmittanceEstimator::RatioTracking, true);
}

TEST(Tracking, UnbiasedMarchingTransmittanceIsUnbiased) {
    checkEstimator(TransmittanceEstimator::UnbiasedMarching, false);
}

}  // namespace
}  // namespace vdbmarch
