// The feature AOVs (render.aovs depth, albedo, normal; docs/aovs.md): one
// delta-tracked free flight along the camera ray to its first real
// collision in a medium or its first visible surface, following perfect
// specular surfaces (glass) to the first non-specular event for albedo and
// normal, as OpenImageDenoise recommends. The same estimator for every
// method, on a random stream of its own, so the beauty never changes.
#pragma once

#include "core/rng.h"
#include "transport/thread_context.h"

namespace vdbmarch {

struct FirstEvent {
    bool hasDepth = false;  // the camera ray met a medium or a surface
    Vec3 depthPoint{0, 0, 0};  // where (before any bend)
    // Throughput to the first non-specular event times its albedo (sigma_s /
    // sigma_t in a medium, the diffuse albedo on a surface); zero when the
    // path leaves the scene or ends on a light first.
    Color albedo{0};
    // Unit direction back along the path at a medium event, the shading
    // normal facing the arriving ray on a diffuse surface, zero otherwise.
    Vec3 normal{0, 0, 0};
};

FirstEvent traceFirstEvent(ThreadContext& ctx, const Ray& cameraRay, Rng& rng);

}  // namespace vdbmarch
