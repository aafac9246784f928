#include "transport/tracking.h"

#include <algorithm>

namespace vdbmarch {

void regionMajorants(ThreadContext& ctx, int region, const Ray& r, float tEnd, std::vector<MajorantSegment>& out) {
    out.clear();
    const auto& media = ctx.scene.regions[size_t(region)].media;
    auto coefficient = [&](int mi) {
        const Medium& m = *ctx.scene.media[size_t(mi)];
        return majorantSigmaT(m.sigma_a + m.sigma_s);
    };
    // Each medium's segments: its density bounds times its sigma_t.
    auto append = [&](int mi, std::vector<MajorantSegment>& to) {
        const float k = coefficient(mi);
        ctx.queries[size_t(mi)]->forEachDensityBound(r, 0.f, tEnd, [&](const DensityBound& s) {
            to.push_back({s.t0, s.t1, mediumMajorant(s.maxDensity, k)});
            return true;
        });
    };
    if (media.size() == 1) {
        append(media[0], out);
        return;
    }
    // Several media: sum their piecewise-constant majorants.
    std::vector<MajorantSegment> all;
    std::vector<float> cuts;
    std::vector<std::pair<size_t, size_t>> ranges;
    for (int mi : media) {
        const size_t first = all.size();
        append(mi, all);
        for (size_t i = first; i < all.size(); ++i) {
            cuts.push_back(all[i].t0);
            cuts.push_back(all[i].t1);
        }
        ranges.push_back({first, all.size()});
    }
    std::sort(cuts.begin(), cuts.end());
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
        float a = cuts[i], b = cuts[i + 1], mid = 0.5f * (a + b), sum = 0;
        if (!std::isfinite(mid)) mid = a + 1;
        for (const auto& rg : ranges)
            for (size_t j = rg.first; j < rg.second; ++j)
                if (all[j].t0 <= mid && mid < all[j].t1) sum += all[j].sigmaMaj;
        if (sum > 0) out.push_back({a, b, sum});
    }
}

bool hasChromaticExtinction(const Scene& scene) {
    for (const auto& m : scene.media) {
        const Color k = m->sigma_a + m->sigma_s;
        if (k.x != k.y || k.y != k.z) return true;
    }
    return false;
}

}  // namespace vdbmarch
