#include "denoise/denoise_planes.h"

namespace vdbmarch::denoising {

std::vector<float> channelOf(const std::vector<Color>& v, int c) {
    std::vector<float> out(v.size());
    for (size_t i = 0; i < v.size(); ++i) out[i] = v[i][c];
    return out;
}

Plane boxAverage(const Plane& in, int radius) {
    const int w = in.width, h = in.height;
    Plane horizontal(w, h, in.pad), out(w, h, in.pad);
    forEachRow(h, [&](int y) {
        const float* src = in.row(y);
        float* dst = horizontal.row(y);
        for (int x = 0; x < w; ++x) {
            const int x0 = std::max(0, x - radius), x1 = std::min(w - 1, x + radius);
            float sum = 0;
            for (int i = x0; i <= x1; ++i) sum += src[i];
            dst[x] = sum / float(x1 - x0 + 1);
        }
    });
    forEachRow(h, [&](int y) {
        const int y0 = std::max(0, y - radius), y1 = std::min(h - 1, y + radius);
        float* dst = out.row(y);
        for (int x = 0; x < w; ++x) dst[x] = 0;
        for (int i = y0; i <= y1; ++i) {
            const float* src = horizontal.row(i);
            for (int x = 0; x < w; ++x) dst[x] += src[x];
        }
        const float scale = 1.f / float(y1 - y0 + 1);
        for (int x = 0; x < w; ++x) dst[x] *= scale;
    });
    out.replicateEdges();
    return out;
}

Plane gaussian(const Plane& in, float sigma, GaussianMode mode) {
    const int w = in.width, h = in.height, radius = int(std::ceil(3.f * sigma));
    std::vector<float> kernel(size_t(2 * radius + 1));
    for (int i = -radius; i <= radius; ++i)
        kernel[size_t(i + radius)] = std::exp(-0.5f * float(i * i) / (sigma * sigma));
    auto inverseWeights = [&](int size) {
        std::vector<float> inverse(static_cast<size_t>(size));
        for (int i = 0; i < size; ++i) {
            float sum = 0;
            for (int p = std::max(0, i - radius); p <= std::min(size - 1, i + radius); ++p)
                sum += kernel[size_t(p - i + radius)];
            inverse[size_t(i)] = 1.f / sum;
        }
        return inverse;
    };
    const std::vector<float> inverseX = inverseWeights(w), inverseY = inverseWeights(h);
    const bool spread = mode == GaussianMode::Spread;
    Plane horizontal(w, h, in.pad), out(w, h, in.pad);
    forEachRow(h, [&](int y) {
        const float* src = in.row(y);
        float* dst = horizontal.row(y);
        for (int x = 0; x < w; ++x) {
            float sum = 0;
            for (int i = std::max(0, x - radius); i <= std::min(w - 1, x + radius); ++i)
                sum += kernel[size_t(i - x + radius)] * (spread ? src[i] * inverseX[size_t(i)] : src[i]);
            dst[x] = spread ? sum : sum * inverseX[size_t(x)];
        }
    });
    forEachRow(h, [&](int y) {
        float* dst = out.row(y);
        for (int x = 0; x < w; ++x) dst[x] = 0;
        for (int j = std::max(0, y - radius); j <= std::min(h - 1, y + radius); ++j) {
            const float k = kernel[size_t(j - y + radius)] * (spread ? inverseY[size_t(j)] : inverseY[size_t(y)]);
            const float* src = horizontal.row(j);
            for (int x = 0; x < w; ++x) dst[x] += k * src[x];
        }
    });
    return out;
}

}  // namespace vdbmarch::denoising
