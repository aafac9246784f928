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

#include <string>

#include "render/render.h"

namespace vdbmarch {

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
