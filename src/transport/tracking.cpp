#include "transport/tracking.h"

#include <algorithm>

namespace vdbmarch {

void forEachMediumMajorant(ThreadContext& ctx, int mi, const Ray& r, float tEnd,
                           const std::function<bool(const MajorantSegment&)>& visit) {
    const Medium& m = *ctx.scene.media[size_t(mi)];
    if (!ctx.scene.desc.render.globalMajorant || m.minVoxelSize() == 0) {
        ctx.queries[size_t(mi)]->forEachMajorant(r, 0.f, tEnd, visit);
        return;
    }
    float t0 = 0, t1 = tEnd;
    if (m.maxDensity() > 0 && m.worldBounds().intersect(r, t0, t1) && t1 > t0) visit({t0, t1, m.maxDensity()});
}

void mediumMajorants(ThreadContext& ctx, int mi, const Ray& r, float tEnd, std::vector<MajorantSegment>& out) {
    forEachMediumMajorant(ctx, mi, r, tEnd, [&](const MajorantSegment& s) {
        out.push_back(s);
        return true;
    });
}

void regionMajorants(ThreadContext& ctx, int region, const Ray& r, float tEnd, int channel,
                     std::vector<MajorantSegment>& out) {
    out.clear();
    const auto& media = ctx.scene.regions[size_t(region)].media;
    auto coefficient = [&](int mi) {
        const Medium& m = *ctx.scene.media[size_t(mi)];
        return trackedSigmaT(m.sigma_a + m.sigma_s, channel);
    };
    if (media.size() == 1) {
        float k = coefficient(media[0]);
        mediumMajorants(ctx, media[0], r, tEnd, out);
        for (auto& s : out) s.maxDensity = mediumMajorant(s.maxDensity, k);
        return;
    }
    // Several media: sum their piecewise-constant majorants.
    std::vector<MajorantSegment> all;
    std::vector<float> cuts;
    std::vector<std::pair<size_t, size_t>> ranges;
    for (int mi : media) {
        size_t first = all.size();
        mediumMajorants(ctx, mi, r, tEnd, all);
        float k = coefficient(mi);
        for (size_t i = first; i < all.size(); ++i) {
            all[i].maxDensity = mediumMajorant(all[i].maxDensity, k);
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
                if (all[j].t0 <= mid && mid < all[j].t1) sum += all[j].maxDensity;
        if (sum > 0) out.push_back({a, b, sum});
    }
}

}  // namespace vdbmarch
