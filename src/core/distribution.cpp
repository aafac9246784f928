#include "core/distribution.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vdbmarch {

PiecewiseConstant1D::PiecewiseConstant1D(std::vector<float> weights) : mWeights(std::move(weights)) {
    const size_t n = mWeights.size();
    if (n == 0) throw std::logic_error("PiecewiseConstant1D needs at least one cell");
    mCdf.assign(n + 1, 0.0);
    for (size_t i = 0; i < n; ++i) {
        if (!(mWeights[i] >= 0) || !std::isfinite(mWeights[i]))
            throw std::logic_error("PiecewiseConstant1D: weights must be finite and >= 0");
        mCdf[i + 1] = mCdf[i] + double(mWeights[i]);
    }
    const double total = mCdf[n];
    mIntegral = total / double(n);
    mPdf.resize(n);
    for (size_t i = 0; i <= n; ++i) mCdf[i] = total > 0 ? mCdf[i] / total : double(i) / double(n);
    for (size_t i = 0; i < n; ++i) mPdf[i] = total > 0 ? float(double(mWeights[i]) * double(n) / total) : 1.f;
    mCdf[n] = 1;
}

float PiecewiseConstant1D::sample(float u, float& pdf, size_t& cell) const {
    const size_t n = mWeights.size();
    // First cell whose CDF end exceeds u; zero-weight cells are never picked.
    const double ud = double(u);
    size_t i = size_t(std::upper_bound(mCdf.begin() + 1, mCdf.end(), ud) - (mCdf.begin() + 1));
    i = std::min(i, n - 1);
    while (i > 0 && mPdf[i] == 0) --i;  // u == 1 rounding guard
    cell = i;
    pdf = mPdf[i];
    const double width = mCdf[i + 1] - mCdf[i];
    const double t = width > 0 ? (ud - mCdf[i]) / width : 0.5;
    float x = float((double(i) + std::min(std::max(t, 0.0), 1.0)) / double(n));
    // Keep x inside cell i after rounding, so pdf(x) is the pdf it was drawn with.
    const float lo = float(double(i) / double(n)), hi = float(double(i + 1) / double(n));
    while (x >= hi || size_t(x * float(n)) > i) x = std::nextafter(x, lo);
    while (x < lo || size_t(x * float(n)) < i) x = std::nextafter(x, hi);
    return x;
}

float PiecewiseConstant1D::pdf(float x) const {
    const size_t n = mWeights.size();
    if (!(x >= 0 && x < 1)) return 0;
    return mPdf[std::min(n - 1, size_t(x * float(n)))];
}

PiecewiseConstant2D::PiecewiseConstant2D(const std::vector<float>& weights, int width, int height)
    : mWidth(width), mHeight(height) {
    if (width <= 0 || height <= 0 || weights.size() != size_t(width) * size_t(height))
        throw std::logic_error("PiecewiseConstant2D: table size mismatch");
    std::vector<float> rowIntegrals(static_cast<size_t>(height), 0.f);
    mRows.reserve(size_t(height));
    for (int y = 0; y < height; ++y) {
        const auto first = weights.begin() + ptrdiff_t(size_t(y) * size_t(width));
        mRows.emplace_back(std::vector<float>(first, first + width));
        rowIntegrals[size_t(y)] = float(mRows.back().integral());
    }
    mMarginal = PiecewiseConstant1D(std::move(rowIntegrals));
}

void PiecewiseConstant2D::sample(float u1, float u2, float& u, float& v, float& pdf) const {
    float pv, pu;
    size_t row, col;
    v = mMarginal.sample(u2, pv, row);
    u = mRows[row].sample(u1, pu, col);
    pdf = pv * pu;
}

float PiecewiseConstant2D::pdf(float u, float v) const {
    if (!(v >= 0 && v < 1) || !(u >= 0 && u < 1)) return 0;
    const size_t row = std::min(size_t(mHeight - 1), size_t(v * float(mHeight)));
    return mMarginal.cellPdf(row) * mRows[row].pdf(u);
}

}  // namespace vdbmarch
