#include "volume/vdb_read_guard.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <vector>

#include "core/memory.h"

namespace vdbmarch {

double vdbCheckTimeout(uint64_t bytes, double readBytesPerSecond) {
    const double decode = double(bytes) / 20e6;
    const double read = readBytesPerSecond > 0 ? double(bytes) / readBytesPerSecond : 0.0;
    return 8 + decode + 10 * read;
}

double measureReadSpeed(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return 0;
    constexpr size_t Limit = size_t(64) << 20, Chunk = size_t(1) << 20;
    std::vector<char> buf(Chunk);
    size_t total = 0;
    const auto start = std::chrono::steady_clock::now();
    while (total < Limit) {
        const ssize_t got = ::read(fd, buf.data(), Chunk);
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) break;
        total += size_t(got);
    }
    ::close(fd);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return total == 0 ? 0.0 : double(total) / std::max(seconds, 1e-6);
}

std::unique_ptr<FatalGuard> guardVdbRead(const std::string& path) {
    if (FatalGuard::active()) return nullptr;  // the outer guard covers this read
    struct stat st {};
    const uint64_t bytes = ::stat(path.c_str(), &st) == 0 ? uint64_t(st.st_size) : 0;
    const double seconds = vdbCheckTimeout(bytes, bytes ? measureReadSpeed(path) : 0.0);
    const uint64_t available = availableMemoryBytes(), resident = residentMemoryBytes();
    const uint64_t growth = available > resident ? (available - resident) / 10 * 9 : 0;
    return std::make_unique<FatalGuard>(path + ": damaged VDB file: reading it", seconds, growth);
}

}  // namespace vdbmarch
