#include "core/memory.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "core/error.h"

namespace vdbmarch {

namespace {

// cgroup v2 (memory.max) or v1 (memory.limit_in_bytes); 0 when unlimited or absent.
uint64_t cgroupLimit() {
    for (const char* path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
        std::ifstream in(path);
        std::string text;
        if (!(in >> text) || text == "max") continue;
        try {
            const unsigned long long v = std::stoull(text);
            if (v > 0 && v < (1ull << 60)) return v;
        } catch (...) {
        }
    }
    return 0;
}

}  // namespace

uint64_t residentMemoryBytes() {
    std::FILE* f = std::fopen("/proc/self/statm", "r");
    if (!f) return 0;
    unsigned long long size = 0, resident = 0;
    const int got = std::fscanf(f, "%llu %llu", &size, &resident);
    std::fclose(f);
    return got == 2 ? uint64_t(resident) * uint64_t(::sysconf(_SC_PAGESIZE)) : 0;
}

uint64_t peakResidentMemoryBytes() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("VmHWM:", 0) == 0) return uint64_t(std::strtoull(line.c_str() + 6, nullptr, 10)) * 1024;
    return 0;
}

uint64_t availableMemoryBytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
    uint64_t physical = pages > 0 && pageSize > 0 ? uint64_t(pages) * uint64_t(pageSize) : 0;
    const uint64_t limit = cgroupLimit();
    if (limit > 0 && (physical == 0 || limit < physical)) physical = limit;
    return physical;
}

std::string formatBytes(uint64_t bytes) {
    char buf[64];
    if (bytes >= (1ull << 30)) std::snprintf(buf, sizeof buf, "%.1f GiB", double(bytes) / double(1ull << 30));
    else std::snprintf(buf, sizeof buf, "%.0f MiB", std::max(1.0, double(bytes) / double(1ull << 20)));
    return buf;
}

void checkMemory(uint64_t bytes, const std::string& what) {
    const uint64_t available = availableMemoryBytes();
    if (available == 0 || bytes <= available) return;
    throw InputError(str(what, " needs about ", formatBytes(bytes), " of memory; this machine has ",
                         formatBytes(available)));
}

}  // namespace vdbmarch
