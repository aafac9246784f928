// Checkpoint files (render --checkpoint, docs/farm.md): a render's state
// (RenderCheckpoint) with what it belongs to. Written whole or not at all
// (AtomicFile), read back only when undamaged and for the same render.
//
// Layout: a line "vdbmarch checkpoint <format>", a line of JSON (identity,
// sample and pass counters, counters, array sizes), the arrays in binary
// (host byte order: a checkpoint resumes on the machine kind that wrote
// it), and the FNV-1a hash of everything before it (8 bytes), which finds a
// truncated or damaged file before anything is parsed.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/stats.h"
#include "render/film.h"

namespace vdbmarch {

struct Illumination;

// Everything a render has accumulated at a sample boundary (the photon pass
// it was at follows from nextSample): samples
// [firstSample, nextSample) of every pixel are in the sums.
struct RenderCheckpoint {
    int nextSample = 0;
    double seconds = 0;   // the run's time so far (counts in --time)
    // The first photons and cache, part of `seconds`, which a render resumed
    // from a file traces again (not kept in checkpoint files).
    double setupSeconds = 0;
    // In memory only, for a render stopped by request: its photons and cache
    // at the pass it stopped in, which a resume in the same process takes
    // over instead of tracing them again (method_pilot.cpp's stages). The
    // resume advances them, so they serve one resume.
    std::shared_ptr<Illumination> illumination;
    RenderCounters counters;
    PixelSums sums{0};
    PhotonPassSums open;                    // the pass being rendered (pass -1: none)
    std::vector<PhotonPassSums> passSums;   // with RenderOptions::photonPassRange: the passes closed so far
    AovSums aovs;
};

// Checkpoints (render --checkpoint, docs/farm.md): at sample boundaries the
// render hands its whole state to `save`, every `everySeconds` and when
// `stopRequested` says so (a signal); then, if a stop was requested, it
// returns with RenderResult::interrupted set. A render given `resume`
// continues from that state: its image is bit-identical to an
// uninterrupted one.
struct CheckpointHooks {
    double everySeconds = 300;
    std::function<void(const RenderCheckpoint&)> save;
    std::function<bool()> stopRequested;
    const RenderCheckpoint* resume = nullptr;
};

// Hands a running render's state to hooks.save: `c` (sample, time and
// counters filled in) with the film's sums lent to it, not copied (a large
// frame's are hundreds of megabytes), and taken back even if saving throws.
void saveCheckpoint(const CheckpointHooks& hooks, RenderCheckpoint& c, Film& film);
// The film of a render resumed from `c`: a copy of its sums.
void resumeFilm(const RenderCheckpoint& c, Film& film);

// What a checkpoint belongs to; every field must match to resume.
struct CheckpointIdentity {
    std::string version;     // VDBMARCH_VERSION
    std::string renderHash;  // scene, settings and cache file (vdbmarch:renderHash)
    std::string window;      // the pixels rendered: "x0,y0,x1,y1"
    std::string budget;      // "spp 64", "time 30 s", "passes 2-4 of 64 spp"
};

void writeCheckpointFile(const std::string& path, const CheckpointIdentity& id, const RenderCheckpoint& c);

// Throws InputError naming the file when it cannot be read, is not a
// checkpoint, is damaged or truncated, or was written for another version,
// scene or settings, window or sample budget (naming both values).
RenderCheckpoint readCheckpointFile(const std::string& path, const CheckpointIdentity& expected);

}  // namespace vdbmarch
