#include "app/compare_command.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "image/exr_io.h"
#include "image/metrics.h"

namespace vdbmarch {

namespace {

std::string windowText(const ExrWindow& w) {
    return str("data [", w.data.x0, ", ", w.data.x1, ") x [", w.data.y0, ", ", w.data.y1, ") of ", w.display.width(), "x",
               w.display.height());
}

// Bitwise, channel by channel: NaN payloads and signed zeros count, as a
// render is meant to be reproduced exactly.
int compareIdentical(const CompareArgs& a) {
    const ExrContents t = readExrContents(a.test), r = readExrContents(a.reference);
    if (t.window.data != r.window.data || t.window.display != r.window.display) {
        std::printf("identical no\nwindows differ: %s (%s) against %s (%s)\n", windowText(t.window).c_str(),
                    a.test.c_str(), windowText(r.window).c_str(), a.reference.c_str());
        return 1;
    }
    std::vector<const std::vector<float>*> tp = {&t.image.rgba}, rp = {&r.image.rgba};
    std::vector<std::string> names = {"RGBA"};
    std::vector<size_t> widths = {4};
    auto layerNames = [](const ExrContents& c) {
        std::string s;
        for (const ExrLayer& l : c.layers)
            for (const std::string& ch : l.channels) s += l.name + "." + ch + " ";
        return s;
    };
    const std::string testChannels = layerNames(t), referenceChannels = layerNames(r);
    if (testChannels != referenceChannels) {
        std::printf("identical no\nchannels differ: %s(%s) against %s(%s)\n", testChannels.c_str(), a.test.c_str(),
                    referenceChannels.c_str(), a.reference.c_str());
        return 1;
    }
    for (size_t i = 0; i < t.layers.size(); ++i) {
        tp.push_back(&t.layers[i].pixels);
        rp.push_back(&r.layers[i].pixels);
        names.push_back(t.layers[i].name);
        widths.push_back(t.layers[i].channels.size());
    }
    const size_t pixels = t.image.pixelCount();
    std::vector<char> differs(pixels, 0);
    std::string first;
    for (size_t k = 0; k < tp.size(); ++k)
        for (size_t p = 0; p < pixels; ++p)
            if (std::memcmp(tp[k]->data() + p * widths[k], rp[k]->data() + p * widths[k], widths[k] * sizeof(float))) {
                if (first.empty())
                    first = str(" (first: ", names[k], " at pixel (", t.window.data.x0 + int(p % size_t(t.image.width)),
                                ", ", t.window.data.y0 + int(p / size_t(t.image.width)), "))");
                differs[p] = 1;
            }
    const size_t n = size_t(std::count(differs.begin(), differs.end(), 1));
    size_t channels = 0;
    for (size_t w : widths) channels += w;
    std::printf("identical %s\npixels %zu\nchannels %zu\ndiffering_pixels %zu%s\n", n ? "no" : "yes", pixels, channels,
                n, first.c_str());
    return n ? 1 : 0;
}

// The test image, or its layer `name` as RGBA (alpha 1 where the layer has
// none); an InputError names the layers the file has.
Image testImage(const CompareArgs& a) {
    if (a.layer.empty()) return readExr(a.test);
    const ExrContents c = readExrContents(a.test);
    const ExrLayer* l = findLayer(c.layers, a.layer);
    if (!l) {
        std::string names;
        for (const ExrLayer& other : c.layers) names += (names.empty() ? "" : ", ") + other.name;
        throw InputError(str("--layer ", a.layer, ": ", a.test, " has no such layer (it has: ",
                             names.empty() ? std::string("none") : names, ")"));
    }
    Image out(c.image.width, c.image.height);
    const size_t pixels = out.pixelCount();
    const char* names[] = {"R", "G", "B", "A"};
    for (size_t k = 0; k < 4; ++k) {
        const std::vector<float> v = layerChannel(*l, names[k], pixels);
        if (v.empty() && k < 3 && pixels > 0)
            throw InputError(str("--layer ", a.layer, ": the layer of ", a.test, " has no R, G and B channels"));
        for (size_t p = 0; p < pixels; ++p) out.rgba[4 * p + k] = v.empty() ? 1.f : v[p];
    }
    return out;
}

// Two renders whose random numbers differ agree within 4 standard errors
// per region and channel (exit 0), or not (exit 1).
int comparePaired(const Image& test, const Image& reference) {
    const PairedAgreement p = pairedAgreement(test, reference);
    const char* regions[] = {"image", "top-left", "top-right", "bottom-left", "bottom-right"};
    const char* channels = "RGBA";
    for (int q = 0; q < PairedAgreement::Regions; ++q)
        std::printf("z_%s %.3g %.3g %.3g %.3g\n", regions[q], p.z[q][0], p.z[q][1], p.z[q][2], p.z[q][3]);
    const bool agree = p.maxAbsZ <= 4;
    std::printf("max_abs_z %.3g (%s, %c)\nagree %s\n", p.maxAbsZ, regions[p.region], channels[p.channel],
                agree ? "yes" : "no");
    return agree ? 0 : 1;
}

}  // namespace

int runCompare(const CompareArgs& a) {
    if (!a.layer.empty() && a.identical) throw InputError("--layer and --identical: the identity check reads every layer");
    if (a.identical && a.paired) throw InputError("--identical and --paired: choose one check");
    if (a.identical) {
        if (!a.diff.empty()) throw InputError("--diff and --identical: the identity check writes no image");
        return compareIdentical(a);
    }
    if (!a.diff.empty()) checkWritable(a.diff);
    Image ia = testImage(a), ib = readExr(a.reference);
    if (a.paired) {
        const int rc = comparePaired(ia, ib);
        if (!a.diff.empty()) writeFalseColorDiff(a.diff, ia, ib);
        return rc;
    }
    ImageErrorStats s = compareImages(ia, ib);
    std::printf("rmse %.6g\nrelmse %.6g\nmean_abs_rel_error %.6g\nmean_test %.6g\nmean_reference %.6g\n"
                "rmse_over_mean %.6g\nlow_frequency_error %.6g\nnonfinite_test %zu\nnonfinite_reference %zu\npixels %zu\n",
                s.rmse, s.relMse, s.meanAbsRelError, s.meanA, s.meanB, s.meanB != 0 ? s.rmse / s.meanB : 0.0,
                lowFrequencyError(ia, ib), s.nonFiniteA, s.nonFiniteB, s.pixels);
    if (!a.diff.empty()) writeFalseColorDiff(a.diff, ia, ib);
    return 0;
}

}  // namespace vdbmarch
