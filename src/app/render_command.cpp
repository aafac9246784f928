#include "app/render_command.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "app/denoise_frame.h"
#include "app/huge_page_heap.h"
#include "app/method_pilot.h"
#include "app/tiles.h"
#include "app/vdb_check.h"
#include "core/atomic_file.h"
#include "core/memory.h"
#include "image/exr_io.h"
#include "image/png_io.h"
#include "parse/frames.h"
#include "parse/method.h"
#include "parse/scene_json.h"
#include "render/checkpoint.h"
#include "render/render.h"
#include "scene/scene.h"
#include "volume/medium.h"

namespace vdbmarch {

const SceneOptionTable<RenderArgs>& renderSceneOptions() {
    static const SceneOptionTable<RenderArgs> table = {
        {"--method", "render.method", "Estimator: auto (the default: chosen from what the scene contains), " + methodList(),
         &RenderArgs::method},
        {"--spp", "render.spp", "Samples per pixel", &RenderArgs::spp},
        {"--seed", "render.seed", "Random seed", &RenderArgs::seed},
        {"--threads", "render.threads", "Worker threads (0 = all cores)", &RenderArgs::threads},
        {"--step", "render.step", "March step in world units (default: one voxel)", &RenderArgs::step},
        {"--exposure", "render.exposure", "PNG exposure in stops", &RenderArgs::exposure},
        {"--li", "render.li",
         "How marchers estimate L_i: path (next-event estimation + a continuation path, and photons for "
         "caustics; default), photons (shadow rays + non-direct photons: the paper) or cache (the radiance "
         "cache alone: fast, biased preview)",
         &RenderArgs::li},
        {"--ray-samples", "render.ray_samples",
         "L_i samples per ray segment for transmittance and guided (render.ray_samples)", &RenderArgs::raySamples},
        {"--aovs", "render.aovs",
         "Extra EXR layers, comma-separated: depth, albedo, normal, direct, indirect (docs/aovs.md)",
         &RenderArgs::aovs},
        {"--noise", "render.noise",
         "Noise target: stop once the estimated RMSE over the image's mean is below this (e.g. 0.02), sampling "
         "only the pixels still above it; --time or --spp, if given, still cap the render (docs/noise.md)",
         &RenderArgs::noise},
        {"--sh-order", "cache.sh_order", "SH order of the cache built for guided; 0 = scalar cache (cache.sh_order)",
         &RenderArgs::shOrder},
    };
    return table;
}

namespace {

// The samples per pixel a render to a noise target stops at when nothing
// else caps it.
constexpr int MaxNoiseTargetSpp = 1 << 16;

// --preview: half the width and height, an eighth of the samples (at least
// one), a quarter of the photons; everything else as the scene says.
std::vector<std::string> previewOverrides(const SceneDesc& d) {
    return {str("camera.resolution=[", std::max(1, d.camera.width / 2), ",", std::max(1, d.camera.height / 2), "]"),
            str("render.spp=", std::max(1, (d.render.spp + 4) / 8)),
            str("photons.count=", std::min<int64_t>(d.photons.count, std::max<int64_t>(1000, d.photons.count / 4)))};
}

// "guided", or "reference (auto: multiple scattering in open media)".
std::string methodLabel(const RenderSettings& r) {
    return r.methodAuto ? str(methodName(r.method), " (auto: ", r.methodReason, ")") : std::string(methodName(r.method));
}

// "; noise 2.1 % (estimated)" for the summary line, with the target's outcome.
std::string noiseSummary(const RenderSettings& rs, const RenderResult& r) {
    if (!r.noise.valid) return "";
    std::string s = str("; noise ", std::round(1000 * r.noise.relative()) / 10, " % (estimated)");
    if (rs.noise > 0)
        s += str(", target ", 100 * rs.noise, " % ", r.reachedNoiseTarget ? "reached" : "not reached", " with ",
                 std::round(r.meanSpp * 10) / 10, " samples per pixel on average");
    return s;
}

// Refuses bad option values and unwritable outputs before anything is loaded.
void validate(const RenderArgs& a) {
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
    if (!a.checkpoint.empty() && !a.resume.empty() && a.checkpoint != a.resume)
        throw InputError(str("--checkpoint ", a.checkpoint, " and --resume ", a.resume,
                             ": a render resumes from and saves to one file; give one of them"));
    if (!a.checkpoint.empty()) checkWritable(a.checkpoint);
    if (!a.resume.empty()) checkWritable(a.resume);
    if (a.checkpointEvery && !(*a.checkpointEvery > 0 && std::isfinite(*a.checkpointEvery)))
        throw InputError(str("--checkpoint-every ", *a.checkpointEvery, ": must be a positive number of seconds"));
    if ((a.checkpointEvery || a.keepCheckpoint) && a.checkpoint.empty() && a.resume.empty())
        throw InputError("--checkpoint-every and --keep-checkpoint need --checkpoint FILE (or --resume FILE)");
    if (a.spp && *a.spp < 1) throw InputError(str("--spp ", *a.spp, ": must be at least 1"));
    if (a.seed && *a.seed < 0) throw InputError(str("--seed ", *a.seed, ": must be a non-negative integer"));
    if (a.threads && *a.threads < 0)
        throw InputError(str("--threads ", *a.threads, ": must be 0 (all cores) or more"));
    if (a.step && !(*a.step > 0 && std::isfinite(*a.step)))
        throw InputError(str("--step ", *a.step, ": must be a positive length in world units"));
    if (a.timeBudget && !(*a.timeBudget > 0 && std::isfinite(*a.timeBudget)))
        throw InputError(str("--time ", *a.timeBudget, ": must be a positive number of seconds"));
    if (a.timeBudget && a.spp)
        throw InputError("--time and --spp both given: a render is budgeted either by samples or by seconds");
    if (a.noise && !(*a.noise >= 1e-4 && *a.noise <= 10))
        throw InputError(str("--noise ", *a.noise, ": must be a relative error between 0.0001 and 10 (e.g. 0.02)"));
    if (a.denoise && a.noDenoise) throw InputError("--denoise and --no-denoise: give one of them");
    parseTileRequest(a.tile, a.crop, a.passes);
}

// The render's peak memory, predicted before any volume is read from what
// the process holds now, each medium's load (volume/medium.h) and the image;
// photons and the cache are checked where they are made (docs/memory.md).
// Refuses a render that cannot fit; returns the prediction.
uint64_t checkRenderMemory(const SceneDesc& desc, const PixelRect& window, bool emitted) {
    uint64_t held = residentMemoryBytes(), peak = held, media = 0;
    for (const MediumDesc& m : desc.media) {
        const MediumMemory need = predictMediumMemory(m);
        peak = std::max(peak, held + need.loading);
        held += need.resident;
        media += need.resident;
    }
    // Rendering adds the image and what the threads, Embree and the EXR
    // writer take (about 8 MB, measured on the sample scenes at 8x8 pixels).
    constexpr uint64_t RenderOverhead = uint64_t(8) << 20;
    const uint64_t image = imageMemoryBytes(window.width(), window.height(), desc.render.aovs, emitted);
    peak = std::max(peak, held + image + RenderOverhead);
    checkMemory(peak, str("this render (media ", formatBytes(media), " once loaded, image ", formatBytes(image),
                          ", with the grids' loading peak and what the process holds)"));
    return peak;
}

// Timings, counts and counters of a finished render (--stats).
std::string statsJson(const RenderArgs& a, const SceneDesc& desc, const Scene& scene, const RenderResult& r,
                      double loadSeconds, double total, uint64_t predictedMemory, double denoiseSeconds,
                      double denoiseReserve, const std::optional<MethodPilot>& pilot) {
    const RenderCounters& c = r.counters;
    nlohmann::json s;
    s["seconds"] = {{"load", loadSeconds}, {"render", r.seconds}, {"photons_and_cache", r.illuminationSeconds},
                    {"total", total}};
    if (denoiseSeconds >= 0) s["seconds"]["denoise"] = denoiseSeconds;
    if (denoiseReserve > 0) s["seconds"]["denoise_reserved"] = denoiseReserve;
    s["photons"] = r.photons;
    s["photon_passes"] = r.photonPasses;
    s["cache_cells"] = r.cacheCells;
    s["threads"] = r.threads;
    s["method"] = methodName(desc.render.method);
    s["method_auto"] = desc.render.methodAuto;
    if (desc.render.methodAuto) s["method_reason"] = desc.render.methodReason;
    if (pilot) {
        nlohmann::json& p = s["method_pilots"] = nlohmann::json::array();
        for (const PilotMeasurement& m : pilot->measured)
            p.push_back({{"method", methodName(m.method)}, {"spp", m.samples}, {"seconds", m.seconds},
                         {"setup_seconds", m.setupSeconds}, {"noise_rmse", m.rmse},
                         {"predicted_noise_rmse", m.predictedRmse}});
    }
    s["spp"] = r.spp;
    s["mean_spp"] = r.meanSpp;
    if (r.noise.valid)
        s["noise_estimate"] = {{"relative", r.noise.relative()}, {"rmse", r.noise.rmse}, {"mean", r.noise.mean}};
    if (desc.render.noise > 0) s["noise_target"] = {{"target", desc.render.noise}, {"reached", r.reachedNoiseTarget}};
    if (a.timeBudget) s["time_budget"] = *a.timeBudget;
    s["resolution"] = {r.image.width, r.image.height};
    s["memory"] = {{"predicted_peak_bytes", predictedMemory},
                   {"peak_bytes", peakResidentMemoryBytes()},
                   {"photon_bytes", r.photonBytes},
                   {"cache_bytes", r.cacheBytes},
                   {"heap_on_huge_pages", heapOnHugePages()}};
    s["step"] = scene.step;
    s["shadow_step"] = scene.shadowStep;
    s["counters"] = {{"camera_rays", c.cameraRays},         {"surface_hits", c.surfaceHits},
                     {"march_samples", c.marchSamples},     {"li_samples", c.liSamples},
                     {"shadow_rays", c.shadowRays},
                     {"shadow_samples", c.shadowSamples},   {"non_finite_samples", c.nonFiniteSamples},
                     {"marched_length", c.marchedLength},   {"skipped_empty_length", c.skippedLength}};
    return s.dump(2) + "\n";
}

// The scene overrides the command line gives. Command-line options are
// overrides of the scene document, so they are validated by the same parser
// and recorded in the output.
std::vector<std::string> commandLineOverrides(const RenderArgs& a) {
    std::vector<std::string> overrides = a.sets;
    appendSceneOverrides(a, renderSceneOptions(), overrides);
    if (!a.res.empty()) overrides.push_back(resolutionOverride(a.res));
    // A noise target given here is the budget: the scene's spp no longer caps it.
    if (a.noise && !a.spp && !a.timeBudget) overrides.push_back(str("render.spp=", MaxNoiseTargetSpp));
    if (a.denoise) overrides.push_back("render.denoise=\"on\"");
    if (a.noDenoise) overrides.push_back("render.denoise=\"off\"");
    return overrides;
}

// The scene with the command line's overrides; with --preview, loaded again
// with the preview's on top (they depend on the scene's own values).
SceneDesc loadRenderScene(const RenderArgs& a, std::vector<std::string>& overrides, std::optional<int> frame) {
    SceneDesc desc = loadSceneInput(a.input, overrides, frame);
    if (a.preview) {
        // A quick look: the same scene with a quarter of the pixels, an
        // eighth of the samples (or of the time) and a quarter of the photons.
        const std::vector<std::string> p = previewOverrides(desc);
        overrides.insert(overrides.end(), p.begin(), p.end());
        desc = loadSceneInput(a.input, overrides, frame);
    }
    return desc;
}

// Whether the frame is denoised in this process (not after merge).
bool denoisesHere(const RenderArgs& a, RenderSettings::Denoise mode) {
    return mode == RenderSettings::Denoise::On || (mode == RenderSettings::Denoise::Preview && !a.png.empty());
}

// The render's options: budget, window, the halves the denoiser needs and,
// for a timed render denoised here, the time kept back for it.
RenderOptions renderOptions(const RenderArgs& a, const SceneDesc& desc, const TileRequest& tile,
                            const PixelRect& window, std::chrono::steady_clock::time_point t0) {
    RenderOptions options;
    options.illumination.cacheFile = a.cache;
    options.illumination.force = a.force;
    options.progress = !a.quiet && !a.noProgress && isatty(STDERR_FILENO);
    if (a.timeBudget) {
        options.timeBudget = a.preview ? *a.timeBudget / 8 : *a.timeBudget;
        options.runStart = t0;
    }
    if (tile.count > 0 || tile.cropped) options.crop = window;
    if (tile.byPasses()) options.photonPassRange = std::make_pair(tile.firstPass, tile.endPass);
    // The denoiser (docs/denoise.md) works on the two half renders: of the
    // whole frame here, of a tile's after merge (a tile alone would show seams).
    const RenderSettings::Denoise denoiseMode = desc.render.denoise;
    const bool denoiseHere = denoisesHere(a, denoiseMode);
    options.keepHalves = tile.any() ? denoiseMode != RenderSettings::Denoise::Off && !tile.byPasses() : denoiseHere;
    // The emission seen straight is denoised apart (docs/denoise.md), where
    // the scene has emissive media or sphere lights the camera can see.
    options.keepEmitted = (options.keepHalves || (tile.byPasses() && denoiseMode != RenderSettings::Denoise::Off)) &&
                          sceneEmitsLight(desc);
    // A timed render that is denoised here keeps back the denoiser's
    // predicted time (at most half the budget): --time is the whole run's.
    if (options.timeBudget > 0 && denoiseHere && !tile.any()) {
        const DenoiseShape shape{options.keepEmitted, desc.render.aovs.albedo, desc.render.aovs.normal,
                                 desc.render.aovs.depth};
        options.reserveSeconds = std::min(
            predictDenoiseSeconds(window.width(), window.height(), shape, desc.render.threads), 0.5 * options.timeBudget);
        // Adaptive sampling weighs each block's noise by what the denoiser
        // leaves of it (docs/noise.md, "Timed renders").
        options.denoisedVariance = [threads = desc.render.threads](const FrameHalves& f) {
            std::vector<ExrLayer> layers = f.aovs;
            appendHalfLayers(layers, Image(f.even), Image(f.odd), f.emittedEven, f.emittedOdd);
            std::vector<float> variances;
            denoiseFrame(f.even.width, f.even.height, layers, threads, &variances);
            return variances;
        };
    }
    return options;
}

// A render's checkpoint file (--checkpoint, --resume): what identifies the
// render in it, and the state resumed from it. The hooks refer to it, so it
// lives as long as the render.
struct Checkpointing {
    std::string path;
    CheckpointIdentity identity;
    std::optional<RenderCheckpoint> resumed;
};

// Resumes from the checkpoint file when it is there (--resume: it must be),
// and saves to it every --checkpoint-every seconds and on a signal.
void setUpCheckpoints(const RenderArgs& a, const SceneDesc& desc, const TileRequest& tile, const PixelRect& window,
                      Checkpointing& cp, RenderOptions& options) {
    CheckpointIdentity& identity = cp.identity;
    identity.version = VDBMARCH_VERSION;
    identity.renderHash = renderHash(desc, a.cache);
    identity.window = str(window.x0, ",", window.y0, ",", window.x1, ",", window.y1);
    identity.budget = options.timeBudget > 0 ? str("time ", options.timeBudget, " s")
                      : tile.byPasses()      ? str("passes ", a.passes, " of ", desc.render.spp, " spp")
                                             : str("spp ", desc.render.spp);
    if (desc.render.noise > 0) identity.budget += str(", noise ", desc.render.noise);
    if (::access(cp.path.c_str(), F_OK) == 0) {
        cp.resumed = readCheckpointFile(cp.path, identity);
        if (cp.resumed->sums.L.size() != size_t(window.width()) * size_t(window.height()))
            throw InputError(str(cp.path, ": the checkpoint holds ", cp.resumed->sums.L.size(), " pixels, this render ",
                                 window.width() * window.height(), " (damaged)"));
        if (!a.quiet)
            std::fprintf(stderr, "vdbmarch: resuming from %s at sample %d (%.1f s spent)\n", cp.path.c_str(),
                         cp.resumed->nextSample, cp.resumed->seconds);
    } else if (!a.resume.empty()) {
        throw InputError(str("--resume ", a.resume, ": no such checkpoint (render with --checkpoint ", a.resume,
                             " to write one)"));
    }
    CheckpointHooks hooks;
    hooks.everySeconds = a.checkpointEvery.value_or(DefaultCheckpointSeconds);
    hooks.save = [&cp](const RenderCheckpoint& c) { writeCheckpointFile(cp.path, cp.identity, c); };
    hooks.stopRequested = [] { return stopSignal() != 0; };
    hooks.resume = cp.resumed ? &*cp.resumed : nullptr;
    options.checkpoint = std::move(hooks);
    stopGracefullyOnSignals();
}

// Denoises the rendered frame where this process does (not a tile's: merge
// does), the halves joining the layers either way; returns the seconds it
// took, or -1. `preview` becomes the denoised image.
double denoiseRendered(RenderResult& r, const RenderOptions& options, RenderSettings::Denoise mode,
                       const TileRequest& tile, int threads, Image& preview) {
    if (!options.keepHalves) return -1;
    if (r.spp < 2) {
        warn(str("not denoised: the denoiser needs at least 2 samples per pixel (", r.spp, " rendered)"));
        return -1;
    }
    // The halves join the layers, which are the denoiser's input (the AOV
    // features among them). The EXR keeps them with the denoised RGBA and
    // the noisy beauty; a tile keeps its noisy RGBA and the halves for
    // merge; a preview-only EXR drops them again.
    appendHalfLayers(r.layers, std::move(r.evenHalf), std::move(r.oddHalf), r.emittedEven, r.emittedOdd);
    if (tile.any()) return -1;
    const auto d0 = std::chrono::steady_clock::now();
    preview = denoiseFrame(r.image.width, r.image.height, r.layers, threads);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - d0).count();
    if (mode == RenderSettings::Denoise::On) {
        r.layers.push_back(rgbaLayer(NoisyLayer, r.image));
        r.image = preview;
    } else {
        r.layers.erase(std::remove_if(r.layers.begin(), r.layers.end(), isDenoiserInput), r.layers.end());
    }
    return seconds;
}

// The EXR's metadata: how the frame was made, and the scene it was made of.
StringAttributes exrAttributes(const RenderArgs& a, const SceneDesc& desc, const Scene& scene, const TileRequest& tile,
                               const RenderResult& r) {
    StringAttributes attrs = {
        {"vdbmarch:version", VDBMARCH_VERSION},
        {"vdbmarch:source", desc.file},
        {"vdbmarch:method", methodLabel(desc.render)},
        {"vdbmarch:spp", std::to_string(r.spp)},
        {"vdbmarch:photonPasses", std::to_string(r.photonPasses)},
        {"vdbmarch:timeBudget", a.timeBudget ? str(*a.timeBudget) : std::string("none")},
        {"vdbmarch:seed", std::to_string(desc.render.seed)},
        {"vdbmarch:step", str(scene.step)},
        {"vdbmarch:shadowStep", str(scene.shadowStep)},
        {"vdbmarch:renderSeconds", str(r.seconds)},
        {"vdbmarch:scene", desc.jsonText},
        {RenderHashAttribute, renderHash(desc, a.cache)},
        {NoiseTargetAttribute, desc.render.noise > 0 ? str(desc.render.noise) : std::string("none")},
        {"vdbmarch:meanSpp", str(r.meanSpp)},
    };
    for (auto& kv : noiseAttributes(r.noise)) attrs.push_back(std::move(kv));
    attrs.emplace_back(DenoiseAttribute, denoiseModeName(desc.render.denoise));
    if (desc.frame) attrs.emplace_back("vdbmarch:frame", std::to_string(*desc.frame));
    if (!a.cache.empty()) attrs.emplace_back("vdbmarch:cache", a.cache);
    for (auto& kv : tileAttributes(tile, r)) attrs.push_back(std::move(kv));
    return attrs;
}

// The summary line on stderr: what was rendered, how, in how long, and where to.
void printSummary(const RenderArgs& a, const SceneDesc& desc, const Scene& scene, const TileRequest& tile,
                  const RenderResult& r, double loadSeconds, double total, double denoiseSeconds) {
    std::fprintf(stderr, "vdbmarch: %s%dx%d, %s, method %s, step %g: rendered in %.3f s (%sload %.3f s, total %.3f s) -> %s%s%s%s\n",
                 tile.count > 0 ? str("tile ", tile.index, "/", tile.count, " (rows ", r.window.y0, "-", r.window.y1 - 1, ") of ").c_str()
                 : tile.cropped ? str("crop ", a.crop, " of ").c_str()
                 : tile.byPasses() ? str("photon passes ", a.passes, " (samples ", r.firstSample, "-", r.firstSample + r.spp - 1, ") of ").c_str() : "",
                 scene.camera->width(), scene.camera->height(),
                 (r.meanSpp < r.spp - 0.05 ? str(r.spp, " spp (", std::round(r.meanSpp * 10) / 10, " on average)")
                                           : str(r.spp, " spp")).c_str(),
                 methodLabel(desc.render).c_str(), double(scene.step),
                 r.seconds,
                 r.illuminationSeconds > 0
                     ? str("photons and cache ", std::round(r.illuminationSeconds * 1000) / 1000, " s in ",
                           r.photonPasses, r.photonPasses == 1 ? " pass, " : " passes, ").c_str()
                     : "",
                 loadSeconds, total, a.output.c_str(), a.png.empty() ? "" : ", ", a.png.c_str(),
                 (noiseSummary(desc.render, r) +
                  (denoiseSeconds >= 0 ? str("; denoised in ", std::round(denoiseSeconds * 1000) / 1000, " s") : ""))
                     .c_str());
}

// One render: the whole command for one frame (`frame` set by --frames, its
// paths already substituted in `a`) or without frames.
int renderFrame(const RenderArgs& a, std::optional<int> frame) {
    auto t0 = std::chrono::steady_clock::now();
    validate(a);
    std::vector<std::string> overrides = commandLineOverrides(a);
    if (!a.cache.empty() && !endsWith(a.cache, ".vdb"))
        throw InputError(str("--cache ", a.cache, ": the cache must be a .vdb file written by vdbmarch bake"));
    if (a.force && a.cache.empty()) throw InputError("--force only applies to --cache");

    if (!a.cache.empty()) checkVdbFilesIsolated({a.cache});  // a baked cache is a VDB file too
    SceneDesc desc = loadRenderScene(a, overrides, frame);
    const TileRequest tile = parseTileRequest(a.tile, a.crop, a.passes);
    const PixelRect window = windowOf(tile, desc.camera.width, desc.camera.height);
    // The emitted part's sums, where a denoised render of the scene may keep them.
    const bool emitted = desc.render.denoise != RenderSettings::Denoise::Off && sceneEmitsLight(desc);
    checkImageMemory(window.width(), window.height(), desc.render.aovs, emitted);  // before any volume is loaded
    const uint64_t predictedMemory = checkRenderMemory(desc, window, emitted);
    std::unique_ptr<Scene> scene = buildScene(desc);
    double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    RenderOptions options = renderOptions(a, desc, tile, window, t0);
    Checkpointing checkpoint;
    checkpoint.path = a.resume.empty() ? a.checkpoint : a.resume;
    if (!checkpoint.path.empty()) setUpCheckpoints(a, desc, tile, window, checkpoint, options);
    // auto in a timed render of the whole frame: the method chosen by
    // pilots (app/method_pilot.h).
    std::optional<MethodPilot> pilot;
    if (desc.render.methodAuto && options.timeBudget > 0 && !tile.any() && checkpoint.path.empty() && a.cache.empty())
        pilot.emplace();
    RenderResult r = pilot ? renderByPilots(*scene, options, *pilot) : renderImage(*scene, options);
    if (pilot) {
        desc.render.method = pilot->method;
        desc.render.methodReason = scene->desc.render.methodReason =
            str(pilot->reason, "; the rule: ", desc.render.methodReason);
        if (!a.quiet) std::fprintf(stderr, "vdbmarch: %s\n", describePilot(*pilot).c_str());
    }
    if (r.interrupted) {
        if (!a.quiet)
            std::fprintf(stderr, "vdbmarch: stopped by %s after %d samples per pixel; the state is in %s: run the "
                                 "same command to resume (exit status %d)\n",
                         strsignal(stopSignal()), r.firstSample + r.spp, checkpoint.path.c_str(), ExitCheckpointed);
        return ExitCheckpointed;
    }
    if (r.counters.nonFiniteSamples > 0)
        warn(str(r.counters.nonFiniteSamples, " path sample(s) gave NaN or Inf and were dropped"));

    Image preview = r.image;
    const double denoiseSeconds = denoiseRendered(r, options, desc.render.denoise, tile, desc.render.threads, preview);
    const StringAttributes attrs = exrAttributes(a, desc, *scene, tile, r);
    if (tile.byPasses()) r.layers = passLayers(r);
    writeExr(a.output, r.image, attrs, r.layers,
             ExrWindow{r.window, PixelRect{0, 0, scene->camera->width(), scene->camera->height()}});
    if (!a.saveScene.empty()) writeTextFileAtomic(a.saveScene, prettySceneJson(desc) + "\n");
    if (!a.png.empty()) writePng(a.png, preview, desc.render.exposure);
    double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!a.stats.empty()) writeTextFileAtomic(a.stats, statsJson(a, desc, *scene, r, loadSeconds, total, predictedMemory,
                                                                  denoiseSeconds, options.reserveSeconds, pilot));
    if (!checkpoint.path.empty() && !a.keepCheckpoint) std::remove(checkpoint.path.c_str());  // the render is whole
    if (!a.quiet) printSummary(a, desc, *scene, tile, r, loadSeconds, total, denoiseSeconds);
    return 0;
}

// The arguments of one frame: the frame token of every path option replaced.
RenderArgs atFrame(RenderArgs a, int frame) {
    for (std::string* path : {&a.output, &a.png, &a.stats, &a.saveScene, &a.cache, &a.checkpoint, &a.resume})
        *path = substituteFrame(*path, frame);
    return a;
}

}  // namespace

// --frames: each frame rendered as if alone, one after the other, with the
// same seed (docs/farm.md, "Frames"); without it, one render.
int runRender(const RenderArgs& a) {
    const std::vector<std::pair<std::string, std::string>> outputs = {
        {"-o", a.output},          {"--png", a.png},         {"--stats", a.stats}, {"--save-scene", a.saveScene},
        {"--checkpoint", a.checkpoint}, {"--resume", a.resume}};
    if (a.frames.empty()) {
        std::vector<std::pair<std::string, std::string>> paths = outputs;
        paths.emplace_back("--cache", a.cache);
        checkFrameOutputs(paths, 0, "");
        return renderFrame(a, std::nullopt);
    }
    const std::vector<int> frames = parseFrameRange(a.frames);
    checkFrameOutputs(outputs, frames.size(), a.frames);
    validate(atFrame(a, frames.front()));
    checkFrameInputs(a.input, a.sets, frames, {{"--cache", a.cache}});
    // A frame stopped by a signal ends the run; the frames before it are
    // done, and running the command again resumes that frame.
    int status = 0;
    for (int frame : frames) {
        runFrame(frame, [&] { status = renderFrame(atFrame(a, frame), frame); });
        if (status != 0) return status;
    }
    return 0;
}

}  // namespace vdbmarch
