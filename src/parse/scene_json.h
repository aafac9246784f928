// The scene as a JSON document, for the few places that build or edit one
// (bare .vdb scenes, overrides, --save-scene); everything else sees only the
// plain SceneDesc of scene_desc.h, without nlohmann/json.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "parse/scene_desc.h"

namespace vdbmarch {

// Applies one "key.path=value" override (value parsed as JSON, else string).
void applyOverride(nlohmann::json& doc, const std::string& assignment);
// Parses an already-built document (used for bare .vdb scenes); `frame` as
// for parseSceneText (scene_desc.h).
SceneDesc parseSceneJson(const nlohmann::json& doc, const std::string& file,
                         std::optional<int> frame = std::nullopt);
// The effective document, pretty-printed.
std::string prettySceneJson(const SceneDesc& desc, int indent = 2);

}  // namespace vdbmarch
