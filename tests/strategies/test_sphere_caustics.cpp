// Sphere caustic connections (strategies/sphere_caustics.h): the solver's
// connections against the traced rays, and the connection estimate of the
// light a glass ball focuses from a sphere light onto a point against
// brute force (directions drawn uniformly in the cone of the ball, traced
// through it, counted where they hit the light); the same for connections
// across the ball's surface once (a light inside it seen from outside, a
// light outside seen from inside).
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"
#include "support/support.h"
#include "strategies/sphere_caustics.h"

namespace vdbmarch {
namespace {


// Distance from y to the exit ray of the connection.
double missDistance(const SphereConnection& c, const Vec3& y) {
    const Vec3 v = y - c.p2;
    const Vec3 perp = v - c.wo * dot(v, c.wo);
    return double(length(perp));
}

// Whether one of the n connections leaves x along w (within about 4.5e-3 rad):
// the solver found the traced path of direction w.
bool leavesAlong(const SphereConnection* c, int n, const Vec3& w) {
    float best = -1;
    for (int k = 0; k < n; ++k) best = std::max(best, dot(c[k].wi, w));
    return best > 0.99999f;
}

TEST(SphereCaustics, EveryConnectionPassesThroughItsEndPoint) {
    const GlassSphere s = test::figure4Ball();
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
    const GlassSphere s = test::figure4Ball();
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
        const bool found = leavesAlong(c, n, -t.wo);
        missed += !found;
        if (!found && missed <= 4)
            ADD_FAILURE() << "no root for the path through x = " << x.x << " " << x.y << " " << x.z << " (" << n
                          << " found)";
    }
    EXPECT_GT(tried, 15000);
    EXPECT_EQ(missed, 0) << "of " << tried;
}

// The irradiance-like integral at x of a sphere light (centre lightC,
// radius rl) through the ball: the integral over directions w of
// [the ray through the ball, or across its surface, hits the light] times
// the Fresnel transmittances (an isotropic receiver, f = 1, L_e = 1). Brute
// force draws w uniformly in the ball's cone seen from x (over all
// directions from inside), traces it and counts the hits; the connections
// draw y uniformly on the light and bring (1 - F...) cos theta_y / (p_A G)
// for each root. The two must agree within 4 standard errors.
void expectConnectionsMatchBruteForce(const GlassSphere& s, const Vec3& x, const Vec3& lightC, float rl, bool across,
                                      uint64_t seed) {
    const bool xInside = length(x - s.center) < s.radius;
    const float sin2 = xInside ? 1.f : s.radius * s.radius / lengthSquared(s.center - x);
    const float cosMax = xInside ? -1.f : std::sqrt(1 - sin2);
    const Vec3 axis = xInside ? Vec3(0, 0, 1) : normalize(s.center - x);
    const double dirPdf = 1 / (2 * double(Pi) * (1 - double(cosMax)));
    Rng rng(seed);
    auto estimate = [](int n, auto&& sample, double& se) {
        double sum = 0, sum2 = 0;
        for (int i = 0; i < n; ++i) {
            const double v = sample();
            sum += v;
            sum2 += v * v;
        }
        const double mean = sum / n;
        se = std::sqrt((sum2 / n - mean * mean) / n);
        return mean;
    };
    double seB, seC;
    const double meanB = estimate(1000000, [&] {
        const Vec3 w = sampleUniformCone(axis, cosMax, rng.uniform(), rng.uniform());
        SphereConnection t;
        if (!(across ? traceAcrossSphere(s, x, w, t) : traceThroughSphere(s, x, w, t))) return 0.0;
        // Does the ray after the glass hit the light sphere?
        const Vec3 oc = t.p2 - lightC;
        const float b = dot(t.wo, oc), c = dot(oc, oc) - rl * rl;
        return c > 0 && b < 0 && b * b - c > 0 ? double(t.transmission) / dirPdf : 0.0;
    }, seB);
    const double pA = 1 / (4 * double(Pi) * rl * rl);
    const double meanC = estimate(100000, [&] {
        const Vec3 ny = sampleUniformSphere(rng.uniform(), rng.uniform());
        const Vec3 y = lightC + ny * rl;
        SphereConnection c[MaxSphereConnections];
        const int n = across ? connectAcrossSphere(s, x, y, c) : connectThroughSphere(s, x, y, c);
        double v = 0;
        for (int k = 0; k < n; ++k) {
            const double cosY = -double(dot(c[k].wo, ny));
            if (cosY > 0) v += double(c[k].transmission) * cosY / (pA * c[k].spreading);
        }
        return v;
    }, seC);
    ASSERT_GT(meanB, 0);
    EXPECT_NEAR(meanC, meanB, 4 * std::sqrt(seB * seB + seC * seC))
        << "x " << x.x << " " << x.y << " " << x.z << ": connections " << meanC << " +- " << seC << ", tracing "
        << meanB << " +- " << seB;
}

TEST(SphereCaustics, ConnectionEstimateMatchesBruteForceTracing) {
    for (const Vec3 x : {Vec3(0.f, -0.3f, 0.f), Vec3(0.12f, -0.1f, 0.05f), Vec3(0.3f, 0.1f, -0.2f)})
        expectConnectionsMatchBruteForce(test::figure4Ball(), x, Vec3(0.f, 2.6f, 0.f), 0.1f, false, 11);
}

// A point inside the ball (within 0.9 of its radius) and one outside it.
Vec3 insidePoint(const GlassSphere& s, Rng& rng) {
    return s.center + sampleUniformSphere(rng.uniform(), rng.uniform()) * (0.9f * s.radius * std::cbrt(rng.uniform()));
}
Vec3 outsidePoint(Rng& rng) {
    return Vec3(rng.uniform() * 3 - 1.5f, -0.8f + rng.uniform() * 3.0f, rng.uniform() * 3 - 1.5f);
}

TEST(SphereCaustics, EveryConnectionAcrossTheSurfacePassesThroughItsEndPoint) {
    const GlassSphere s = test::figure4Ball();
    Rng rng(5);
    for (const bool fromInside : {false, true}) {
        int tried = 0, found = 0, foundThorough = 0;
        for (int i = 0; i < 2000; ++i) {
            const Vec3 out = outsidePoint(rng);
            if (!(length(out - s.center) > 1.05f * s.radius)) continue;
            const Vec3 in = insidePoint(s, rng);
            const Vec3 x = fromInside ? in : out, y = fromInside ? out : in;
            ++tried;
            SphereConnection c[MaxSphereConnections];
            const int n = connectAcrossSphere(s, x, y, c);
            found += n > 0;
            SphereConnection ct[MaxSphereConnections];
            const int nt = connectAcrossSphere(s, x, y, ct, true);
            foundThorough += nt > 0;
            // What the grid alone misses are paths that graze the ball
            // outside, between its last point and the arc's end: little
            // light passes there (and sphere lights weigh the connections
            // against the paths' own hits).
            if (nt > 0 && n == 0) {
                EXPECT_LT(ct[0].transmission, 0.3f);
            }
            for (int k = 0; k < n; ++k) {
                EXPECT_EQ(c[k].refractions, 1);
                EXPECT_LT(missDistance(c[k], y), 1e-4) << "x " << x.x << " " << x.y << " " << x.z;
                EXPECT_GT(dot(c[k].wo, y - c[k].p2), 0.f);
                EXPECT_NEAR(length(c[k].p2 - s.center), s.radius, 1e-5f);
                SphereConnection t;
                ASSERT_TRUE(traceAcrossSphere(s, x, c[k].wi, t));
                EXPECT_LT(length(t.p2 - c[k].p2), 1e-5f);
                EXPECT_GT(c[k].spreading, 0.0);
                EXPECT_GT(c[k].transmission, 0.f);
                EXPECT_LE(c[k].transmission, 1.f);
            }
        }
        // The rays refracted into the ball from a point outside fill only
        // part of it (beyond the rays at the critical angle lies a shadow),
        // so about three quarters of the pairs connect.
        EXPECT_GT(found, tried / 2) << (fromInside ? "from inside" : "from outside");
        EXPECT_GE(found, 0.95 * foundThorough) << (fromInside ? "from inside" : "from outside");
    }
}

// A point x on the ray that leaves the glass at t.p2: outside the ball, up
// to 2.5 away; inside it, before the chord's end (false where the chord is
// too short to hold one).
bool pointAlong(const GlassSphere& s, const SphereConnection& t, bool outside, Rng& rng, Vec3& x) {
    float along;
    if (outside) along = 0.05f + 2.5f * rng.uniform();
    else {
        const float chord = -2 * dot(t.p2 - s.center, t.wo);
        if (!(chord > 0.02f)) return false;
        along = (0.01f + 0.98f * rng.uniform()) * chord;
    }
    x = t.p2 + t.wo * along;
    return true;
}

// Paths traced across the surface from a point (inside the ball, or
// outside it), then found again from points along them on the other side.
TEST(SphereCaustics, TheSolverFindsEveryTracedPathAcrossTheSurface) {
    const GlassSphere s = test::figure4Ball();
    for (const Vec3 y : {Vec3(0.1f, 0.8f, -0.05f), s.center, Vec3(0.f, 2.6f, 0.f), Vec3(0.6f, 0.2f, 0.3f)}) {
        const bool yInside = length(y - s.center) < s.radius;
        Rng rng(9);
        int tried = 0, missed = 0;
        for (int i = 0; i < 5000; ++i) {
            Vec3 w;
            if (yInside) w = sampleUniformSphere(rng.uniform(), rng.uniform());
            else {
                const float sin2 = s.radius * s.radius / lengthSquared(s.center - y);
                w = sampleUniformCone(normalize(s.center - y), std::sqrt(1 - sin2), rng.uniform(), rng.uniform());
            }
            SphereConnection t;
            if (!traceAcrossSphere(s, y, w, t)) continue;
            Vec3 x;
            if (!pointAlong(s, t, yInside, rng, x)) continue;
            ++tried;
            SphereConnection c[MaxSphereConnections];
            const int n = connectAcrossSphere(s, x, y, c, true);
            const bool found = leavesAlong(c, n, -t.wo);
            missed += !found;
            if (!found && missed <= 4)
                ADD_FAILURE() << "no root for the path through x = " << x.x << " " << x.y << " " << x.z << " (" << n
                              << " found)";
        }
        EXPECT_GT(tried, 3000);
        EXPECT_EQ(missed, 0) << "of " << tried << " from " << y.x << " " << y.y << " " << y.z;
    }
}

// The same across the surface once: a light inside the ball seen from
// outside, and a light outside seen from inside.
TEST(SphereCaustics, ConnectionAcrossTheSurfaceMatchesBruteForceTracing) {
    struct Case {
        Vec3 x, lightC;
        float rl;
    };
    const Case cases[] = {{Vec3(0.f, -0.3f, 0.f), Vec3(0.1f, 0.8f, 0.05f), 0.08f},
                          {Vec3(0.7f, 0.9f, 0.4f), Vec3(-0.05f, 0.7f, 0.f), 0.1f},
                          {Vec3(0.1f, 0.6f, 0.1f), Vec3(0.f, 2.6f, 0.f), 0.3f},
                          {Vec3(-0.2f, 0.9f, 0.f), Vec3(1.2f, 0.4f, 0.3f), 0.2f}};
    for (const Case& cs : cases) expectConnectionsMatchBruteForce(test::figure4Ball(), cs.x, cs.lightC, cs.rl, true, 13);
}

// A light at infinity (directional, collimated): its parallel rays traced
// into the ball, through it or into it, found again from points along them.
TEST(SphereCaustics, TheSolverFindsEveryParallelRayThroughOrIntoTheBall) {
    const GlassSphere s = test::figure4Ball();
    for (const Vec3 wL : {normalize(Vec3(0.3f, 1.f, -0.2f)), Vec3(0.f, 1.f, 0.f), normalize(Vec3(1.f, 0.1f, 0.f))}) {
        const Vec3 a = normalize(cross(wL, Vec3(0.3f, 0.1f, 1.f))), b = cross(wL, a);
        Rng rng(17);
        int tried = 0, missed = 0;
        for (int i = 0; i < 8000; ++i) {
            // A ray of the beam: uniform over the ball's disk, from far away.
            const float r = s.radius * std::sqrt(rng.uniform()), phi = 2 * Pi * rng.uniform();
            const Vec3 start = s.center + wL * 10.f + a * (r * std::cos(phi)) + b * (r * std::sin(phi));
            const bool through = i % 2 == 0;
            SphereConnection t;
            if (!(through ? traceThroughSphere(s, start, -wL, t) : traceAcrossSphere(s, start, -wL, t))) continue;
            Vec3 x;
            if (!pointAlong(s, t, through, rng, x)) continue;
            ++tried;
            SphereConnection c[MaxSphereConnections];
            const int n = through ? connectThroughSphereToward(s, x, wL, c) : connectAcrossSphereToward(s, x, wL, c);
            const bool found = leavesAlong(c, n, -t.wo);
            for (int k = 0; k < n; ++k) {
                EXPECT_GT(dot(c[k].wo, wL), 0.99999f);
                EXPECT_GT(c[k].spreading, 0.0);
            }
            missed += !found;
            if (!found && missed <= 4)
                ADD_FAILURE() << (through ? "through" : "into") << ": no root for the ray through x = " << x.x << " "
                              << x.y << " " << x.z << " (" << n << " found)";
        }
        EXPECT_GT(tried, 6000);
        EXPECT_EQ(missed, 0) << "of " << tried;
    }
}

// The irradiance-like integral at x of a light at infinity through the
// ball: brute force counts the directions whose exit direction falls within
// 0.01 rad of the light's, over that cone's solid angle (directions drawn
// in a cone of 0.1 rad around the connection, which must hold every one
// counted); the connection brings (1 - F...) / J.
TEST(SphereCaustics, ParallelConnectionsMatchBruteForceTracing) {
    const GlassSphere s = test::figure4Ball();
    const Vec3 wL = normalize(Vec3(0.2f, 1.f, 0.1f));
    const double cosAccept = std::cos(0.01), omegaAccept = 2 * double(Pi) * (1 - cosAccept);
    const float cosSample = std::cos(0.1f);
    for (const Vec3 x : {Vec3(0.f, -0.4f, 0.f), Vec3(0.15f, -0.1f, 0.05f), Vec3(0.05f, 0.6f, -0.1f),
                         Vec3(-0.1f, 0.9f, 0.1f)}) {
        const bool inside = length(x - s.center) < s.radius;
        SphereConnection c[MaxSphereConnections];
        const int n = inside ? connectAcrossSphereToward(s, x, wL, c) : connectThroughSphereToward(s, x, wL, c);
        ASSERT_EQ(n, 1) << "x " << x.x << " " << x.y << " " << x.z;
        const double conn = double(c[0].transmission) / c[0].spreading;
        const double dirPdf = double(uniformConePdf(cosSample));
        Rng rng(19);
        const int nb = 4000000;
        double sumB = 0, sumB2 = 0;
        float cosWidest = 1;
        for (int i = 0; i < nb; ++i) {
            const Vec3 w = sampleUniformCone(c[0].wi, cosSample, rng.uniform(), rng.uniform());
            SphereConnection t;
            double v = 0;
            if (inside ? traceAcrossSphere(s, x, w, t) : traceThroughSphere(s, x, w, t))
                if (double(dot(t.wo, wL)) > cosAccept) {
                    v = double(t.transmission) / (dirPdf * omegaAccept);
                    cosWidest = std::min(cosWidest, dot(w, c[0].wi));
                }
            sumB += v;
            sumB2 += v * v;
        }
        const double meanB = sumB / nb, seB = std::sqrt((sumB2 / nb - meanB * meanB) / nb);
        EXPECT_GT(cosWidest, std::cos(0.075f));  // the sampled cone holds every direction counted
        // The brute force's own bias: J varies over the 0.01 rad cone, a
        // second-order effect of under 0.5 % away from the caustic's folds.
        EXPECT_NEAR(conn, meanB, 4 * seB + 0.005 * meanB)
            << "x " << x.x << " " << x.y << " " << x.z << ": connection " << conn << ", tracing " << meanB << " +- "
            << seB;
    }
}

}  // namespace
}  // namespace vdbmarch
