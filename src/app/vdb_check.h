// Damaged VDB files must never crash or hang a render: OpenVDB's reader
// trusts the sizes and compressed blocks it reads (a few changed bytes can
// make it write past a buffer), so the commands read every VDB file they are
// about to open once in a separate process first. A crash, a hang or an
// error there becomes one InputError naming the file; the render itself then
// reads a file that read cleanly. (Truncated files are refused in-process,
// by the grid extent check of volume/vdb_medium.cpp.)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "parse/scene_desc.h"

namespace vdbmarch {

// Runs `vdbmarch check PATH` (this executable) in a child process and waits
// for it, at most timeoutSeconds (0: automatic, vdbCheckTimeout of the file's
// size and this machine's read speed, measured on it). Throws
// InputError naming the file when it crashed, hung or failed, with the
// child's message.
void checkVdbFileIsolated(const std::string& path, double timeoutSeconds = 0);

// The watchdog's limit for a file of `bytes` on a disk that reads
// `readBytesPerSecond`: 8 s, plus decoding at 20 MB/s (OpenVDB decodes well
// above that), plus ten times the time to read the bytes. A small file is
// refused within about 8 s; a large file on a slow disk keeps its margin.
double vdbCheckTimeout(uint64_t bytes, double readBytesPerSecond);

// Reads up to the first 64 MB of `path` and returns the bytes per second
// (0 when nothing could be read). The child then reads those bytes from
// the page cache.
double measureReadSpeed(const std::string& path);

// The VDB files a scene (or a bare .vdb input) opens, each once.
std::vector<std::string> vdbFilesOf(const SceneDesc& desc);

// The vdbmarch executable that runs `check --in-process` (set by the
// command's main, from /proc/self/exe). Until it is set (the library used
// from other programs, the tests), checkVdbFilesIsolated does nothing.
void setVdbCheckExecutable(const std::string& path);

// checkVdbFileIsolated for each file, unless VDBMARCH_TRUST_VDB=1 is set (a
// pipeline that has validated its files can skip the second read).
void checkVdbFilesIsolated(const std::vector<std::string>& files);

}  // namespace vdbmarch
