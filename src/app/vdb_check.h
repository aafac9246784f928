// Damaged VDB files must never crash or hang a render: OpenVDB's reader
// trusts the sizes and compressed blocks it reads (a few changed bytes can
// make it write past a buffer), so the commands read every VDB file they are
// about to open once in a separate process first. A crash, a hang or an
// error there becomes one InputError naming the file; the render itself then
// reads a file that read cleanly. (Truncated files are refused in-process,
// by the grid extent check of volume/vdb_medium.cpp.)
#pragma once

#include <string>
#include <vector>

#include "parse/scene_desc.h"

namespace vdbmarch {

// Runs `vdbmarch check PATH` (this executable) in a child process and waits
// for it, at most timeoutSeconds (0: automatic, from the file size). Throws
// InputError naming the file when it crashed, hung or failed, with the
// child's message.
void checkVdbFileIsolated(const std::string& path, double timeoutSeconds = 0);

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
