// A complete scene for a bare .vdb file: the camera frames the grid's world
// bounds, a sun-like directional light and a constant sky light it, and the
// coefficients are chosen from the grid's density range and size so that any
// asset reads as a cloud (optical depth ~6 across its typical chord).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "parse/scene_json.h"

namespace vdbmarch {

// The generated scene as JSON (what --set overrides apply to).
nlohmann::json autoSceneJson(const std::string& vdbPath);

// `vdbPath` is a real file (its frame token already replaced); `frame` is
// recorded, and replaces the token in paths that overrides set.
SceneDesc loadAutoScene(const std::string& vdbPath, const std::vector<std::string>& overrides = {},
                        std::optional<int> frame = std::nullopt);

}  // namespace vdbmarch
