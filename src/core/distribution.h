// Piecewise-constant distributions for importance sampling tabulated
// functions (an environment map's texels). Each comes with its pdf; the
// continuous sample inverts the CDF within the chosen cell, so sample() and
// pdf() agree exactly (tests/core/test_distribution.cpp: chi-square).
#pragma once

#include <cstddef>
#include <vector>

namespace vdbmarch {

// A density on [0, 1) proportional to n non-negative cell weights.
class PiecewiseConstant1D {
public:
    PiecewiseConstant1D() = default;
    // Weights must be finite and >= 0; all zero gives the uniform density
    // (integral() then reports 0 so callers can tell).
    explicit PiecewiseConstant1D(std::vector<float> weights);

    size_t size() const { return mWeights.size(); }
    // Mean weight: the integral of the step function over [0, 1).
    double integral() const { return mIntegral; }
    // x in [0, 1) with density pdf(x); `cell` is the cell it falls in.
    float sample(float u, float& pdf, size_t& cell) const;
    float pdf(float x) const;
    float cellPdf(size_t cell) const { return mPdf[cell]; }

private:
    std::vector<float> mWeights, mPdf;
    std::vector<double> mCdf;  // size n + 1, mCdf[0] = 0, mCdf[n] = 1
    double mIntegral = 0;
};

// A density on [0, 1)^2 proportional to a width x height table of
// non-negative weights (row-major, row y covers v in [y/h, (y+1)/h)): the
// marginal over rows, then each row's conditional over columns.
class PiecewiseConstant2D {
public:
    PiecewiseConstant2D() = default;
    PiecewiseConstant2D(const std::vector<float>& weights, int width, int height);

    double integral() const { return mMarginal.integral(); }
    // (u, v) in [0, 1)^2 with density pdf(u, v).
    void sample(float u1, float u2, float& u, float& v, float& pdf) const;
    float pdf(float u, float v) const;

private:
    int mWidth = 0, mHeight = 0;
    std::vector<PiecewiseConstant1D> mRows;
    PiecewiseConstant1D mMarginal;
};

}  // namespace vdbmarch
