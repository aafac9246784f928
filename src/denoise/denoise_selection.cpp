#include "denoise/denoise_selection.h"

namespace vdbmarch::denoising {

std::vector<Plane> selectCandidates(const std::vector<std::vector<Plane>>& filtered, const std::vector<Plane>& inverse,
                                    const std::vector<Plane>& clamped, const std::vector<Plane>& variance,
                                    int radius, Plane* ownWeight) {
    const size_t candidates = filtered.size(), planes = filtered[0].size();
    const int w = clamped[0].width, h = clamped[0].height;
    std::vector<Plane> risk;
    for (size_t j = 0; j < candidates; ++j) {
        Plane sure(w, h, 0);
        forEachRow(h, [&](int y) {
            for (int x = 0; x < w; ++x) {
                float sum = 0;
                for (size_t c = 0; c < 3; ++c) {
                    const float d = filtered[j][c].at(x, y) - clamped[c].at(x, y);
                    const float s2 = 0.5f * variance[c].at(x, y);
                    sum += d * d - s2 + 2.f * s2 * inverse[j].at(x, y);
                }
                sure.at(x, y) = sum;
            }
        });
        risk.push_back(boxAverage(sure, radius));
    }
    std::vector<Plane> choice(candidates, Plane(w, h, 0));
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            size_t best = 0;
            for (size_t j = 1; j < candidates; ++j)
                if (risk[j].at(x, y) < risk[best].at(x, y)) best = j;
            choice[best].at(x, y) = 1.f;
        }
    });
    for (Plane& c : choice) c = boxAverage(c, radius);
    std::vector<Plane> out(planes, Plane(w, h, 0));
    if (ownWeight) *ownWeight = Plane(w, h, 0);
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            float total = 0;
            for (size_t j = 0; j < candidates; ++j) total += choice[j].at(x, y);
            if (ownWeight) {
                float own = 0;
                for (size_t j = 0; j < candidates; ++j) own += choice[j].at(x, y) * inverse[j].at(x, y);
                ownWeight->at(x, y) = own / total;
            }
            for (size_t c = 0; c < planes; ++c) {
                float v = 0;
                for (size_t j = 0; j < candidates; ++j) v += choice[j].at(x, y) * filtered[j][c].at(x, y);
                out[c].at(x, y) = v / total;
            }
        }
    });
    return out;
}

void estimateOutputVariance(const std::vector<Plane>& variance, const Plane& ownWeight, float restoreSigma,
                            std::vector<float>& out) {
    const int w = variance[0].width, h = variance[0].height;
    const float restored = restoreSigma > 0 ? 1.f / (4.f * 3.14159265f * restoreSigma * restoreSigma) : 0.f;
    out.assign(size_t(w) * size_t(h), 0.f);
    forEachRow(h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            float noise = 0;
            for (size_t c = 0; c < 3; ++c) noise += 0.5f * variance[c].at(x, y);
            out[size_t(y) * size_t(w) + size_t(x)] = noise * (ownWeight.at(x, y) + restored);
        }
    });
}

// NL-means averages each pixel with similar ones wherever they are in the
// search window, which moves light between bright and dim structure at
// scales of several pixels (BENCHMARKS.md). The Gaussian average of
// (clamped - filtered) is added back: only detail finer than the Gaussian is
// the filter's. The light the firefly clamp took is added back spread by a
// wide Gaussian (a faint haze; a narrow one turns fireflies into blobs): the
// image keeps its energy.
void restoreLocalMeans(std::vector<Plane>& selected, const std::vector<Plane>& clamped,
                       const std::vector<Plane>& clampedLight, const DenoiseOptions& options) {
    const int w = selected[0].width, h = selected[0].height;
    for (int c = 0; c < 3; ++c) {
        const size_t k = size_t(c);
        if (options.restoreSigma > 0) {
            Plane change(w, h, 0);
            forEachRow(h, [&](int y) {
                for (int x = 0; x < w; ++x) change.at(x, y) = clamped[k].at(x, y) - selected[k].at(x, y);
            });
            const Plane restored = gaussian(change, options.restoreSigma, GaussianMode::Average);
            forEachRow(h, [&](int y) {
                for (int x = 0; x < w; ++x) selected[k].at(x, y) += restored.at(x, y);
            });
        }
        if (options.suppressFireflies && options.fireflySigma > 0) {
            const Plane spread = gaussian(clampedLight[k], options.fireflySigma, GaussianMode::Spread);
            forEachRow(h, [&](int y) {
                for (int x = 0; x < w; ++x) selected[k].at(x, y) += spread.at(x, y);
            });
        }
    }
}

}  // namespace vdbmarch::denoising
