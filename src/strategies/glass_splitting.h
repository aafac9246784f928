// Glass events of radiance paths (experiments.glass_splitting): a small light
// mirrored in glass is a highlight a thousand times its surroundings'
// brightness, which the Fresnel choice (reflect with chance F, a few
// percent) finds in a few of a pixel's samples. So at a glass event
//  - a camera path's first SplitDielectricEvents glass events follow both
//    outcomes, weighted F and 1 - F (the caller traces the reflection);
//  - every other one counts what its reflection sees at the end of its first
//    segment (a sphere light or the background, times the transmittance)
//    weighted by F: where the reflection crosses no medium that is all it
//    brings, and the path goes on by refraction weighted 1 - F; else the
//    path makes the Fresnel choice and, taking the reflection, skips that
//    light.
// Both have the Fresnel choice's expectation (docs/method.md, "Glass
// highlights"). Other surfaces, and glass with the setting off, are
// sampleSurfaceEvent's.
#pragma once

#include "core/rng.h"
#include "transport/surface_event.h"
#include "transport/thread_context.h"

namespace vdbmarch {

struct PathSurfaceEvent {
    SurfaceEvent event;  // the outcome the path goes on with
    Color weight;        // its weight
    // The reflection to trace beside it, weighted mirrorWeight (split).
    bool split = false;
    SurfaceEvent mirror;
    Color mirrorWeight;
    // Light counted at the event, to be multiplied by the path's throughput:
    // what the reflection sees, with MIS weight 1 (a light hit after a
    // reflection breaks every sphere caustic pattern).
    Color light;
    // The part of `light`'s weight that is the background seen through
    // (alpha: a camera path that sees the background in glass).
    float backgroundSeen = 0;
    // The path took a reflection whose light was counted: it must not count
    // the light or background its next segment ends on.
    bool mirrorCounted = false;
};

// The event at `hit` for a radiance path travelling along d in `region`;
// u: the three uniforms (the Fresnel choice, then the diffuse direction).
// `split`: the path may follow both outcomes of glass here (a camera path's
// first glass events); `seenFromCamera`: the path has not scattered yet (it
// sees the environment map as a backdrop).
PathSurfaceEvent pathSurfaceEvent(ThreadContext& ctx, const SurfaceHit& hit, const Vec3& d, int region, const float u[3],
                                  bool split, bool seenFromCamera, Rng& rng);

}  // namespace vdbmarch
