// Uses libpng's simplified API (png_image): it does the setjmp/longjmp error
// handling internally and reports failures as a message, so no C++ object
// lives across a longjmp here.
#include "image/png_io.h"

#include "core/error.h"
#include "core/atomic_file.h"

#include <png.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace vdbmarch {

float linearToSrgb(float v) {
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

float srgbToLinear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

void writePngRgb8(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb) {
    if (width <= 0 || height <= 0)
        throw std::logic_error(str(path, ": cannot write: image is empty (", width, "x", height, ")"));
    if (rgb.size() != size_t(width) * size_t(height) * 3)
        throw std::logic_error(str(path, ": cannot write: pixel buffer does not match ", width, "x", height));

    AtomicFile file(path);
    std::FILE* f = std::fopen(file.tempPath().c_str(), "wb");
    if (!f) throw IoError(str(path, ": cannot write: ", std::strerror(errno)));

    png_image image;
    std::memset(&image, 0, sizeof(image));
    image.version = PNG_IMAGE_VERSION;
    image.width = png_uint_32(width);
    image.height = png_uint_32(height);
    image.format = PNG_FORMAT_RGB;  // 8-bit formats are tagged sRGB by libpng
    bool ok = png_image_write_to_stdio(&image, f, 0, rgb.data(), 0, nullptr) != 0;
    std::string pngMessage = image.message;
    png_image_free(&image);
    // fclose reports deferred write errors such as a full disk.
    bool streamFailed = std::ferror(f) != 0;
    errno = 0;
    bool closed = std::fclose(f) == 0;
    int closeErr = errno;
    if (!ok) throw IoError(str(path, ": cannot write: ", pngMessage));
    if (streamFailed || !closed)
        throw IoError(str(path, ": cannot write: ", std::strerror(closeErr ? closeErr : EIO)));
    file.commit();
}

void writePng(const std::string& path, const Image& img, float exposureStops) {
    if (!std::isfinite(exposureStops))
        throw std::logic_error(str(path, ": cannot write: exposure ", exposureStops, " is not finite"));
    if (img.rgba.size() != img.pixelCount() * 4)
        throw std::logic_error(str(path, ": cannot write: pixel buffer does not match ", img.width,
                             "x", img.height));
    writePngRgb8(path, img.width, img.height, toSrgb8(img, exposureStops));
}

std::vector<uint8_t> toSrgb8(const Image& img, float exposureStops) {
    const float scale = std::exp2(exposureStops);
    std::vector<uint8_t> rgb(img.pixelCount() * 3);
    for (size_t i = 0; i < img.pixelCount(); ++i) {
        for (int c = 0; c < 3; ++c) {
            float v = img.rgba[i * 4 + c] * scale;
            // NaN / inf would otherwise become arbitrary bytes; black is the honest "no value".
            v = std::isfinite(v) ? clamp(linearToSrgb(std::max(v, 0.f)), 0.f, 1.f) : 0.f;
            rgb[i * 3 + c] = uint8_t(std::lround(v * 255.f));
        }
    }
    return rgb;
}

Image readPng(const std::string& path) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw IoError(str(path, ": cannot open: ", std::strerror(errno)));

    png_image image;
    std::memset(&image, 0, sizeof(image));
    image.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_stdio(&image, f)) {
        std::string message = image.message;
        png_image_free(&image);
        std::fclose(f);
        throw InputError(str(path, ": cannot read PNG: ", message));
    }
    image.format = PNG_FORMAT_RGBA;  // converts grey, palette and 16-bit files
    std::vector<uint8_t> bytes(PNG_IMAGE_SIZE(image));
    bool ok = png_image_finish_read(&image, nullptr, bytes.data(), 0, nullptr) != 0;
    std::string message = image.message;
    png_image_free(&image);
    std::fclose(f);
    if (!ok) throw InputError(str(path, ": cannot read PNG: ", message));

    float toLinear[256];
    for (int i = 0; i < 256; ++i) toLinear[i] = srgbToLinear(i / 255.f);
    Image img(int(image.width), int(image.height));
    for (size_t i = 0; i < img.pixelCount(); ++i) {
        for (int c = 0; c < 3; ++c) img.rgba[i * 4 + c] = toLinear[bytes[i * 4 + c]];
        img.rgba[i * 4 + 3] = bytes[i * 4 + 3] / 255.f;
    }
    return img;
}

}  // namespace vdbmarch
