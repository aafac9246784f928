// The pipeline: scene -> (photons -> cache, later) -> marcher -> image.
#pragma once

#include <functional>
#include <string>

#include "core/stats.h"
#include "image/image.h"
#include "scene/scene.h"

namespace vdbmarch {

struct RenderOptions {
    bool progress = false;  // progress bar on stderr
};

struct RenderResult {
    Image image;
    RenderCounters counters;
    double seconds = 0;   // rendering only
    int threads = 0;      // worker threads used
};

// Renders the scene with scene.desc.render's method, spp, seed and threads.
// Deterministic: each pixel sample has its own random stream, so the image is
// bit-identical for any thread count.
RenderResult renderImage(const Scene& scene, const RenderOptions& options = {});

}  // namespace vdbmarch
