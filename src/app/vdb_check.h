// Damaged VDB files must never crash or hang a command. Media and isosurface
// grids are read once, in this process, under a guard (volume/
// vdb_read_guard.h): a crash, hang or runaway allocation inside OpenVDB's
// reader ends the command with one message naming the file. This file keeps
// the separate-process read for `vdbmarch check` (a damaged file among many
// must not stop the check of the others) and for baked caches (render
// --cache, inspect). Truncated files are refused before reading, by the grid
// extent check of volume/vdb_medium.cpp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "volume/vdb_read_guard.h"

namespace vdbmarch {

// Runs `vdbmarch check PATH` (this executable) in a child process and waits
// for it, at most timeoutSeconds (0: automatic, vdbCheckTimeout of the file's
// size and this machine's read speed, measured on it). Throws
// InputError naming the file when it crashed, hung or failed, with the
// child's message.
void checkVdbFileIsolated(const std::string& path, double timeoutSeconds = 0);

// The vdbmarch executable that runs `check --in-process` (set by the
// command's main, from /proc/self/exe). Until it is set (the library used
// from other programs, the tests), checkVdbFilesIsolated does nothing.
void setVdbCheckExecutable(const std::string& path);

// checkVdbFileIsolated for each file, unless VDBMARCH_TRUST_VDB=1 is set (a
// pipeline that has validated its files can skip the second read).
void checkVdbFilesIsolated(const std::vector<std::string>& files);

}  // namespace vdbmarch
