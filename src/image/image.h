// A float RGBA framebuffer: the one in-memory image type shared by the
// renderer, the file writers and the comparison tools.
#pragma once

#include "core/error.h"
#include "core/math.h"

#include <cstddef>
#include <vector>

namespace vdbmarch {

// A rectangle of pixels [x0, x1) x [y0, y1) of a frame, top row 0.
struct PixelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    bool empty() const { return x1 <= x0 || y1 <= y0; }
    bool contains(const PixelRect& r) const { return r.x0 >= x0 && r.y0 >= y0 && r.x1 <= x1 && r.y1 <= y1; }
    bool overlaps(const PixelRect& r) const { return r.x0 < x1 && x0 < r.x1 && r.y0 < y1 && y0 < r.y1; }
    bool operator==(const PixelRect& r) const { return x0 == r.x0 && y0 == r.y0 && x1 == r.x1 && y1 == r.y1; }
    bool operator!=(const PixelRect& r) const { return !(*this == r); }
};

struct Image {
    int width = 0, height = 0;
    std::vector<float> rgba;  // 4 floats per pixel, row-major, top row first

    Image() = default;
    // Zero-initialised (transparent black), so renderers can accumulate into it.
    Image(int w, int h) : width(w), height(h) {
        if (w < 0 || h < 0) throw std::logic_error(str("Image: invalid size ", w, "x", h));
        rgba.assign(size_t(w) * size_t(h) * 4, 0.f);
    }

    size_t pixelCount() const { return size_t(width) * size_t(height); }
    bool empty() const { return width == 0 || height == 0; }

    Color rgb(int x, int y) const {
        const float* p = &rgba[index(x, y)];
        return {p[0], p[1], p[2]};
    }
    float alpha(int x, int y) const { return rgba[index(x, y) + 3]; }
    void set(int x, int y, const Color& c, float a) {
        float* p = &rgba[index(x, y)];
        p[0] = c.x; p[1] = c.y; p[2] = c.z; p[3] = a;
    }

private:
    size_t index(int x, int y) const { return (size_t(y) * size_t(width) + size_t(x)) * 4; }
};

}  // namespace vdbmarch
