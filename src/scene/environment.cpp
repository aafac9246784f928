#include "scene/environment.h"

#include <cmath>

#include "core/error.h"
#include "core/sampling.h"
#include "image/exr_io.h"

namespace vdbmarch {

namespace {
}

Environment::Environment(const EnvironmentDesc& desc, const std::string& what) {
    const Image img = readExr(desc.file);
    if (img.empty()) throw InputError(str(what, " (", desc.file, "): the image is empty"));
    if (img.width != 2 * img.height)
        throw InputError(str(what, " (", desc.file, "): a lat-long map is twice as wide as it is high; this one is ",
                             img.width, "x", img.height));
    std::vector<Color> texels(img.pixelCount());
    size_t bad = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            Color c = img.rgb(x, y);
            for (int k = 0; k < 3; ++k)
                if (!std::isfinite(c[k]) || c[k] < 0) {
                    c[k] = 0;
                    ++bad;
                }
            texels[size_t(y) * size_t(img.width) + size_t(x)] = c;
        }
    if (bad > 0)
        warn(str(what, " (", desc.file, "): ", bad, " texel channel", bad == 1 ? " was" : "s were",
                 " NaN, infinite or negative and became 0"));
    build(std::move(texels), img.width, img.height, desc.scale, desc.rotationDeg);
    if (isBlack()) warn(str(what, " (", desc.file, "): the map is black (or its scale is 0): it gives no light"));
}

Environment::Environment(std::vector<Color> texels, int width, int height, float scale, float rotationDeg) {
    if (width != 2 * height || texels.size() != size_t(width) * size_t(height))
        throw std::logic_error("Environment: texels must be a 2:1 table");
    build(std::move(texels), width, height, scale, rotationDeg);
}

void Environment::build(std::vector<Color> texels, int width, int height, float scale, float rotationDeg) {
    mWidth = width;
    mHeight = height;
    mTexels = std::move(texels);
    for (Color& c : mTexels) {
        c = c * scale;
        if (!isFinite(c)) c = Color(0);  // a huge scale: overflow is not light
    }
    const double a = double(rotationDeg) * PiD / 180;
    mCos = float(std::cos(a));
    mSin = float(std::sin(a));
    // Texel power: radiance x solid angle, the solid angle of row y being
    // (2 pi / width) (cos theta_0 - cos theta_1). Sampling in (u, v) with
    // weights luminance-free average(L) x that solid angle makes the
    // solid-angle pdf p(u, v) / (2 pi^2 sin theta).
    std::vector<float> weights(mTexels.size());
    double sum[3] = {0, 0, 0};
    for (int y = 0; y < height; ++y) {
        const double t0 = PiD * y / height, t1 = PiD * (y + 1) / height;
        const double dOmega = 2 * PiD / width * (std::cos(t0) - std::cos(t1));
        for (int x = 0; x < width; ++x) {
            const Color& c = mTexels[size_t(y) * size_t(width) + size_t(x)];
            for (int k = 0; k < 3; ++k) sum[k] += double(c[k]) * dOmega;
            weights[size_t(y) * size_t(width) + size_t(x)] = float(double(average(c)) * dOmega);
        }
    }
    mIntegral = Color(float(sum[0]), float(sum[1]), float(sum[2]));
    mIntegralAvg = average(mIntegral);
    for (float& w : weights)
        if (!std::isfinite(w)) w = 0;
    mDistribution = PiecewiseConstant2D(weights, width, height);
}

void Environment::directionToUv(const Vec3& d, float& u, float& v) {
    u = float(std::atan2(double(d.x), double(-d.z)) / (2 * PiD));
    if (u < 0) u += 1;
    if (!(u < 1)) u = 0;
    // theta from atan2: near the poles y rounds to +-1 while x and z still
    // hold sin(theta) accurately.
    v = float(std::atan2(std::hypot(double(d.x), double(d.z)), double(d.y)) / PiD);
    if (!(v < 1)) v = std::nextafter(1.f, 0.f);
}

Vec3 Environment::uvToDirection(float u, float v) {
    const double theta = PiD * double(v), phi = 2 * PiD * double(u);
    const double s = std::sin(theta);
    return Vec3(float(s * std::sin(phi)), float(std::cos(theta)), float(-s * std::cos(phi)));
}

const Color& Environment::texel(float u, float v) const {
    const int x = std::min(mWidth - 1, std::max(0, int(u * float(mWidth))));
    const int y = std::min(mHeight - 1, std::max(0, int(v * float(mHeight))));
    return mTexels[size_t(y) * size_t(mWidth) + size_t(x)];
}

Color Environment::radiance(const Vec3& w) const {
    if (!hasMap()) return mConstant;
    float u, v;
    directionToUv(toLocal(w), u, v);
    return texel(u, v);
}

Color Environment::radianceSeen(const Vec3& w) const {
    if (!hasMap()) return mConstant;
    float u, v;
    directionToUv(toLocal(w), u, v);
    const float x = u * float(mWidth) - 0.5f, y = v * float(mHeight) - 0.5f;
    const float fx = std::floor(x), fy = std::floor(y);
    const float tx = x - fx, ty = y - fy;
    auto at = [&](int ix, int iy) -> const Color& {
        ix = ((ix % mWidth) + mWidth) % mWidth;  // azimuth wraps
        iy = std::min(mHeight - 1, std::max(0, iy));
        return mTexels[size_t(iy) * size_t(mWidth) + size_t(ix)];
    };
    const int ix = int(fx), iy = int(fy);
    return (at(ix, iy) * (1 - tx) + at(ix + 1, iy) * tx) * (1 - ty) +
           (at(ix, iy + 1) * (1 - tx) + at(ix + 1, iy + 1) * tx) * ty;
}

bool Environment::sample(float u1, float u2, Vec3& w, float& pdf, Color& radianceOverPdf) const {
    if (!hasMap()) {
        w = sampleUniformSphere(u1, u2);
        pdf = uniformSpherePdf();
        radianceOverPdf = mConstant / pdf;
        return !vdbmarch::isBlack(mConstant);
    }
    if (isBlack()) return false;
    float u, v, puv;
    mDistribution.sample(u1, u2, u, v, puv);
    if (!(puv > 0)) return false;
    w = toWorld(uvToDirection(u, v));
    // The pdf and radiance of the direction as pdf() and radiance() see it:
    // a (u, v) on a texel edge may round into the neighbour on the way to a
    // direction and back, and MIS needs the two to agree exactly.
    pdf = this->pdf(w);
    if (!(pdf > 0) || !std::isfinite(pdf)) return false;
    radianceOverPdf = radiance(w) / pdf;
    return true;
}

float Environment::pdf(const Vec3& w) const {
    if (!hasMap()) return uniformSpherePdf();
    if (isBlack()) return 0;
    float u, v;
    const Vec3 local = toLocal(w);
    directionToUv(local, u, v);
    const double sinTheta = std::hypot(double(local.x), double(local.z)) / double(length(local));
    if (!(sinTheta > 0)) return 0;
    return float(double(mDistribution.pdf(u, v)) / (2 * PiD * PiD * sinTheta));
}

Color Environment::integral() const { return hasMap() ? mIntegral : mConstant * (4 * Pi); }

}  // namespace vdbmarch
