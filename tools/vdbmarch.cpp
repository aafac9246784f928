// The vdbmarch command: option wiring and dispatch to the commands of
// src/app (one *_command.cpp each). All errors from the library arrive as
// exceptions and leave here as one line on stderr and a non-zero exit code;
// outputs are written atomically, so a failed run leaves nothing behind.
#include <cstdio>
#include <exception>
#include <string>
#include <variant>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "app/bake_command.h"
#include "app/bench_command.h"
#include "app/compare_command.h"
#include "app/huge_page_heap.h"
#include "app/info_command.h"
#include "app/inspect_command.h"
#include "app/merge_command.h"
#include "app/render_command.h"
#include "app/vdb_check.h"
#include "core/atomic_file.h"
#include "core/error.h"

using namespace vdbmarch;

namespace {

// Registers every option of a command's scene-override table; a given value
// lands in its field of `args`, an absent one leaves the field empty.
template <class Args>
void addSceneOptions(CLI::App* command, Args& args, const SceneOptionTable<Args>& table) {
    for (const SceneOption<Args>& o : table)
        std::visit([&](auto field) { command->add_option(o.flag, args.*field, o.help); }, o.field);
}

}  // namespace

int main(int argc, char** argv) {
    // First: a command that reads grids replaces itself by itself, with huge pages for the heap.
    restartWithHugePageHeap(argc, argv);
    removeTemporaryFilesOnInterrupt();
    // `check` and baked caches are read in a child process of this executable.
    {
        char self[4096];
        const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1);
        if (n > 0) setVdbCheckExecutable(std::string(self, size_t(n)));
    }
    CLI::App app{"vdbmarch: physically based ray marching of OpenVDB smoke, clouds and fog"};
    app.set_version_flag("--version", std::string("vdbmarch ") + VDBMARCH_VERSION);
    app.require_subcommand(1);

    RenderArgs ra;
    CLI::App* render = app.add_subcommand("render", "Render a JSON scene or a bare .vdb file to EXR (and PNG)");
    render->add_option("input", ra.input, "Scene .json, or a .vdb to render with automatic camera and lights")->required();
    render->add_option("-o,--output", ra.output, "Output image (.exr, float RGBA, alpha = 1 - transmittance)")->required();
    render->add_option("--png", ra.png, "Also write an sRGB PNG preview");
    addSceneOptions(render, ra, renderSceneOptions());
    render->add_option("--time", ra.timeBudget,
                       "Time budget in seconds for the whole run, instead of --spp: whole sweeps of one sample "
                       "per pixel while the next fits");
    render->add_flag("--denoise", ra.denoise,
                     "Denoise the EXR's RGBA too, keeping the noisy beauty as layer 'noisy' (render.denoise = on; "
                     "the PNG preview is denoised by default)");
    render->add_flag("--no-denoise", ra.noDenoise, "Write the PNG preview noisy too (render.denoise = off)");
    render->add_option("--res", ra.res, "Resolution WIDTHxHEIGHT");
    render->add_option("--set", ra.sets, "Override a scene key: key.path=value (JSON value), repeatable");
    render->add_option("--stats", ra.stats, "Write timings and counters as JSON");
    render->add_option("--save-scene", ra.saveScene,
                       "Write the effective scene (after --set and options; the generated one for a .vdb) as JSON");
    render->add_option("--cache", ra.cache, "Use this baked cache (vdbmarch bake) instead of building one");
    render->add_option("--frames", ra.frames,
                       "Render frames A-B[:STEP] (or one frame N) in turn: '####' in the input, the scene's file "
                       "paths, -o, --png, --stats, --save-scene and --cache is the frame number, zero-padded");
    render->add_flag("--force", ra.force, "Use a --cache baked for another scene (warns)");
    render->add_flag("-q,--quiet", ra.quiet, "No progress bar or summary line");
    render->add_flag("--no-progress", ra.noProgress, "No progress bar");
    render->add_option("--tile", ra.tile,
                       "Render tile I of N (0-based) of a fixed split of the frame into N bands of rows; the EXR's "
                       "data window is the tile (vdbmarch merge assembles tiles)");
    render->add_option("--crop", ra.crop, "Render only pixels [x0, x1) x [y0, y1) of the frame: x0,y0,x1,y1");
    render->add_option("--passes", ra.passes,
                       "Render only the camera samples of photon passes FIRST to END-1 (FIRST-END) of a progressive "
                       "render, keeping each pass's sums for merge");
    render->add_option("--checkpoint", ra.checkpoint,
                       "Save the render's state to this file every --checkpoint-every seconds and when SIGTERM, SIGINT "
                       "or SIGUSR1 arrives (then exit with status 75); resume from it when it exists; removed when "
                       "the render completes");
    render->add_option("--checkpoint-every", ra.checkpointEvery, "Seconds between checkpoints (default 300)");
    render->add_option("--resume", ra.resume, "Resume from this checkpoint, which must exist (then as --checkpoint)");
    render->add_flag("--keep-checkpoint", ra.keepCheckpoint, "Keep the checkpoint file when the render completes");
    render->add_flag("--preview", ra.preview,
                     "A quick look: half the resolution, an eighth of the samples (or of --time), a quarter of the photons");

    CompareArgs ca;
    CLI::App* compare = app.add_subcommand("compare", "Error metrics of a test image against a reference (EXR)");
    compare->add_option("test", ca.test, "Test image (.exr)")->required();
    compare->add_option("reference", ca.reference, "Reference image (.exr)")->required();
    compare->add_option("--diff", ca.diff, "Write a false-colour difference PNG");
    compare->add_option("--layer", ca.layer,
                        "Measure this layer of the test image (its R, G, B and A channels) instead of its RGBA: "
                        "noisy, even or odd of a denoised render");
    compare->add_flag("--identical", ca.identical,
                      "Only check bit-identity of every channel of every pixel (and the windows): exit 0 if "
                      "identical, 1 if not");
    compare->add_flag("--paired", ca.paired,
                      "Check that two renders whose random numbers differ agree: the mean per-pixel difference over "
                      "the image and each quadrant, per channel, within 4 standard errors (exit 0), or not (exit 1)");

    MergeArgs ma;
    CLI::App* merge = app.add_subcommand(
        "merge", "Assemble the tiles of one render (render --tile / --crop) into the whole frame, or fold its parts by "
                 "photon passes (render --passes), checking that they belong together; nothing is written on error");
    merge->add_option("tiles", ma.tiles, "Tile (or part) EXR files")->required();
    merge->add_option("-o,--output", ma.output, "Output image (.exr)")->required();
    merge->add_option("--png", ma.png, "Also write an sRGB PNG preview");
    merge->add_option("--exposure", ma.exposure, "PNG exposure in stops (default: the scene's render.exposure)");
    merge->add_flag("-q,--quiet", ma.quiet, "No summary line");

    BenchArgs ba;
    CLI::App* bench = app.add_subcommand("bench", "Run time against error: methods x budgets against a reference");
    bench->add_option("scene", ba.scene, "Scene .json or .vdb")->required();
    bench->add_option("-o,--output", ba.options.outDir,
                      "Output folder: bench.csv and bench.md (seconds, RMSE, relMSE, and the 50th and 95th "
                      "percentiles and p95/p50 of the per-pixel relative error |I-R|/(R+eps), eps = 1% of the "
                      "reference mean, where the reference's alpha >= 0.01: lower p95/p50 = more even quality), "
                      "bench.png, the cached reference")->required();
    bench->add_option("--methods", ba.methods, "Comma-separated methods, auto and vdb_render among them (default uniform,reference)");
    bench->add_option("--budgets", ba.budgets, "Comma-separated budgets: spp, or seconds with --seconds");
    bench->add_option("--vdb-render-steps", ba.vdbSteps,
                      "Steps in voxels for the method vdb_render (OpenVDB's renderer; default 4,2,1,0.5)");
    bench->add_flag("--seconds", ba.options.budgetSeconds, "Budgets are seconds (whole sweeps of one sample per pixel within the time)");
    bench->add_option("--reference", ba.options.referencePath, "Reference EXR (default: render one with the reference method)");
    bench->add_option("--reference-spp", ba.options.referenceSpp, "Samples per pixel of a rendered reference (default 256)");
    bench->add_option("--repeats", ba.options.repeats, "Runs per point; the median time is kept (default 1)");
    bench->add_option("--res", ba.res, "Resolution WIDTHxHEIGHT");
    bench->add_option("--set", ba.sets, "Override a scene key: key.path=value, repeatable");
    bench->add_option("--strip", ba.options.stripPath,
                      "Also write a PNG image strip: a row per method, a column per budget (the median-time run), "
                      "the reference first; tone mapped as the --png preview with render.exposure");
    bench->add_flag("--strip-no-reference", ba.stripNoReference, "Leave the reference column out of the strip");
    bench->add_option("--strip-width", ba.options.stripMaxWidth,
                      "Largest strip width in pixels; tiles are box-downscaled to fit (default 2000)");

    BakeArgs ka;
    CLI::App* bake = app.add_subcommand("bake", "Trace photons and bake the in-scattered radiance cache to a .vdb");
    bake->add_option("input", ka.input, "Scene .json, or a .vdb (automatic scene)")->required();
    bake->add_option("-o,--output", ka.output, "Output cache (.vdb; one float grid per SH coefficient and level)")->required();
    addSceneOptions(bake, ka, bakeSceneOptions());
    bake->add_flag("--adaptive", ka.adaptive, "Octree-like cache subdivided where photons are dense (cache.adaptive)");
    bake->add_flag("--uniform", ka.uniform, "Uniform cache even if the scene asks for an adaptive one");
    bake->add_option("--set", ka.sets, "Override a scene key: key.path=value, repeatable");
    bake->add_option("--stats", ka.stats, "Write timings, counts and memory as JSON");
    bake->add_option("--frames", ka.frames,
                     "Bake frames A-B[:STEP] (or one frame N) in turn: '####' in the input, the scene's file paths, "
                     "-o and --stats is the frame number, zero-padded");
    bake->add_flag("-q,--quiet", ka.quiet, "No summary line");

    InspectArgs ia;
    CLI::App* inspect = app.add_subcommand("inspect", "Summarise a baked cache, or write L_i for a direction or a slice");
    inspect->add_option("cache", ia.input, "Cache .vdb written by vdbmarch bake")->required();
    inspect->add_option("--direction", ia.direction, "x,y,z: direction the light leaves in (towards the viewer)");
    inspect->add_option("--slice", ia.slice, "x=V, y=V or z=V: a false-colour PNG slice at that world coordinate");
    inspect->add_option("-o,--output", ia.output, "Output: .vdb with --direction alone, .png with --slice");

    CheckArgs cka;
    CLI::App* check = app.add_subcommand(
        "check", "Read every grid of VDB files fully, in a separate process: exit 1 naming each damaged or cut file");
    check->add_option("files", cka.files, "VDB files")->required();
    check->add_flag("--in-process", cka.inProcess, "Read in this process, guarded: a damaged file ends the command with a message naming it (without this flag each file is read in its own process, so one damaged file does not stop the check of the others)");
    check->add_flag("-q,--quiet", cka.quiet, "Print nothing for files that read cleanly");

    InfoArgs fa;
    CLI::App* info = app.add_subcommand("info", "List the grids of a .vdb file and summarise its density grid");
    info->add_option("file", fa.file, "VDB file")->required();

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
        std::fprintf(stderr, "vdbmarch: error: %s\nRun with --help for usage.\n", e.what());
        return 2;
    }
    try {
        if (*render) return runRender(ra);
        if (*compare) return runCompare(ca);
        if (*merge) return runMerge(ma);
        if (*info) return runInfo(fa);
        if (*check) return runCheck(cka);
        if (*bake) return runBake(ka);
        if (*inspect) return runInspect(ia);
        if (*bench) return runBenchCommand(ba);
    } catch (const InputError& e) {
        std::fprintf(stderr, "vdbmarch: error: %s\n", e.what());
        return 1;
    } catch (const IoError& e) {
        std::fprintf(stderr, "vdbmarch: error: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vdbmarch: internal error: %s\n", e.what());
        return 3;
    }
    return 0;
}
