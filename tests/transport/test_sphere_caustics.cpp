// Sphere caustic connections (transport/sphere_caustics.h): the solver's
// connections against the traced rays, and the connection estimate of the
// light a glass ball focuses from a sphere light onto a point against
// brute force (directions drawn uniformly in the cone of the ball, traced
// through it, counted where they hit the light).
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"
#include "transport/sphere_caustics.h"

namespace vdbmarch {
namespace {

GlassSphere ball() {
    GlassSphere s;
    s.center = Vec3(0.f, 0.75f, 0.f);
    s.radius = 0.45f;
    s.ior = 1.5f;
    return s;
}

// Distance from y to the exit ray of the connection.
double missDistance(const SphereConnection& c, const Vec3& y) {
    const Vec3 v = y - c.p2;
    const Vec3 perp = v - c.wo * dot(v, c.wo);
    return double(length(perp));
}

TEST(SphereCaustics, EveryConnectionPassesThroughItsEndPoint) {
    const GlassSphere s = ball();
    Rng rng(7);
    int found = 0, multiple = 0;
    for (int i = 0; i < 2000; ++i) {
        const Vec3 x(rng.uniform() * 2 - 1, -0.8f + rng.uniform() * 1.0f, rng.uniform() * 2 - 1);
        const Vec3 y = Vec3(0.f, 2.6f, 0.f) + sampleUniformSphere(rng.uniform(), rng.uniform()) * 0.1f;
        SphereConnection c[MaxSphereConnections];
        const int n = connectThroughSphere(s, x, y, c);
        found += n > 0;
        multiple += n > 1;
        for (int k = 0; k < n; ++k) {
            EXPECT_LT(missDistance(c[k], y), 1e-4) << "x " << x.x << " " << x.y << " " << x.z;
            EXPECT_GT(dot(c[k].wo, y - c[k].p2), 0.f);
            // The connection is the traced ray of its own direction.
            SphereConnection t;
            ASSERT_TRUE(traceThroughSphere(s, x, c[k].wi, t));
            EXPECT_LT(length(t.p2 - c[k].p2), 1e-5f);
            EXPECT_GT(c[k].spreading, 0.0);
            EXPECT_GT(c[k].transmission, 0.f);
            EXPECT_LE(c[k].transmission, 1.f);
        }
    }
    EXPECT_GT(found, 1500);  // below the ball nearly every point sees the light through it
    EXPECT_GT(multiple, 0);  // inside the caustic's envelope three paths meet
}

// The paths of a point light through the ball, traced forwards from the
// light, then found again from points along their exit rays: near the
// lens's axis, where the rays through its middle cross in pairs closer than
// the solver's grid, and near the folds of the caustic.
TEST(SphereCaustics, TheSolverFindsEveryTracedPathFromAPoint) {
    const GlassSphere s = ball();
    const Vec3 y(0.f, 2.6f, 0.f);
    Rng rng(3);
    int tried = 0, missed = 0;
    for (int i = 0; i < 20000; ++i) {
        // A direction from y into the ball's cone, traced through it.
        const Vec3 axis = normalize(s.center - y);
        const float sin2 = s.radius * s.radius / lengthSquared(s.center - y);
        const Vec3 w = sampleUniformCone(axis, std::sqrt(1 - sin2), rng.uniform(), rng.uniform());
        SphereConnection t;
        if (!traceThroughSphere(s, y, w, t)) continue;
        // A point on the exit ray, up to 2.5 below the ball.
        const Vec3 x = t.p2 + t.wo * (0.05f + 2.5f * rng.uniform());
        ++tried;
        SphereConnection c[MaxSphereConnections];
        const int n = connectThroughSphere(s, x, y, c, true);
        float best = -1;
        for (int k = 0; k < n; ++k) best = std::max(best, dot(c[k].wi, -t.wo));
        missed += !(best > 0.99999f);
        if (!(best > 0.99999f) && missed <= 4)
            ADD_FAILURE() << "no root for the path through x = " << x.x << " " << x.y << " " << x.z << " (" << n
                          << " found)";
    }
    EXPECT_GT(tried, 15000);
    EXPECT_EQ(missed, 0) << "of " << tried;
}

// Irradiance-like integral at x of the light through the ball: the
// integral over directions w of L_e [the ray through the ball hits the light]
// (1 - F1)(1 - F2) (an isotropic receiver, f = 1).
TEST(SphereCaustics, ConnectionEstimateMatchesBruteForceTracing) {
    const GlassSphere s = ball();
    const Vec3 lightC(0.f, 2.6f, 0.f);
    const float rl = 0.1f;
    for (const Vec3 x : {Vec3(0.f, -0.3f, 0.f), Vec3(0.12f, -0.1f, 0.05f), Vec3(0.3f, 0.1f, -0.2f)}) {
        // Brute force: w uniform in the cone of the ball seen from x.
        const Vec3 axis = normalize(s.center - x);
        const float sin2 = s.radius * s.radius / lengthSquared(s.center - x);
        const float cosMax = std::sqrt(1 - sin2);
        const double conePdf = double(uniformConePdf(cosMax));
        Rng rng(11);
        const int nb = 1000000;
        double sumB = 0, sumB2 = 0;
        for (int i = 0; i < nb; ++i) {
            const Vec3 w = sampleUniformCone(axis, cosMax, rng.uniform(), rng.uniform());
            SphereConnection t;
            double v = 0;
            if (traceThroughSphere(s, x, w, t)) {
                // Does the exit ray hit the light sphere?
                const Vec3 oc = t.p2 - lightC;
                const float b = dot(t.wo, oc), c = dot(oc, oc) - rl * rl;
                if (c > 0 && b < 0 && b * b - c > 0) v = double(t.transmission) / conePdf;
            }
            sumB += v;
            sumB2 += v * v;
        }
        const double meanB = sumB / nb, seB = std::sqrt((sumB2 / nb - meanB * meanB) / nb);

        // Connections: y uniform on the light, each root f L T cos / (p_A G).
        const int nc = 100000;
        double sumC = 0, sumC2 = 0;
        const double pA = 1 / (4 * double(Pi) * rl * rl);
        for (int i = 0; i < nc; ++i) {
            const Vec3 ny = sampleUniformSphere(rng.uniform(), rng.uniform());
            const Vec3 y = lightC + ny * rl;
            SphereConnection c[MaxSphereConnections];
            const int n = connectThroughSphere(s, x, y, c);
            double v = 0;
            for (int k = 0; k < n; ++k) {
                const double cosY = -double(dot(c[k].wo, ny));
                if (cosY > 0) v += double(c[k].transmission) * cosY / (pA * c[k].spreading);
            }
            sumC += v;
            sumC2 += v * v;
        }
        const double meanC = sumC / nc, seC = std::sqrt((sumC2 / nc - meanC * meanC) / nc);
        ASSERT_GT(meanB, 0);
        EXPECT_NEAR(meanC, meanB, 4 * std::sqrt(seB * seB + seC * seC))
            << "x " << x.x << " " << x.y << " " << x.z << ": connections " << meanC << " +- " << seC << ", tracing "
            << meanB << " +- " << seB;
    }
}

}  // namespace
}  // namespace vdbmarch
