// Blackbody colours: chromaticities against a published Planckian-locus
// table, the Rec.709 matrix against its defining white and primaries, the
// temperature table against the exact sum, and the brightness law.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/blackbody.h"

namespace vdbmarch {
namespace {

// CIE 1931 xy of blackbodies, 4 decimals: John Walker, "Colour Rendering of
// Spectra" (fourmilab.ch/documents/specrend), the output table of specrend.c,
// which sums Planck's law against the CIE 1931 2-degree functions at 5 nm
// from 380 to 780 nm. Tolerance: half a unit of the 4th decimal (5e-5) plus
// the effect of our wider 360-830 nm sum, at most 7e-5 (measured: 6.5e-5 at
// 10000 K, computing ours over 380-780 nm instead).
TEST(Blackbody, ChromaticityMatchesPublishedPlanckianLocus) {
    struct Row {
        double kelvin, x, y;
    };
    const Row table[] = {{1000, 0.6528, 0.3444}, {1500, 0.5857, 0.3931}, {2000, 0.5267, 0.4133},
                         {2500, 0.4770, 0.4137}, {3000, 0.4369, 0.4041}, {4000, 0.3805, 0.3768},
                         {5000, 0.3451, 0.3516}, {6500, 0.3135, 0.3237}, {8000, 0.2952, 0.3048},
                         {10000, 0.2807, 0.2884}};
    const double tol = 5e-5 + 7e-5;
    double worst = 0;
    for (const Row& r : table) {
        const Xyz c = blackbodyXyz(r.kelvin);
        const double s = c.X + c.Y + c.Z;
        EXPECT_NEAR(c.X / s, r.x, tol) << r.kelvin << " K";
        EXPECT_NEAR(c.Y / s, r.y, tol) << r.kelvin << " K";
        worst = std::max({worst, std::fabs(c.X / s - r.x), std::fabs(c.Y / s - r.y)});
    }
    if (std::getenv("VDBMARCH_VERBOSE")) std::printf("max chromaticity error %.3g\n", worst);
}

// The matrix is derived from the BT.709 primaries and D65: D65 (Y = 1) must
// map to RGB (1, 1, 1) and each primary to a pure channel, up to float rounding.
TEST(Blackbody, Rec709MatrixMapsD65ToEqualRgbAndPrimariesToChannels) {
    auto fromXy = [](double x, double y) { return Xyz{x / y, 1, (1 - x - y) / y}; };
    const Color white = xyzToRec709(fromXy(0.3127, 0.3290));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(white[c], 1.0, 1e-6) << c;
    const double px[3] = {0.64, 0.30, 0.15}, py[3] = {0.33, 0.60, 0.06};
    for (int p = 0; p < 3; ++p) {
        const Color rgb = xyzToRec709(fromXy(px[p], py[p]));
        for (int c = 0; c < 3; ++c) {
            if (c != p) {
                EXPECT_NEAR(rgb[c] / rgb[p], 0.0, 1e-6) << "primary " << p << " channel " << c;
            }
        }
        // A primary of Y = 1 has 1 / (its luminance weight) in its channel:
        // 0.2126, 0.7152, 0.0722 (BT.709, rounded to 4 decimals).
        EXPECT_NEAR(1 / rgb[p], luminance(Color(p == 0, p == 1, p == 2)), 5e-5) << p;
    }
}

// The interpolated table against the exact sum, at 3000 temperatures spread
// over the table, luminance-1 units (measured: 1.4e-5, near 38000 K).
TEST(Blackbody, TableMatchesExactColour) {
    double worst = 0;
    for (int i = 0; i < 3000; ++i) {
        const double t = BlackbodyMinKelvin * std::pow(double(BlackbodyMaxKelvin / BlackbodyMinKelvin), (i + 0.5) / 3000);
        const Color a = blackbodyColor(float(t)), b = blackbodyColorExact(t);
        for (int c = 0; c < 3; ++c) worst = std::max(worst, double(std::fabs(a[c] - b[c])));
    }
    if (std::getenv("VDBMARCH_VERBOSE")) std::printf("max table error %.3g\n", worst);
    EXPECT_LT(worst, 3e-5);
}

TEST(Blackbody, ColourHasLuminanceOneAndIsClampedOutsideTheTable) {
    for (float t : {300.f, 500.f, 800.f, 1200.f, 1900.f, 3000.f, 6500.f, 15000.f, 40000.f, 1e6f}) {
        const Color c = blackbodyColor(t);
        EXPECT_NEAR(luminance(c), 1.0, 1e-5) << t;
        EXPECT_GE(minComponent(c), 0.f) << t;
    }
    auto expectSame = [](const Color& a, const Color& b, const char* what) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-5) << what;
    };
    expectSame(blackbodyColor(100), blackbodyColor(BlackbodyMinKelvin), "100 K");
    expectSame(blackbodyColor(0), blackbodyColor(BlackbodyMinKelvin), "0 K");
    expectSame(blackbodyColor(1e5f), blackbodyColor(BlackbodyMaxKelvin), "1e5 K");
    // Low temperatures are red, high ones blue.
    EXPECT_GT(blackbodyColor(1500).x, blackbodyColor(1500).z);
    EXPECT_GT(blackbodyColor(20000).z, blackbodyColor(20000).x);
}

// Stefan-Boltzmann brightness with Cycles' scale: sigma T^4 / pi x 1e-6.
TEST(Blackbody, LuminanceFollowsStefanBoltzmann) {
    const double sigma = 5.670374419e-8;  // W m^-2 K^-4 (CODATA 2018)
    for (float t : {800.f, 1500.f, 2728.f, 6000.f})
        EXPECT_NEAR(blackbodyLuminance(t), sigma * std::pow(double(t), 4) / M_PI * 1e-6, 1e-6 * blackbodyLuminance(t));
    EXPECT_NEAR(blackbodyLuminance(2728), 1.0, 1e-3);
    EXPECT_EQ(blackbodyLuminance(0), 0.f);
    EXPECT_EQ(blackbodyLuminance(-5), 0.f);
    EXPECT_NEAR(luminance(blackbodyRadiance(1800)), blackbodyLuminance(1800), 1e-5 * blackbodyLuminance(1800));
}

}  // namespace
}  // namespace vdbmarch
