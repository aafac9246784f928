#include "core/atomic_file.h"

#include "core/error.h"

#include <atomic>
#include <csignal>
#include <fstream>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <utility>

namespace vdbmarch {

namespace {

std::atomic<unsigned> gTempCounter{0};

// Temporary files in flight, for the interrupt handler: fixed storage, since
// a signal handler may only touch plain memory and call unlink().
constexpr int MaxLiveTemps = 32;
constexpr size_t MaxTempPath = 4096;
char gLiveTemps[MaxLiveTemps][MaxTempPath];
std::atomic<bool> gLiveUsed[MaxLiveTemps];

int registerTemp(const std::string& path) {
    if (path.size() >= MaxTempPath) return -1;
    for (int i = 0; i < MaxLiveTemps; ++i) {
        bool expected = false;
        if (gLiveUsed[i].compare_exchange_strong(expected, true)) {
            std::memcpy(gLiveTemps[i], path.c_str(), path.size() + 1);
            return i;
        }
    }
    return -1;  // untracked: still removed by the destructor
}

void unregisterTemp(int slot) {
    if (slot >= 0) gLiveUsed[slot].store(false);
}

extern "C" void removeTempsAndReraise(int sig) {
    for (int i = 0; i < MaxLiveTemps; ++i)
        if (gLiveUsed[i].load()) ::unlink(gLiveTemps[i]);
    std::signal(sig, SIG_DFL);
    std::raise(sig);
}

// Splits "a/b/c.exr" into "a/b" and "c.exr"; a bare name lives in ".".
void splitPath(const std::string& path, std::string& dir, std::string& name) {
    size_t slash = path.find_last_of('/');
    if (slash == std::string::npos) {
        dir = ".";
        name = path;
    } else {
        dir = slash == 0 ? "/" : path.substr(0, slash);
        name = path.substr(slash + 1);
    }
}

}  // namespace

AtomicFile::AtomicFile(std::string finalPath) : mFinalPath(std::move(finalPath)) {
    std::string dir, name;
    splitPath(mFinalPath, dir, name);
    if (name.empty()) throw IoError(str(mFinalPath, ": cannot write: not a file name"));
    // pid + per-process counter keeps concurrent writers (threads or
    // processes) from sharing a temporary file.
    mTempPath = str(dir == "/" ? "" : dir, "/.", name, ".tmp-", ::getpid(), "-", gTempCounter++);
    mSlot = registerTemp(mTempPath);
}

AtomicFile::~AtomicFile() {
    if (!mCommitted) ::unlink(mTempPath.c_str());
    unregisterTemp(mSlot);
}

void removeTemporaryFilesOnInterrupt() {
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, removeTempsAndReraise);
}

namespace {
volatile std::sig_atomic_t gStopSignal = 0;
// When the first stop signal came (CLOCK_MONOTONIC, ns; lock-free, so a
// handler may touch it).
std::atomic<long long> gStopSignalNs{0};
static_assert(std::atomic<long long>::is_always_lock_free, "the signal handler needs a lock-free clock stamp");
// One signal is often delivered twice: GNU timeout sends it to its child
// and then to its whole process group, and Slurm signals every process of a
// job step (a wrapper that forwards it adds a second). A repeat within this
// window is the same request, not a second one.
constexpr long long RepeatWindowNs = 1000000000LL;

long long monotonicNs() {
    timespec ts{};
    ::clock_gettime(CLOCK_MONOTONIC, &ts);  // async-signal-safe
    return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

extern "C" void requestStop(int sig) {
    const long long now = monotonicNs();
    if (gStopSignal != 0) {
        if (now - gStopSignalNs.load() < RepeatWindowNs) return;  // a duplicate delivery
        // A second request: stop now, as without checkpoints.
        removeTempsAndReraise(sig == SIGUSR1 ? SIGTERM : sig);
        return;
    }
    gStopSignalNs.store(now);
    gStopSignal = sig;
}
}  // namespace

void stopGracefullyOnSignals() {
    for (int sig : {SIGINT, SIGTERM, SIGUSR1}) std::signal(sig, requestStop);
}

int stopSignal() { return int(gStopSignal); }

void AtomicFile::commit() {
    if (mCommitted) return;
    // fsync before rename: otherwise a crash can leave the new name pointing
    // at an empty file on some file systems.
    int fd = ::open(mTempPath.c_str(), O_RDONLY);
    if (fd < 0)
        throw IoError(str(mFinalPath, ": cannot write: temporary file '", mTempPath,
                          "': ", std::strerror(errno)));
    bool synced = ::fsync(fd) == 0 || errno == EINVAL;  // EINVAL: fs without fsync
    int syncErr = errno;
    ::close(fd);
    if (!synced)
        throw IoError(str(mFinalPath, ": cannot write: ", std::strerror(syncErr)));
    if (std::rename(mTempPath.c_str(), mFinalPath.c_str()) != 0)
        throw IoError(str(mFinalPath, ": cannot write: rename from '", mTempPath,
                          "' failed: ", std::strerror(errno)));
    mCommitted = true;
}

void checkWritable(const std::string& path) {
    std::string dir, name;
    splitPath(path, dir, name);
    if (name.empty()) throw IoError(str(path, ": cannot write: not a file name"));
    struct stat st;
    if (::stat(dir.c_str(), &st) != 0)
        throw IoError(str(path, ": cannot write: directory '", dir, "': ", std::strerror(errno)));
    if (!S_ISDIR(st.st_mode))
        throw IoError(str(path, ": cannot write: '", dir, "' is not a directory"));
    // Write + search permission are what creating and renaming the temp file need.
    if (::access(dir.c_str(), W_OK | X_OK) != 0)
        throw IoError(str(path, ": cannot write: directory '", dir, "': ", std::strerror(errno)));
    if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
        throw IoError(str(path, ": cannot write: it is a directory"));
}

void writeTextFileAtomic(const std::string& path, const std::string& text) {
    AtomicFile f(path);
    {
        std::ofstream out(f.tempPath(), std::ios::binary);
        out << text;
        if (!out) throw IoError(str(path, ": cannot write"));
    }
    f.commit();
}

}  // namespace vdbmarch
