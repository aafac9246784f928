#include "core/blackbody.h"

#include <array>
#include <cmath>

namespace vdbmarch {

namespace {

// CIE 1931 2-degree standard observer colour matching functions xbar, ybar,
// zbar at 5 nm from 360 to 830 nm: the official CIE table (CIE 015:2018,
// table 1; the 5 nm rows of the 1 nm table as distributed with pbrt-v4,
// src/pbrt/util/spectrum.cpp).
constexpr double CmfStartNm = 360, CmfStepNm = 5;
constexpr double Cmf[][3] = {
    {0.0001299000, 0.000003917000, 0.0006061000},  // 360 nm
    {0.0002321000, 0.000006965000, 0.001086000},  // 365 nm
    {0.0004149000, 0.00001239000, 0.001946000},  // 370 nm
    {0.0007416000, 0.00002202000, 0.003486000},  // 375 nm
    {0.001368000, 0.00003900000, 0.006450001},  // 380 nm
    {0.002236000, 0.00006400000, 0.01054999},  // 385 nm
    {0.004243000, 0.0001200000, 0.02005001},  // 390 nm
    {0.007650000, 0.0002170000, 0.03621000},  // 395 nm
    {0.01431000, 0.0003960000, 0.06785001},  // 400 nm
    {0.02319000, 0.0006400000, 0.1102000},  // 405 nm
    {0.04351000, 0.001210000, 0.2074000},  // 410 nm
    {0.07763000, 0.002180000, 0.3713000},  // 415 nm
    {0.1343800, 0.004000000, 0.6456000},  // 420 nm
    {0.2147700, 0.007300000, 1.0390501},  // 425 nm
    {0.2839000, 0.01160000, 1.3856000},  // 430 nm
    {0.3285000, 0.01684000, 1.6229600},  // 435 nm
    {0.3482800, 0.02300000, 1.7470600},  // 440 nm
    {0.3480600, 0.02980000, 1.7826000},  // 445 nm
    {0.3362000, 0.03800000, 1.7721100},  // 450 nm
    {0.3187000, 0.04800000, 1.7441000},  // 455 nm
    {0.2908000, 0.06000000, 1.6692000},  // 460 nm
    {0.2511000, 0.07390000, 1.5281000},  // 465 nm
    {0.1953600, 0.09098000, 1.2876400},  // 470 nm
    {0.1421000, 0.1126000, 1.0419000},  // 475 nm
    {0.09564000, 0.1390200, 0.8129501},  // 480 nm
    {0.05795001, 0.1693000, 0.6162000},  // 485 nm
    {0.03201000, 0.2080200, 0.4651800},  // 490 nm
    {0.01470000, 0.2586000, 0.3533000},  // 495 nm
    {0.004900000, 0.3230000, 0.2720000},  // 500 nm
    {0.002400000, 0.4073000, 0.2123000},  // 505 nm
    {0.009300000, 0.5030000, 0.1582000},  // 510 nm
    {0.02910000, 0.6082000, 0.1117000},  // 515 nm
    {0.06327000, 0.7100000, 0.07824999},  // 520 nm
    {0.1096000, 0.7932000, 0.05725001},  // 525 nm
    {0.1655000, 0.8620000, 0.04216000},  // 530 nm
    {0.2257499, 0.9148501, 0.02984000},  // 535 nm
    {0.2904000, 0.9540000, 0.02030000},  // 540 nm
    {0.3597000, 0.9803000, 0.01340000},  // 545 nm
    {0.4334499, 0.9949501, 0.008749999},  // 550 nm
    {0.5120501, 1.0000000, 0.005749999},  // 555 nm
    {0.5945000, 0.9950000, 0.003900000},  // 560 nm
    {0.6784000, 0.9786000, 0.002749999},  // 565 nm
    {0.7621000, 0.9520000, 0.002100000},  // 570 nm
    {0.8425000, 0.9154000, 0.001800000},  // 575 nm
    {0.9163000, 0.8700000, 0.001650001},  // 580 nm
    {0.9786000, 0.8163000, 0.001400000},  // 585 nm
    {1.0263000, 0.7570000, 0.001100000},  // 590 nm
    {1.0567000, 0.6949000, 0.001000000},  // 595 nm
    {1.0622000, 0.6310000, 0.0008000000},  // 600 nm
    {1.0456000, 0.5668000, 0.0006000000},  // 605 nm
    {1.0026000, 0.5030000, 0.0003400000},  // 610 nm
    {0.9384000, 0.4412000, 0.0002400000},  // 615 nm
    {0.8544499, 0.3810000, 0.0001900000},  // 620 nm
    {0.7514000, 0.3210000, 0.0001000000},  // 625 nm
    {0.6424000, 0.2650000, 0.00004999999},  // 630 nm
    {0.5419000, 0.2170000, 0.00003000000},  // 635 nm
    {0.4479000, 0.1750000, 0.00002000000},  // 640 nm
    {0.3608000, 0.1382000, 0.00001000000},  // 645 nm
    {0.2835000, 0.1070000, 0.000000000000},  // 650 nm
    {0.2187000, 0.08160000, 0.000000000000},  // 655 nm
    {0.1649000, 0.06100000, 0.000000000000},  // 660 nm
    {0.1212000, 0.04458000, 0.000000000000},  // 665 nm
    {0.08740000, 0.03200000, 0.000000000000},  // 670 nm
    {0.06360000, 0.02320000, 0.000000000000},  // 675 nm
    {0.04677000, 0.01700000, 0.000000000000},  // 680 nm
    {0.03290000, 0.01192000, 0.000000000000},  // 685 nm
    {0.02270000, 0.008210000, 0.000000000000},  // 690 nm
    {0.01584000, 0.005723000, 0.000000000000},  // 695 nm
    {0.01135916, 0.004102000, 0.000000000000},  // 700 nm
    {0.008110916, 0.002929000, 0.000000000000},  // 705 nm
    {0.005790346, 0.002091000, 0.000000000000},  // 710 nm
    {0.004109457, 0.001484000, 0.000000000000},  // 715 nm
    {0.002899327, 0.001047000, 0.000000000000},  // 720 nm
    {0.002049190, 0.0007400000, 0.000000000000},  // 725 nm
    {0.001439971, 0.0005200000, 0.000000000000},  // 730 nm
    {0.0009999493, 0.0003611000, 0.000000000000},  // 735 nm
    {0.0006900786, 0.0002492000, 0.000000000000},  // 740 nm
    {0.0004760213, 0.0001719000, 0.000000000000},  // 745 nm
    {0.0003323011, 0.0001200000, 0.000000000000},  // 750 nm
    {0.0002348261, 0.00008480000, 0.000000000000},  // 755 nm
    {0.0001661505, 0.00006000000, 0.000000000000},  // 760 nm
    {0.0001174130, 0.00004240000, 0.000000000000},  // 765 nm
    {0.00008307527, 0.00003000000, 0.000000000000},  // 770 nm
    {0.00005870652, 0.00002120000, 0.000000000000},  // 775 nm
    {0.00004150994, 0.00001499000, 0.000000000000},  // 780 nm
    {0.00002935326, 0.00001060000, 0.000000000000},  // 785 nm
    {0.00002067383, 0.000007465700, 0.000000000000},  // 790 nm
    {0.00001455977, 0.000005257800, 0.000000000000},  // 795 nm
    {0.00001025398, 0.000003702900, 0.000000000000},  // 800 nm
    {0.000007221456, 0.000002607800, 0.000000000000},  // 805 nm
    {0.000005085868, 0.000001836600, 0.000000000000},  // 810 nm
    {0.000003581652, 0.000001293400, 0.000000000000},  // 815 nm
    {0.000002522525, 0.0000009109300, 0.000000000000},  // 820 nm
    {0.000001776509, 0.0000006415300, 0.000000000000},  // 825 nm
    {0.000001251141, 0.0000004518100, 0.000000000000},  // 830 nm
};
constexpr int CmfCount = int(sizeof(Cmf) / sizeof(Cmf[0]));
static_assert(CmfCount == 95, "360..830 nm at 5 nm");

// Second radiation constant c2 = h c / k_B (CODATA 2018, exact since the SI
// redefinition): m K. The first constant cancels in the normalised colour.
constexpr double C2 = 1.438776877e-2;
constexpr double C1L = 2 * 6.62607015e-34 * 299792458.0 * 299792458.0;  // 2 h c^2, W m^2 / sr

struct Mat3 {
    double m[3][3];
};

Mat3 inverse(const Mat3& a) {
    const auto& m = a.m;
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                       m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    Mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            // Cofactor of m[j][i] (transposed) over the determinant.
            const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
            r.m[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
        }
    return r;
}

// XYZ -> RGB for the ITU-R BT.709 primaries R (0.64, 0.33), G (0.30, 0.60),
// B (0.15, 0.06) and white D65 (0.3127, 0.3290): the RGB -> XYZ matrix has the
// primaries' XYZ as columns, each scaled so that RGB (1,1,1) is the white
// with Y = 1 (SMPTE RP 177).
Mat3 rec709FromXyz() {
    const double px[3] = {0.64, 0.30, 0.15}, py[3] = {0.33, 0.60, 0.06};
    const double wx = 0.3127, wy = 0.3290;
    Mat3 p;
    for (int c = 0; c < 3; ++c) {
        p.m[0][c] = px[c] / py[c];
        p.m[1][c] = 1;
        p.m[2][c] = (1 - px[c] - py[c]) / py[c];
    }
    const Mat3 pi = inverse(p);
    const double w[3] = {wx / wy, 1, (1 - wx - wy) / wy};
    Mat3 rgbToXyz;
    for (int c = 0; c < 3; ++c) {
        const double s = pi.m[c][0] * w[0] + pi.m[c][1] * w[1] + pi.m[c][2] * w[2];
        for (int r = 0; r < 3; ++r) rgbToXyz.m[r][c] = p.m[r][c] * s;
    }
    return inverse(rgbToXyz);
}

// Luminance-1 colours before clipping, smooth in T.
Color unclippedColor(double kelvin) {
    const Color c = xyzToRec709(blackbodyXyz(kelvin));
    return c / luminance(c);
}

// Out-of-gamut colours lose their negative components, then get luminance 1 again.
Color clipToGamut(const Color& c) {
    if (!(minComponent(c) < 0)) return c;
    const Color k = max(c, Color(0));
    return k / luminance(k);
}

// Unclipped colours at equal steps of reciprocal temperature (mired,
// 1e6 / T): the Planckian locus is close to linear in it, and equal mired
// steps are roughly equal steps of perceived colour. Clipping after the
// interpolation keeps its kinks out of the table. 1024 entries: the
// interpolation error is below 3e-5 (tests/core/test_blackbody.cpp).
struct ColorTable {
    static constexpr int N = 1024;
    static constexpr float MiredLo = 1e6f / BlackbodyMaxKelvin, MiredHi = 1e6f / BlackbodyMinKelvin;
    static constexpr float Step = (MiredHi - MiredLo) / (N - 1);
    std::array<Color, N> rgb;
    ColorTable() {
        for (int i = 0; i < N; ++i) rgb[size_t(i)] = unclippedColor(1e6 / (double(MiredLo) + double(Step) * i));
    }
};

}  // namespace

double planckRadiance(double lambda, double kelvin) {
    if (!(kelvin > 0)) return 0;
    const double l5 = (lambda * lambda) * (lambda * lambda) * lambda;
    return C1L / (l5 * std::expm1(C2 / (lambda * kelvin)));
}

Xyz blackbodyXyz(double kelvin) {
    Xyz s;
    for (int i = 0; i < CmfCount; ++i) {
        const double b = planckRadiance((CmfStartNm + CmfStepNm * i) * 1e-9, kelvin);
        s.X += b * Cmf[i][0];
        s.Y += b * Cmf[i][1];
        s.Z += b * Cmf[i][2];
    }
    // Dividing by Y removes the spectral constants (and the 5 nm weight).
    return {s.X / s.Y, 1.0, s.Z / s.Y};
}

Color xyzToRec709(const Xyz& xyz) {
    static const Mat3 m = rec709FromXyz();
    double rgb[3];
    for (int r = 0; r < 3; ++r) rgb[r] = m.m[r][0] * xyz.X + m.m[r][1] * xyz.Y + m.m[r][2] * xyz.Z;
    return Color(float(rgb[0]), float(rgb[1]), float(rgb[2]));
}

Color blackbodyColorExact(double kelvin) { return clipToGamut(unclippedColor(kelvin)); }

Color blackbodyColor(float kelvin) {
    static const ColorTable table;
    // kelvin = 0 gives an infinite mired: the lowest temperature's colour.
    const float u = (1e6f / kelvin - ColorTable::MiredLo) * (1.f / ColorTable::Step);
    if (!(u > 0)) return clipToGamut(table.rgb[0]);
    if (!(u < ColorTable::N - 1)) return clipToGamut(table.rgb[ColorTable::N - 1]);
    const int i = int(u);
    const float f = u - float(i);
    return clipToGamut(table.rgb[size_t(i)] * (1 - f) + table.rgb[size_t(i) + 1] * f);
}

}  // namespace vdbmarch
