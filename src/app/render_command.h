// `vdbmarch render`: a scene (or a bare .vdb) to EXR, with an optional PNG
// preview, statistics JSON and the effective scene.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "app/command_line.h"

namespace vdbmarch {

struct RenderArgs {
    std::string input, output, png, res, stats, saveScene, cache;
    std::string tile, crop, passes;  // --tile I/N, --crop x0,y0,x1,y1, --passes FIRST-END (app/tiles.h)
    bool force = false, quiet = false, noProgress = false;
    bool preview = false;  // --preview: a quick look (previewOverrides in render_command.cpp)
    std::optional<double> timeBudget;  // --time
    std::vector<std::string> sets;     // --set key.path=value
    std::string frames;                // --frames A-B[:STEP] or N (parse/frames.h); empty: no frames
    // Scene overrides (renderSceneOptions); unset ones keep the scene's values.
    std::string method, li, aovs;
    std::optional<int> spp, threads, raySamples, shOrder;
    std::optional<long long> seed;
    std::optional<double> step, exposure, noise;
    bool denoise = false, noDenoise = false;  // --denoise, --no-denoise (render.denoise on / off)
    // Checkpoints (docs/farm.md, "Checkpoints"): the state file, written every
    // checkpointEvery seconds and when a signal asks the render to stop;
    // --resume names one that must exist. Removed when the render completes
    // unless keepCheckpoint.
    std::string checkpoint, resume;
    std::optional<double> checkpointEvery;
    bool keepCheckpoint = false;
};

// The exit status of a render stopped by SIGTERM, SIGINT or SIGUSR1 after
// writing its checkpoint (EX_TEMPFAIL of sysexits.h): run the same command
// again to resume.
constexpr int ExitCheckpointed = 75;
// Seconds between checkpoints unless --checkpoint-every says otherwise.
constexpr double DefaultCheckpointSeconds = 300;

// The options of `render` that override scene keys (--spp -> render.spp, ...).
const SceneOptionTable<RenderArgs>& renderSceneOptions();

// Renders once, or each frame of --frames in turn.
int runRender(const RenderArgs& args);

}  // namespace vdbmarch
