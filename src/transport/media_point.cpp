#include "transport/media_point.h"

#include <algorithm>

namespace vdbmarch {

ThreadContext::ThreadContext(const Scene& s) : scene(s) {
    for (const auto& m : s.media) queries.push_back(m->makeQuery());
}

void evalMedia(ThreadContext& ctx, int region, const Vec3& p, MediumPoint& mp) {
    const std::vector<int>& media = ctx.scene.regions[size_t(region)].media;
    mp.phase.clear();
    if (media.size() == 1) {  // the common case, once per march step: no sums
        const int mi = media[0];
        const float d = ctx.queries[size_t(mi)]->density(p);
        if (!(d > 0)) {
            mp.sigma_a = mp.sigma_s = mp.sigma_t = mp.emission = Color(0);
            return;
        }
        const Medium& m = *ctx.scene.media[size_t(mi)];
        mp.sigma_a = min(m.sigma_a * d, Color(MaxCoefficient));
        mp.sigma_s = min(m.sigma_s * d, Color(MaxCoefficient));
        mp.sigma_t = mp.sigma_a + mp.sigma_s;
        mp.emission = Color(0);
        if (m.hasEmission) {
            const float e = ctx.queries[size_t(mi)]->emission(p);
            if (e > 0) {
                const Color le = m.emitted(e);
                for (int c = 0; c < 3; ++c) mp.emission[c] = mp.sigma_a[c] > 0 ? le[c] : 0.f;
            }
        }
        mp.phase.add(mp.sigma_s, m.g);
        return;
    }
    mp.sigma_a = mp.sigma_s = mp.sigma_t = mp.emission = Color(0);
    for (int mi : media) {
        float d = ctx.queries[size_t(mi)]->density(p);
        if (!(d > 0)) continue;
        const Medium& m = *ctx.scene.media[size_t(mi)];
        Color sa = min(m.sigma_a * d, Color(MaxCoefficient)), ss = min(m.sigma_s * d, Color(MaxCoefficient));
        mp.sigma_a += sa;
        mp.sigma_s += ss;
        if (m.hasEmission) {
            float e = ctx.queries[size_t(mi)]->emission(p);
            // Normalised below; the scalar mode keeps its order of products.
            if (e > 0) mp.emission += m.blackbody ? sa * m.emitted(e) : sa * m.emissionColor * e;
        }
        mp.phase.add(ss, m.g);
    }
    mp.sigma_t = mp.sigma_a + mp.sigma_s;
    if (!isBlack(mp.emission))
        for (int c = 0; c < 3; ++c) mp.emission[c] = mp.sigma_a[c] > 0 ? mp.emission[c] / mp.sigma_a[c] : 0.f;
}

void regionIntervals(ThreadContext& ctx, int region, const Ray& r, float tMin, float tMax,
                     std::vector<Interval>& out) {
    out.clear();
    const auto& media = ctx.scene.regions[size_t(region)].media;
    if (media.empty() || !(tMax > tMin)) return;
    if (media.size() == 1) {
        ctx.queries[size_t(media[0])]->activeIntervals(r, tMin, tMax, out);
        return;
    }
    auto& all = ctx.mediaIntervals;
    all.clear();
    for (int mi : media) ctx.queries[size_t(mi)]->activeIntervals(r, tMin, tMax, all);
    std::sort(all.begin(), all.end(), [](const Interval& a, const Interval& b) { return a.t0 < b.t0; });
    for (const auto& iv : all) {
        if (!out.empty() && iv.t0 <= out.back().t1) out.back().t1 = std::max(out.back().t1, iv.t1);
        else out.push_back(iv);
    }
}

}  // namespace vdbmarch
