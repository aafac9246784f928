// Reading VDB files in this process, guarded (core/fatal_guard.h): a damaged
// file that crashes, hangs or exhausts memory inside OpenVDB's reader ends the
// command with one message naming the file, and a healthy file is read once.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/fatal_guard.h"

namespace vdbmarch {

// The watchdog's limit for a file of `bytes` on a disk that reads
// `readBytesPerSecond`: 8 s, plus decoding at 20 MB/s (OpenVDB decodes well
// above that), plus ten times the time to read the bytes. A small file is
// refused within about 8 s; a large file on a slow disk keeps its margin.
double vdbCheckTimeout(uint64_t bytes, double readBytesPerSecond);

// Reads up to the first 64 MB of `path` and returns the bytes per second
// (0 when nothing could be read). The reader then finds them in the page cache.
double measureReadSpeed(const std::string& path);

// A guard for reading (and conditioning) `path`: "<path>: damaged VDB file:
// reading it ..." after vdbCheckTimeout of its size and read speed, or when
// the process grows by 90 % of the memory it could still get. Null while
// another guard is active (it covers this read).
std::unique_ptr<FatalGuard> guardVdbRead(const std::string& path);

}  // namespace vdbmarch
