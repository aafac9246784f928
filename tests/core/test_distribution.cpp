// Piecewise-constant distributions: samples land where the pdf says
// (chi-square over sub-cell bins, so the within-cell inversion is checked
// too), pdf() agrees with the pdf a sample was drawn with, and cells of
// weight zero are never drawn.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/distribution.h"
#include "core/rng.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;

TEST(PiecewiseConstant1D, SamplesFollowThePdfWithinAndAcrossCells) {
    const std::vector<float> w = {0.5f, 0, 3, 1, 0, 0, 7, 0.25f};
    PiecewiseConstant1D d(w);
    EXPECT_NEAR(d.integral(), (0.5 + 3 + 1 + 7 + 0.25) / 8, 1e-12);
    const int bins = 8 * 4;  // four bins per cell: the inversion inside a cell is uniform
    std::vector<double> observed(bins, 0), expected(bins, 0);
    const long n = 400000;
    Rng rng(3);
    long zeroCells = 0, pdfMismatch = 0;
    for (long i = 0; i < n; ++i) {
        float pdf;
        size_t cell;
        const float x = d.sample(rng.uniform(), pdf, cell);
        ASSERT_TRUE(x >= 0 && x < 1);
        zeroCells += w[cell] == 0;
        pdfMismatch += d.pdf(x) != pdf || size_t(x * 8) != cell;
        observed[size_t(x * bins)] += 1;
    }
    for (int b = 0; b < bins; ++b) expected[size_t(b)] = n * double(d.pdf((b + 0.5f) / bins)) / bins;
    EXPECT_EQ(zeroCells, 0);
    EXPECT_EQ(pdfMismatch, 0);
    const ChiSquare c = pooledChiSquare(observed, expected, 20);
    EXPECT_GT(c.p(), 1e-4) << "chi2 " << c.chi2 << " dof " << c.dof;
}

TEST(PiecewiseConstant1D, AllZeroWeightsGiveTheUniformDensityAndZeroIntegral) {
    PiecewiseConstant1D d(std::vector<float>(5, 0.f));
    EXPECT_EQ(d.integral(), 0);
    float pdf;
    size_t cell;
    const float x = d.sample(0.7f, pdf, cell);
    EXPECT_EQ(pdf, 1.f);
    EXPECT_NEAR(x, 0.7f, 1e-6f);
}

TEST(PiecewiseConstant1D, EdgeUniformsStayInsideTheirCell) {
    PiecewiseConstant1D d(std::vector<float>{1, 0, 1e-30f, 5, 0});
    for (float u : {0.f, 1e-9f, 0.5f, 0.99999994f, std::nextafter(1.f, 0.f)}) {
        float pdf;
        size_t cell;
        const float x = d.sample(u, pdf, cell);
        EXPECT_TRUE(x >= 0 && x < 1) << u;
        EXPECT_GT(pdf, 0) << u;
        EXPECT_EQ(d.pdf(x), pdf) << u;
    }
}

TEST(PiecewiseConstant2D, SamplesFollowThePdf) {
    const int w = 6, h = 4;
    std::vector<float> table(size_t(w * h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) table[size_t(y * w + x)] = float((x * 7 + y * 3) % 5);  // some zeros
    PiecewiseConstant2D d(table, w, h);
    const int bu = w * 2, bv = h * 2;
    std::vector<double> observed(size_t(bu * bv), 0), expected(size_t(bu * bv), 0);
    const long n = 400000;
    Rng rng(5);
    long mismatch = 0;
    for (long i = 0; i < n; ++i) {
        float u, v, pdf;
        d.sample(rng.uniform(), rng.uniform(), u, v, pdf);
        ASSERT_TRUE(u >= 0 && u < 1 && v >= 0 && v < 1);
        ASSERT_GT(pdf, 0);
        mismatch += std::fabs(d.pdf(u, v) - pdf) > 1e-5f * pdf;
        observed[size_t(int(v * bv) * bu + int(u * bu))] += 1;
    }
    double total = 0;
    for (int j = 0; j < bv; ++j)
        for (int i = 0; i < bu; ++i) {
            const double p = d.pdf((i + 0.5f) / bu, (j + 0.5f) / bv);
            expected[size_t(j * bu + i)] = n * p / (bu * bv);
            total += p / (bu * bv);
        }
    EXPECT_NEAR(total, 1.0, 1e-5);  // the pdf integrates to one
    EXPECT_EQ(mismatch, 0);
    const ChiSquare c = pooledChiSquare(observed, expected, 20);
    EXPECT_GT(c.p(), 1e-4) << "chi2 " << c.chi2 << " dof " << c.dof;
}

}  // namespace
}  // namespace vdbmarch
