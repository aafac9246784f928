#include "render/film.h"

#include <string>
#include <utility>

#include "core/error.h"
#include "core/memory.h"

namespace vdbmarch {

void PixelSums::fold(const PhotonPassSums& pass) {
    for (size_t i = 0; i < L.size(); ++i) {
        L[i] += pass.L[i].rounded();
        T[i] += double(float(pass.T[i]));
        oddL[i] += pass.oddL[i].rounded();
        oddT[i] += double(float(pass.oddT[i]));
    }
    if (!pass.E.empty()) {
        if (E.empty()) E.assign(L.size(), Color(0)), oddE.assign(L.size(), Color(0));
        for (size_t i = 0; i < L.size(); ++i) {
            E[i] += pass.E[i].rounded();
            oddE[i] += pass.oddE[i].rounded();
        }
    }
    samples += pass.samples;
}

Image PixelSums::average(int width, int height) const {
    Image img(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t p = size_t(y) * size_t(width) + size_t(x);
            const float inv = 1.f / float(samplesOf(p));
            img.set(x, y, L[p] * inv, clamp(1.f - float(T[p]) * inv, 0.f, 1.f));
        }
    return img;
}

namespace {

// One half's mean image: per pixel `set(img, x, y, p, n)` with n > 0 the
// half's sample count (pixels of no sample in that half stay 0).
template <class SetPixel>
Image halfImage(const PixelSums& s, int width, int height, bool odd, SetPixel&& set) {
    Image img(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t p = size_t(y) * size_t(width) + size_t(x);
            int ne, no;
            halfCounts(0, s.samplesOf(p), ne, no);
            const int n = odd ? no : ne;
            if (n > 0) set(img, x, y, p, n);
        }
    return img;
}

// The beauty's half: the odd-index samples' sums, or the total minus them.
Image halfImage(const PixelSums& s, int width, int height, bool odd) {
    return halfImage(s, width, height, odd, [&](Image& img, int x, int y, size_t p, int n) {
        const Color l = odd ? s.oddL[p] : s.L[p] - s.oddL[p];
        const double t = odd ? s.oddT[p] : s.T[p] - s.oddT[p];
        img.set(x, y, l / float(n), clamp(1.f - float(t / double(n)), 0.f, 1.f));
    });
}

}  // namespace

Image PixelSums::evenHalf(int width, int height) const { return halfImage(*this, width, height, false); }
Image PixelSums::oddHalf(int width, int height) const { return halfImage(*this, width, height, true); }

Image PixelSums::emittedHalf(int width, int height, bool odd) const {
    if (E.empty()) return Image();
    return halfImage(*this, width, height, odd, [&](Image& img, int x, int y, size_t p, int n) {
        img.set(x, y, (odd ? oddE[p] : E[p] - oddE[p]) / float(n), 1.f);
    });
}

AovSums::AovSums(const AovSet& aovs, size_t pixels) {
    if (aovs.depth) {
        depth.assign(pixels, 0.0);
        depthSamples.assign(pixels, 0);
    }
    if (aovs.albedo) albedo.assign(pixels, Color(0));
    if (aovs.normal) normal.assign(pixels, Color(0));
    if (aovs.splitDirect()) direct.assign(pixels, Color(0));
}

uint64_t AovSums::bytesPerPixel(const AovSet& a) {
    return (a.depth ? sizeof(double) + sizeof(uint32_t) + sizeof(float) : 0) +
           (a.albedo ? sizeof(Color) + 3 * sizeof(float) : 0) + (a.normal ? sizeof(Color) + 3 * sizeof(float) : 0) +
           (a.splitDirect() ? sizeof(Color) : 0) + (a.direct ? 3 * sizeof(float) : 0) +
           (a.indirect ? 3 * sizeof(float) : 0);
}

std::vector<ExrLayer> aovLayers(const AovSet& aovs, const AovSums& s, const PixelSums& sums) {
    std::vector<ExrLayer> layers;
    const std::vector<Color>& beauty = sums.L;
    const size_t pixels = beauty.size();
    auto inv = [&](size_t p) { return 1.f / float(sums.samplesOf(p)); };
    auto colorLayer = [&](const char* name, std::vector<std::string> channels, auto value) {
        ExrLayer l{name, std::move(channels), {}};
        l.pixels.reserve(3 * pixels);
        for (size_t p = 0; p < pixels; ++p) {
            const Color c = value(p);
            l.pixels.insert(l.pixels.end(), {c.x, c.y, c.z});
        }
        layers.push_back(std::move(l));
    };
    if (aovs.depth) {
        ExrLayer l{"depth", {"Z"}, std::vector<float>(pixels)};
        for (size_t p = 0; p < pixels; ++p)
            l.pixels[p] = s.depthSamples[p] > 0 ? float(s.depth[p] / double(s.depthSamples[p])) : NoDepth;
        layers.push_back(std::move(l));
    }
    if (aovs.albedo) colorLayer("albedo", {"R", "G", "B"}, [&](size_t p) { return s.albedo[p] * inv(p); });
    if (aovs.normal) colorLayer("normal", {"X", "Y", "Z"}, [&](size_t p) { return s.normal[p] * inv(p); });
    if (aovs.direct) colorLayer("direct", {"R", "G", "B"}, [&](size_t p) { return s.direct[p] * inv(p); });
    if (aovs.indirect)
        colorLayer("indirect", {"R", "G", "B"}, [&](size_t p) { return beauty[p] * inv(p) - s.direct[p] * inv(p); });
    return layers;
}

Film::Film(size_t pixels, const AovSet& aovSet, bool keepEmitted, bool keepPasses)
    : sums(pixels), aovs(aovSet, pixels), mPixels(pixels), mKeepEmitted(keepEmitted), mKeepPasses(keepPasses) {
    open.pass = -1;
}

void Film::closePhotonPass() {
    if (open.pass < 0) return;
    sums.fold(open);
    if (mKeepPasses) passSums.push_back(std::move(open));
    open = PhotonPassSums();
    open.pass = -1;
}

void Film::openPhotonPass(int pass, int samples) {
    if (open.pass != pass) {
        closePhotonPass();
        open.pass = pass;
        open.L.assign(mPixels, ColorSum());
        open.T.assign(mPixels, 0.0);
        open.oddL.assign(mPixels, ColorSum());
        open.oddT.assign(mPixels, 0.0);
        if (mKeepEmitted) {
            open.E.assign(mPixels, ColorSum());
            open.oddE.assign(mPixels, ColorSum());
        }
    }
    open.samples += samples;
}

uint64_t imageMemoryBytes(int width, int height, const AovSet& aovs, bool emitted) {
    // The totals, the open pass's sums, the RGBA result and the AOVs.
    // Each twice: all samples and the odd-index half. The emitted part: its
    // totals and open sums, twice, and its two RGB layers.
    const uint64_t perPixel = 2 * (sizeof(Color) + sizeof(ColorSum) + 2 * sizeof(double)) + 4 * sizeof(float) +
                              sizeof(int) + sizeof(double) + sizeof(int) + AovSums::bytesPerPixel(aovs) +
                              (emitted ? 2 * (sizeof(Color) + sizeof(ColorSum)) + 6 * sizeof(float) : 0);
    return uint64_t(width) * uint64_t(height) * perPixel;
}

void checkImageMemory(int width, int height, const AovSet& aovs, bool emitted) {
    checkMemory(imageMemoryBytes(width, height, aovs, emitted),
                str("camera.resolution = [", width, ", ", height, "]: the image"));
}

}  // namespace vdbmarch
