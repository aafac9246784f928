// render.method = "auto" (the default): the method that did best at equal
// time for what the scene contains (docs/method.md, "The automatic method",
// has the rule and its figures).
#pragma once

#include <string>

#include "parse/scene_desc.h"

namespace vdbmarch {

// The method for `desc` and, in `why`, a short reason for messages.
Method chooseMethod(const SceneDesc& desc, std::string& why);

}  // namespace vdbmarch
