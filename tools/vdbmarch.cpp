// The vdbmarch command: parse options, validate, run, catch. All errors from
// the library arrive as exceptions and leave here as one line on stderr and a
// non-zero exit code; outputs are written atomically, so a failed run leaves
// nothing behind.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <algorithm>
#include <iostream>
#include <sstream>

#include <CLI/CLI.hpp>
#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/atomic_file.h"
#include "image/exr_io.h"
#include "image/metrics.h"
#include "image/png_io.h"
#include "app/bench.h"
#include "illumination/bake.h"
#include "cache/cache_inspect.h"
#include "marchers/marcher.h"
#include "render/render.h"
#include "scene/auto_scene.h"
#include "scene/scene.h"
#include "volume/medium.h"

using namespace vdbmarch;

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
    if (s.size() < suffix.size()) return false;
    for (size_t i = 0; i < suffix.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
    return true;
}

// "--res WxH" as the override of camera.resolution (validated by the parser).
std::string resolutionOverride(const std::string& res) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(res.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X'))
        throw InputError(str("--res ", res, ": expected WIDTHxHEIGHT, e.g. 640x480"));
    return str("camera.resolution=[", w, ",", h, "]");
}

struct RenderArgs {
    std::string input, output, png, method, res, stats, saveScene, cache, li;
    int shOrder = 0, raySamples = 0;
    bool shOrderSet = false, raySamplesSet = false, force = false;
    // Options the user did not give keep the scene's values; given ones are
    // validated by the scene parser like any other key.
    int spp = 0, threads = 0;
    long long seed = 0;
    double step = 0, exposure = 0, timeBudget = 0;
    bool timeSet = false;
    bool sppSet = false, threadsSet = false, seedSet = false, stepSet = false, exposureSet = false;
    bool quiet = false, noProgress = false;
    std::vector<std::string> sets;
};

int runRender(const RenderArgs& a) {
    auto t0 = std::chrono::steady_clock::now();
    if (!endsWith(a.output, ".exr"))
        throw InputError(str("-o ", a.output, ": the output must be an .exr file"));
    if (!a.png.empty() && !endsWith(a.png, ".png"))
        throw InputError(str("--png ", a.png, ": the preview must be a .png file"));
    if (!a.stats.empty() && !endsWith(a.stats, ".json"))
        throw InputError(str("--stats ", a.stats, ": the statistics file must be a .json file"));
    checkWritable(a.output);
    if (!a.png.empty()) checkWritable(a.png);
    if (!a.stats.empty()) checkWritable(a.stats);
    if (!a.saveScene.empty()) checkWritable(a.saveScene);

    // Command-line options are overrides of the scene document, so they are
    // validated by the same parser and recorded in the output.
    std::vector<std::string> overrides = a.sets;
    if (!a.method.empty()) overrides.push_back("render.method=\"" + a.method + "\"");
    if (a.sppSet && a.spp < 1) throw InputError(str("--spp ", a.spp, ": must be at least 1"));
    if (a.seedSet && a.seed < 0) throw InputError(str("--seed ", a.seed, ": must be a non-negative integer"));
    if (a.threadsSet && a.threads < 0) throw InputError(str("--threads ", a.threads, ": must be 0 (all cores) or more"));
    if (a.stepSet && !(a.step > 0 && std::isfinite(a.step)))
        throw InputError(str("--step ", a.step, ": must be a positive length in world units"));
    if (a.timeSet && !(a.timeBudget > 0 && std::isfinite(a.timeBudget)))
        throw InputError(str("--time ", a.timeBudget, ": must be a positive number of seconds"));
    if (a.timeSet && a.sppSet)
        throw InputError("--time and --spp both given: a render is budgeted either by samples or by seconds");
    if (a.sppSet) overrides.push_back(str("render.spp=", a.spp));
    if (a.seedSet) overrides.push_back(str("render.seed=", a.seed));
    if (a.threadsSet) overrides.push_back(str("render.threads=", a.threads));
    if (a.stepSet) overrides.push_back(str("render.step=", a.step));
    if (a.exposureSet) overrides.push_back(str("render.exposure=", a.exposure));
    if (!a.res.empty()) overrides.push_back(resolutionOverride(a.res));
    if (!a.li.empty()) overrides.push_back("render.li=\"" + a.li + "\"");
    if (a.raySamplesSet) overrides.push_back(str("render.ray_samples=", a.raySamples));
    if (a.shOrderSet) overrides.push_back(str("cache.sh_order=", a.shOrder));
    if (!a.cache.empty() && !endsWith(a.cache, ".vdb"))
        throw InputError(str("--cache ", a.cache, ": the cache must be a .vdb file written by vdbmarch bake"));
    if (a.force && a.cache.empty()) throw InputError("--force only applies to --cache");

    SceneDesc desc = endsWith(a.input, ".vdb") ? loadAutoScene(a.input, overrides) : loadSceneFile(a.input, overrides);
    std::unique_ptr<Scene> scene = buildScene(desc);
    double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    RenderOptions options;
    options.illumination.cacheFile = a.cache;
    options.illumination.force = a.force;
    options.progress = !a.quiet && !a.noProgress && isatty(STDERR_FILENO);
    if (a.timeSet) {
        options.timeBudget = a.timeBudget;
        options.runStart = t0;
    }
    RenderResult r = renderImage(*scene, options);
    const RenderCounters& c = r.counters;
    if (c.nonFiniteSamples > 0)
        warn(str(c.nonFiniteSamples, " path sample(s) gave NaN or Inf and were dropped"));

    StringAttributes attrs = {
        {"vdbmarch:version", VDBMARCH_VERSION},
        {"vdbmarch:source", desc.file},
        {"vdbmarch:method", methodName(desc.render.method)},
        {"vdbmarch:spp", std::to_string(r.spp)},
        {"vdbmarch:timeBudget", a.timeSet ? str(a.timeBudget) : std::string("none")},
        {"vdbmarch:seed", std::to_string(desc.render.seed)},
        {"vdbmarch:step", str(scene->step)},
        {"vdbmarch:shadowStep", str(scene->shadowStep)},
        {"vdbmarch:renderSeconds", str(r.seconds)},
        {"vdbmarch:scene", desc.jsonText},
    };
    writeExr(a.output, r.image, attrs);
    if (!a.saveScene.empty()) writeTextFileAtomic(a.saveScene, prettySceneJson(desc) + "\n");
    if (!a.png.empty()) writePng(a.png, r.image, desc.render.exposure);
    double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!a.stats.empty()) {
        nlohmann::json s;
        s["seconds"] = {{"load", loadSeconds}, {"render", r.seconds}, {"photons_and_cache", r.illuminationSeconds},
                        {"total", total}};
        s["photons"] = r.photons;
        s["cache_cells"] = r.cacheCells;
        s["threads"] = r.threads;
        s["method"] = methodName(desc.render.method);
        s["spp"] = r.spp;
        if (a.timeSet) s["time_budget"] = a.timeBudget;
        s["resolution"] = {r.image.width, r.image.height};
        s["step"] = scene->step;
        s["shadow_step"] = scene->shadowStep;
        s["counters"] = {{"camera_rays", c.cameraRays},         {"surface_hits", c.surfaceHits},
                         {"march_samples", c.marchSamples},     {"li_samples", c.liSamples},
                         {"shadow_rays", c.shadowRays},
                         {"shadow_samples", c.shadowSamples},   {"non_finite_samples", c.nonFiniteSamples},
                         {"marched_length", c.marchedLength},   {"skipped_empty_length", c.skippedLength}};
        writeTextFileAtomic(a.stats, s.dump(2) + "\n");
    }
    if (!a.quiet)
        std::fprintf(stderr, "vdbmarch: %dx%d, %d spp, method %s, step %g: rendered in %.3f s (%sload %.3f s, total %.3f s) -> %s%s%s\n",
                     r.image.width, r.image.height, r.spp, methodName(desc.render.method), double(scene->step),
                     r.seconds,
                     r.illuminationSeconds > 0
                         ? str("photons and cache ", std::round(r.illuminationSeconds * 1000) / 1000, " s, ").c_str()
                         : "",
                     loadSeconds, total, a.output.c_str(), a.png.empty() ? "" : ", ", a.png.c_str());
    return 0;
}

int runCompare(const std::string& a, const std::string& b, const std::string& diff) {
    if (!diff.empty()) checkWritable(diff);
    Image ia = readExr(a), ib = readExr(b);
    ImageErrorStats s = compareImages(ia, ib);
    std::printf("rmse %.6g\nrelmse %.6g\nmean_abs_rel_error %.6g\nmean_test %.6g\nmean_reference %.6g\n"
                "rmse_over_mean %.6g\nnonfinite_test %zu\nnonfinite_reference %zu\npixels %zu\n",
                s.rmse, s.relMse, s.meanAbsRelError, s.meanA, s.meanB, s.meanB != 0 ? s.rmse / s.meanB : 0.0,
                s.nonFiniteA, s.nonFiniteB, s.pixels);
    if (!diff.empty()) writeFalseColorDiff(diff, ia, ib);
    return 0;
}

struct BenchArgs {
    std::string scene, methods = "uniform,reference", budgets = "1,2,4,8", vdbSteps = "4,2,1,0.5", out, reference, res;
    std::string strip;
    bool seconds = false, stripNoReference = false;
    int referenceSpp = 256, repeats = 1, stripWidth = 2000;
    std::vector<std::string> sets;
};

std::vector<std::string> splitList(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string item; std::getline(ss, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

int runBenchCommand(const BenchArgs& a) {
    std::vector<std::string> overrides = a.sets;
    if (!a.res.empty()) overrides.push_back(resolutionOverride(a.res));
    SceneDesc desc = endsWith(a.scene, ".vdb") ? loadAutoScene(a.scene, overrides) : loadSceneFile(a.scene, overrides);
    BenchOptions o;
    o.methods = splitList(a.methods);
    for (const auto& m : o.methods) {
        Method known;
        if (m != "vdb_render" && !parseMethod(m, known))
            throw InputError(str("--methods: unknown method \"", m, "\""));
    }
    for (const auto& b : splitList(a.budgets)) {
        char* end = nullptr;
        double v = std::strtod(b.c_str(), &end);
        if (*end != 0) throw InputError(str("--budgets: \"", b, "\" is not a number"));
        o.budgets.push_back(v);
    }
    o.vdbRenderSteps.clear();
    for (const auto& b : splitList(a.vdbSteps)) {
        char* end = nullptr;
        double v = std::strtod(b.c_str(), &end);
        if (*end != 0) throw InputError(str("--vdb-render-steps: \"", b, "\" is not a number"));
        o.vdbRenderSteps.push_back(v);
    }
    if (a.referenceSpp < 2) throw InputError(str("--reference-spp ", a.referenceSpp, ": must be at least 2"));
    if (a.repeats < 1) throw InputError(str("--repeats ", a.repeats, ": must be at least 1"));
    if (!a.strip.empty() && !endsWith(a.strip, ".png"))
        throw InputError(str("--strip ", a.strip, ": the strip must be a .png file"));
    if (a.stripWidth < 1) throw InputError(str("--strip-width ", a.stripWidth, ": must be a positive number of pixels"));
    o.stripPath = a.strip;
    o.stripReference = !a.stripNoReference;
    o.stripMaxWidth = a.stripWidth;
    o.budgetSeconds = a.seconds;
    o.outDir = a.out;
    o.referencePath = a.reference;
    o.referenceSpp = a.referenceSpp;
    o.repeats = a.repeats;
    BenchResult r = runBench(desc, o);
    std::printf("reference: %s", r.referenceImage.c_str());
    if (r.referenceNoiseRmse > 0) std::printf(" (estimated noise RMSE %.5g)", r.referenceNoiseRmse);
    std::printf("\nwrote %s, %s%s%s%s%s\n", r.csvPath.c_str(), r.tablePath.c_str(), r.plotPath.empty() ? "" : ", ",
                r.plotPath.c_str(), r.stripPath.empty() ? "" : ", ", r.stripPath.c_str());
    return 0;
}

struct BakeArgs {
    std::string input, output, stats;
    long long photons = 0;
    int k = 0, shOrder = 0, threads = 0;
    double quality = 0, minCell = 0;
    long long seed = 0;
    bool photonsSet = false, kSet = false, shOrderSet = false, qualitySet = false, minCellSet = false,
         seedSet = false, threadsSet = false, adaptive = false, uniform = false, quiet = false;
    std::vector<std::string> sets;
};

int runBake(const BakeArgs& a) {
    if (!endsWith(a.output, ".vdb")) throw InputError(str("-o ", a.output, ": the cache must be a .vdb file"));
    if (!a.stats.empty() && !endsWith(a.stats, ".json"))
        throw InputError(str("--stats ", a.stats, ": the statistics file must be a .json file"));
    if (a.adaptive && a.uniform) throw InputError("--adaptive and --uniform both given");
    checkWritable(a.output);
    if (!a.stats.empty()) checkWritable(a.stats);
    // Options are overrides of the scene's "photons" and "cache" keys, so
    // the scene parser validates them like any other key.
    std::vector<std::string> overrides = a.sets;
    if (a.photonsSet) overrides.push_back(str("photons.count=", a.photons));
    if (a.kSet) overrides.push_back(str("photons.k=", a.k));
    if (a.shOrderSet) overrides.push_back(str("cache.sh_order=", a.shOrder));
    if (a.qualitySet) overrides.push_back(str("cache.quality=", a.quality));
    if (a.minCellSet) overrides.push_back(str("cache.min_cell=", a.minCell));
    if (a.adaptive) overrides.push_back("cache.adaptive=true");
    if (a.uniform) overrides.push_back("cache.adaptive=false");
    if (a.seedSet) overrides.push_back(str("render.seed=", a.seed));
    if (a.threadsSet) overrides.push_back(str("render.threads=", a.threads));
    SceneDesc desc = endsWith(a.input, ".vdb") ? loadAutoScene(a.input, overrides) : loadSceneFile(a.input, overrides);
    std::unique_ptr<Scene> scene = buildScene(desc);
    int threads = desc.render.threads > 0 ? desc.render.threads : tbb::info::default_concurrency();
    tbb::task_arena arena(threads);
    BakeResult r;
    arena.execute([&] { r = bakeRadianceCache(*scene, desc.photons, desc.cache); });
    r.cache.save(a.output);
    const RadianceCache& c = r.cache;
    if (!a.stats.empty()) {
        nlohmann::json s;
        s["seconds"] = {{"trace", r.traceSeconds}, {"kd_tree", r.treeSeconds}, {"topology", r.topologySeconds},
                        {"estimate", r.estimateSeconds}, {"total", r.totalSeconds}};
        s["threads"] = threads;
        s["photon_paths"] = r.paths;
        s["photons"] = c.info.photons;
        s["direct_photons"] = r.directPhotons;
        s["cells"] = c.cells.size();
        s["levels"] = c.levels;
        s["sh_order"] = c.info.shOrder;
        s["bytes"] = {{"photon_map", r.photonBytes}, {"cache", r.cacheBytes}};
        writeTextFileAtomic(a.stats, s.dump(2) + "\n");
    }
    if (!a.quiet)
        std::fprintf(stderr,
                     "vdbmarch: %zu photon paths -> %llu photons (%zu direct) in %.3f s; kd-tree %.3f s; %zu cells "
                     "(%d level(s), SH order %d) in %.3f s; total %.3f s -> %s\n",
                     r.paths, static_cast<unsigned long long>(c.info.photons), r.directPhotons, r.traceSeconds,
                     r.treeSeconds, c.cells.size(), c.levels, c.info.shOrder, r.topologySeconds + r.estimateSeconds,
                     r.totalSeconds, a.output.c_str());
    return 0;
}

struct InspectArgs {
    std::string input, direction, slice, output;
};

Vec3 parseDirection(const std::string& text) {
    float x, y, z;
    char extra;
    if (std::sscanf(text.c_str(), "%f,%f,%f%c", &x, &y, &z, &extra) != 3 || !std::isfinite(x) || !std::isfinite(y) ||
        !std::isfinite(z) || x * x + y * y + z * z == 0)
        throw InputError(str("--direction ", text, ": expected a non-zero vector x,y,z"));
    return normalize(Vec3(x, y, z));
}

int runInspect(const InspectArgs& a) {
    RadianceCache c = RadianceCache::load(a.input);
    if (a.slice.empty() && a.direction.empty()) {
        if (!a.output.empty()) throw InputError("-o needs --direction (a .vdb of L_i) or --slice (a .png)");
        std::printf("%s", cacheSummary(c).c_str());
        return 0;
    }
    if (a.output.empty()) throw InputError("--direction and --slice write a file: give -o");
    Vec3 wo(0);
    if (!a.direction.empty()) wo = parseDirection(a.direction);
    if (!a.slice.empty()) {
        if (!endsWith(a.output, ".png")) throw InputError(str("-o ", a.output, ": a slice is written as .png"));
        char axisName = 0, extra;
        float value;
        if (std::sscanf(a.slice.c_str(), "%c=%f%c", &axisName, &value, &extra) != 2 ||
            (axisName != 'x' && axisName != 'y' && axisName != 'z') || !std::isfinite(value))
            throw InputError(str("--slice ", a.slice, ": expected x=VALUE, y=VALUE or z=VALUE (world units)"));
        checkWritable(a.output);
        float maxL = writeCacheSlice(c, axisName - 'x', value, wo, a.output);
        std::printf("slice %s: L_i %s, log scale from %g to %g (4 decades), black = no cell -> %s\n", a.slice.c_str(),
                    a.direction.empty() ? "averaged over directions" : ("towards " + a.direction).c_str(),
                    double(maxL) * 1e-4, double(maxL), a.output.c_str());
        return 0;
    }
    if (!endsWith(a.output, ".vdb")) throw InputError(str("-o ", a.output, ": L_i for a direction is written as .vdb"));
    checkWritable(a.output);
    c.saveDirectional(a.output, wo);
    std::printf("wrote L_i towards %s as float grid(s) 'Li%s' -> %s\n", a.direction.c_str(),
                c.levels > 1 ? "_level<n>" : "", a.output.c_str());
    return 0;
}

int runInfo(const std::string& file) {
    for (const auto& g : listVdbGrids(file)) std::printf("grid %s\n", g.c_str());
    VdbGridSummary s = summarizeVdb(file, "");
    std::printf("summary of '%s': %zu active voxels, voxel size %g, values [%g, %g] mean %g\n"
                "world bounds [%g %g %g] - [%g %g %g]\n",
                s.gridName.c_str(), s.activeVoxels, double(s.voxelSize), double(s.minValue), double(s.maxValue),
                double(s.meanValue), double(s.worldBounds.lo.x), double(s.worldBounds.lo.y), double(s.worldBounds.lo.z),
                double(s.worldBounds.hi.x), double(s.worldBounds.hi.y), double(s.worldBounds.hi.z));
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    removeTemporaryFilesOnInterrupt();
    CLI::App app{"vdbmarch: physically based ray marching of OpenVDB smoke, clouds and fog"};
    app.set_version_flag("--version", std::string("vdbmarch ") + VDBMARCH_VERSION);
    app.require_subcommand(1);

    RenderArgs ra;
    const std::string methods = methodList();
    CLI::App* render = app.add_subcommand("render", "Render a JSON scene or a bare .vdb file to EXR (and PNG)");
    render->add_option("input", ra.input, "Scene .json, or a .vdb to render with automatic camera and lights")->required();
    render->add_option("-o,--output", ra.output, "Output image (.exr, float RGBA, alpha = 1 - transmittance)")->required();
    render->add_option("--png", ra.png, "Also write an sRGB PNG preview");
    render->add_option("--method", ra.method, "Estimator: " + methods);
    auto flagSet = [](bool& b) { return [&b](const std::string&) { b = true; }; };
    render->add_option("--spp", ra.spp, "Samples per pixel")->each(flagSet(ra.sppSet));
    render->add_option("--time", ra.timeBudget,
                       "Time budget in seconds for the whole run, instead of --spp: whole passes of one sample "
                       "per pixel while the next fits")
        ->each(flagSet(ra.timeSet));
    render->add_option("--res", ra.res, "Resolution WIDTHxHEIGHT");
    render->add_option("--seed", ra.seed, "Random seed")->each(flagSet(ra.seedSet));
    render->add_option("--threads", ra.threads, "Worker threads (0 = all cores)")->each(flagSet(ra.threadsSet));
    render->add_option("--step", ra.step, "March step in world units (default: one voxel)")->each(flagSet(ra.stepSet));
    render->add_option("--exposure", ra.exposure, "PNG exposure in stops")->each([&](const std::string&) { ra.exposureSet = true; });
    render->add_option("--set", ra.sets, "Override a scene key: key.path=value (JSON value), repeatable");
    render->add_option("--stats", ra.stats, "Write timings and counters as JSON");
    render->add_option("--save-scene", ra.saveScene,
                       "Write the effective scene (after --set and options; the generated one for a .vdb) as JSON");
    render->add_option("--li", ra.li,
                       "How marchers estimate L_i: photons (shadow rays + non-direct photons, default) or cache "
                       "(the radiance cache alone: fast, biased preview)");
    render->add_option("--ray-samples", ra.raySamples,
                       "L_i samples per ray segment for transmittance and guided (render.ray_samples)")
        ->each(flagSet(ra.raySamplesSet));
    render->add_option("--sh-order", ra.shOrder, "SH order of the cache built for guided; 0 = scalar cache (cache.sh_order)")
        ->each(flagSet(ra.shOrderSet));
    render->add_option("--cache", ra.cache, "Use this baked cache (vdbmarch bake) instead of building one");
    render->add_flag("--force", ra.force, "Use a --cache baked for another scene (warns)");
    render->add_flag("-q,--quiet", ra.quiet, "No progress bar or summary line");
    render->add_flag("--no-progress", ra.noProgress, "No progress bar");

    std::string ca, cb, cdiff;
    CLI::App* compare = app.add_subcommand("compare", "Error metrics of a test image against a reference (EXR)");
    compare->add_option("test", ca, "Test image (.exr)")->required();
    compare->add_option("reference", cb, "Reference image (.exr)")->required();
    compare->add_option("--diff", cdiff, "Write a false-colour difference PNG");

    BenchArgs ba;
    CLI::App* bench = app.add_subcommand("bench", "Run time against error: methods x budgets against a reference");
    bench->add_option("scene", ba.scene, "Scene .json or .vdb")->required();
    bench->add_option("-o,--output", ba.out,
                      "Output folder: bench.csv and bench.md (seconds, RMSE, relMSE, and the 50th and 95th "
                      "percentiles and p95/p50 of the per-pixel relative error |I-R|/(R+eps), eps = 1% of the "
                      "reference mean, where the reference's alpha >= 0.01: lower p95/p50 = more even quality), "
                      "bench.png, the cached reference")->required();
    bench->add_option("--methods", ba.methods, "Comma-separated methods (default uniform,reference)");
    bench->add_option("--budgets", ba.budgets, "Comma-separated budgets: spp, or seconds with --seconds");
    bench->add_option("--vdb-render-steps", ba.vdbSteps,
                      "Steps in voxels for the method vdb_render (OpenVDB's renderer; default 4,2,1,0.5)");
    bench->add_flag("--seconds", ba.seconds, "Budgets are seconds (whole passes within the time)");
    bench->add_option("--reference", ba.reference, "Reference EXR (default: render one with the reference method)");
    bench->add_option("--reference-spp", ba.referenceSpp, "Samples per pixel of a rendered reference (default 256)");
    bench->add_option("--repeats", ba.repeats, "Runs per point; the median time is kept (default 1)");
    bench->add_option("--res", ba.res, "Resolution WIDTHxHEIGHT");
    bench->add_option("--set", ba.sets, "Override a scene key: key.path=value, repeatable");
    bench->add_option("--strip", ba.strip,
                      "Also write a PNG image strip: a row per method, a column per budget (the median-time run), "
                      "the reference first; tone mapped as the --png preview with render.exposure");
    bench->add_flag("--strip-no-reference", ba.stripNoReference, "Leave the reference column out of the strip");
    bench->add_option("--strip-width", ba.stripWidth,
                      "Largest strip width in pixels; tiles are box-downscaled to fit (default 2000)");

    BakeArgs ka;
    CLI::App* bake = app.add_subcommand("bake", "Trace photons and bake the in-scattered radiance cache to a .vdb");
    bake->add_option("input", ka.input, "Scene .json, or a .vdb (automatic scene)")->required();
    bake->add_option("-o,--output", ka.output, "Output cache (.vdb; one float grid per SH coefficient and level)")->required();
    bake->add_option("--photons", ka.photons, "Photon paths to trace (scene key photons.count)")->each(flagSet(ka.photonsSet));
    bake->add_option("--k", ka.k, "Photons per estimate (photons.k)")->each(flagSet(ka.kSet));
    bake->add_option("--quality", ka.quality, "Grid quality a of s = (aN/(k V))^(1/3) (cache.quality)")->each(flagSet(ka.qualitySet));
    bake->add_option("--sh-order", ka.shOrder, "Spherical-harmonics order K, 0-8 (cache.sh_order)")->each(flagSet(ka.shOrderSet));
    bake->add_flag("--adaptive", ka.adaptive, "Octree-like cache subdivided where photons are dense (cache.adaptive)");
    bake->add_flag("--uniform", ka.uniform, "Uniform cache even if the scene asks for an adaptive one");
    bake->add_option("--min-cell", ka.minCell, "Smallest adaptive cell in world units (cache.min_cell)")->each(flagSet(ka.minCellSet));
    bake->add_option("--seed", ka.seed, "Random seed")->each(flagSet(ka.seedSet));
    bake->add_option("--threads", ka.threads, "Worker threads (0 = all cores)")->each(flagSet(ka.threadsSet));
    bake->add_option("--set", ka.sets, "Override a scene key: key.path=value, repeatable");
    bake->add_option("--stats", ka.stats, "Write timings, counts and memory as JSON");
    bake->add_flag("-q,--quiet", ka.quiet, "No summary line");

    InspectArgs ia;
    CLI::App* inspect = app.add_subcommand("inspect", "Summarise a baked cache, or write L_i for a direction or a slice");
    inspect->add_option("cache", ia.input, "Cache .vdb written by vdbmarch bake")->required();
    inspect->add_option("--direction", ia.direction, "x,y,z: direction the light leaves in (towards the viewer)");
    inspect->add_option("--slice", ia.slice, "x=V, y=V or z=V: a false-colour PNG slice at that world coordinate");
    inspect->add_option("-o,--output", ia.output, "Output: .vdb with --direction alone, .png with --slice");

    std::string infoFile;
    CLI::App* info = app.add_subcommand("info", "List the grids of a .vdb file and summarise its density grid");
    info->add_option("file", infoFile, "VDB file")->required();

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
        std::fprintf(stderr, "vdbmarch: error: %s\nRun with --help for usage.\n", e.what());
        return 2;
    }
    try {
        if (*render) return runRender(ra);
        if (*compare) return runCompare(ca, cb, cdiff);
        if (*info) return runInfo(infoFile);
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
