// The worker-thread count of a run: one rule for render and bake.
#pragma once

namespace vdbmarch {

// `requested` when positive (render.threads, --threads), else every core
// TBB may use.
int resolveThreadCount(int requested);

}  // namespace vdbmarch
