// libFuzzer harness: the scene parser (JSON text -> SceneDesc) and the --set
// override path. Any input may be refused with InputError or IoError (a
// message naming the file and key); anything else escaping, a crash, a hang
// or a sanitizer report is a finding. Built by tools/fuzz.sh.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "parse/scene_desc.h"
#include "parse/scene_json.h"

using namespace vdbmarch;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    // The input is a scene document, optionally followed by a line
    // "\n#set key.path=value" applied as a command-line override.
    const size_t cut = text.rfind("\n#set ");
    const std::string doc = cut == std::string::npos ? text : text.substr(0, cut);
    try {
        SceneDesc d = parseSceneText(doc, "fuzz.json");
        (void)d;
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    if (cut != std::string::npos) {
        try {
            nlohmann::json j = nlohmann::json::parse(doc);
            applyOverride(j, text.substr(cut + 6));
            SceneDesc d = parseSceneText(j.dump(), "fuzz.json");
            (void)d;
        } catch (const nlohmann::json::exception&) {  // not JSON at all: the parser above refused it
        } catch (const InputError&) {
        } catch (const IoError&) {
        }
    }
    return 0;
}
