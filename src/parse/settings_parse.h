// The scene's settings objects ("render", "experiments", "photons",
// "cache"), read by parseSceneJson. Internal to src/parse.
#pragma once

#include "parse/json_reader.h"
#include "parse/scene_desc.h"

namespace vdbmarch {

RenderSettings parseRender(const JsonReader& r);
ExperimentSettings parseExperiments(const JsonReader& r);
PhotonSettings parsePhotons(const JsonReader& r);
CacheSettings parseCache(const JsonReader& r);

}  // namespace vdbmarch
