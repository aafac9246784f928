// render.method = "auto" (the default): the method that measured best at
// equal time for what the scene contains (BENCHMARKS.md, "The automatic
// method"; docs/method.md has the rule and its figures).
#pragma once

#include <string>

#include "parse/scene_desc.h"

namespace vdbmarch {

// The method for `desc` and, in `why`, a short reason for messages.
Method chooseMethod(const SceneDesc& desc, std::string& why);

}  // namespace vdbmarch
