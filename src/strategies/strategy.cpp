#include "strategies/strategy.h"

#include <cmath>

#include "transport/surface_event.h"
#include "transport/tracking.h"

namespace vdbmarch {

float trackingDensity(ThreadContext& ctx, const PathSegment& seg, float t, const MediumPoint& mp) {
    Color tau(0);
    for (int mi : ctx.scene.regions[size_t(seg.region)].media) {
        float integral;
        if (!ctx.queries[size_t(mi)]->densityIntegral(seg.ray, 0.f, t, integral) || !(integral > 0)) continue;
        const Medium& m = *ctx.scene.media[size_t(mi)];
        tau += (m.sigma_a + m.sigma_s) * integral;
    }
    if (seg.spectral.channel < 0) return average(mp.sigma_s) * std::exp(-tau.x);  // grey: one transmittance
    return seg.spectral.mixed(mp.sigma_s * Color(std::exp(-tau.x), std::exp(-tau.y), std::exp(-tau.z)));
}

float distanceWeight(float pdfDistance, float pdfTracking) {
    if (!(pdfDistance > 0)) return 0.f;
    const double a = double(pdfDistance) * pdfDistance, b = double(pdfTracking) * pdfTracking;
    return float(a / (a + b));
}

std::vector<BBox> scatterBoundsOf(const Scene& scene) {
    std::vector<BBox> bounds(scene.regions.size(), BBox{});
    for (size_t r = 0; r < scene.regions.size(); ++r)
        for (int mi : scene.regions[r].media) {
            const Medium& m = *scene.media[size_t(mi)];
            if (!isBlack(m.sigma_s) && !m.isVacuum()) bounds[r].expand(m.worldBounds());
        }
    return bounds;
}

bool openToRegion(const Scene& scene, const Vec3& position, int region) {
    for (const SurfaceInfo& surface : scene.surfaces)
        if (!crossedByShadowRays(surface.material))
            return regionAtRayStart(scene, Ray{position, Vec3(0, 0, 1)}) == region;
    return true;
}

}  // namespace vdbmarch
