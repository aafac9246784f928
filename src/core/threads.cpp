#include "core/threads.h"

#include <tbb/info.h>

namespace vdbmarch {

int resolveThreadCount(int requested) { return requested > 0 ? requested : tbb::info::default_concurrency(); }

}  // namespace vdbmarch
