// The heap on transparent huge pages, for the whole vdbmarch process.
// OpenVDB allocates every leaf of a grid it reads on its own (2 KiB for a
// float leaf), and the first touch of each 4 KiB page is a page fault: with
// huge pages OpenVDB's own read of the 8x upsampled Disney cloud took 2.5-2.7 s
// instead of 3.8 s, and vdbmarch's load 3.8-4.9 s instead of 5.4-5.7 s
// (docs/memory.md). glibc backs its heap with huge pages only when the
// tunable glibc.malloc.hugetlb=1 is set when the process starts, so the
// command runs itself again once with it.
#pragma once

#include <optional>
#include <string>

namespace vdbmarch {

// What to do at start-up, from the environment (null: the variable is unset).
struct HeapRestartPlan {
    enum class Action { None, Restart, Restore } action = Action::None;
    // Restart: GLIBC_TUNABLES and the saved caller's value for the new
    // process. Restore: GLIBC_TUNABLES to set again (nullopt: unset it).
    std::string tunables, saved;
    std::optional<std::string> restored;
};
HeapRestartPlan planHeapRestart(const char* glibcTunables, const char* savedTunables, const char* vdbmarchHeap);

// Whether the command line (argv[1] the command) reads VDB grids, where the
// heap on huge pages pays: render, bake, bench, info, inspect, and check
// --in-process (the child of each file `check` reads). A restart costs a
// second start of the executable (about 50 ms, its libraries linked again),
// so the others (compare, merge, check's parent, --help) are not restarted.
bool commandReadsGrids(int argc, const char* const* argv);

// Call first in main(). Where commandReadsGrids, replaces the process by
// the same executable with the same arguments (exec keeps the pid,
// descriptors and signal dispositions) and GLIBC_TUNABLES extended by
// glibc.malloc.hugetlb=1; in the restarted process, restores GLIBC_TUNABLES
// as the caller had it, so that the processes it starts see the caller's
// environment. Does nothing where the user set glibc.malloc.hugetlb, with
// VDBMARCH_HEAP=default, off glibc, in sanitizer builds (their allocator is
// not glibc's), or when exec fails.
void restartWithHugePageHeap(int argc, char** argv);

// True in the process restarted by restartWithHugePageHeap (its heap is on
// huge pages where the kernel offers them); reported in `render --stats`.
bool heapOnHugePages();

}  // namespace vdbmarch
