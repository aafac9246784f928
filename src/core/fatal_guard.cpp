#include "core/fatal_guard.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>

#include "core/memory.h"

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/common_interface_defs.h>
#endif

namespace vdbmarch {

namespace {

std::atomic<bool> gGuardActive{false};
// "vdbmarch: error: <what> ", formatted before the guarded work: a signal
// handler may only write.
char gPrefix[1024];
size_t gPrefixLength = 0;
constexpr int FatalSignals[] = {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT};
struct sigaction gPrevious[std::size(FatalSignals)];
alignas(16) char gAltStack[1 << 16];
// While a guard lives, stderr goes to a memory file (the library's own
// complaints, our warnings) and the real stderr is kept here: the message that
// ends the process comes first, then what the work printed; a guard that ends
// normally replays it.
int gRealStderr = -1;
int gCaptured = -1;

void writeAll(const char* s, size_t n) {
    const int fd = gRealStderr >= 0 ? gRealStderr : STDERR_FILENO;
    while (n > 0) {
        const ssize_t w = ::write(fd, s, n);
        if (w <= 0) return;
        s += w;
        n -= size_t(w);
    }
}

void writeString(const char* s) { writeAll(s, std::strlen(s)); }

// Async-signal-safe: fixed strings only.
const char* signalText(int sig) {
    switch (sig) {
        case SIGSEGV: return "crashed (Segmentation fault, signal 11)\n";
        case SIGBUS: return "crashed (Bus error, signal 7)\n";
        case SIGILL: return "crashed (Illegal instruction, signal 4)\n";
        case SIGFPE: return "crashed (Floating point exception, signal 8)\n";
        case SIGABRT: return "crashed (Aborted, signal 6: heap corruption)\n";
        default: return "crashed\n";
    }
}

// Copies what the guarded work wrote to stderr to the real stderr, each line
// indented (async-signal-safe: read, write, lseek).
void replayCaptured(const char* indent) {
    if (gCaptured < 0) return;
    ::lseek(gCaptured, 0, SEEK_SET);
    char buf[4096];
    bool lineStart = true;
    for (;;) {
        const ssize_t got = ::read(gCaptured, buf, sizeof buf);
        if (got <= 0) break;
        for (ssize_t i = 0; i < got; ++i) {
            if (lineStart) writeString(indent);
            writeAll(&buf[i], 1);
            lineStart = buf[i] == '\n';
        }
    }
    if (!lineStart) writeString("\n");
}

void onFatalSignal(int sig) {
    writeAll(gPrefix, gPrefixLength);
    writeString(signalText(sig));
    replayCaptured("  ");
    ::_exit(1);
}

#if defined(__SANITIZE_ADDRESS__)
void onSanitizerDeath() {
    writeAll(gPrefix, gPrefixLength);
    writeString("crashed (a memory error found by AddressSanitizer, below)\n");
    replayCaptured("  ");
}
#endif

}  // namespace

bool FatalGuard::active() { return gGuardActive.load(); }

FatalGuard::FatalGuard(const std::string& what, double seconds, uint64_t memoryGrowth) {
    bool expected = false;
    if (!gGuardActive.compare_exchange_strong(expected, true)) return;
    mActive = true;
    const std::string prefix = "vdbmarch: error: " + what + " ";
    gPrefixLength = std::min(prefix.size(), sizeof gPrefix);
    std::memcpy(gPrefix, prefix.data(), gPrefixLength);
    // The handler runs on its own stack: a crash may come from a stack overflow.
    stack_t ss{};
    ss.ss_sp = gAltStack;
    ss.ss_size = sizeof gAltStack;
    ::sigaltstack(&ss, nullptr);
    struct sigaction sa {};
    sa.sa_handler = onFatalSignal;
    sa.sa_flags = SA_ONSTACK;
    sigemptyset(&sa.sa_mask);
    for (size_t i = 0; i < std::size(FatalSignals); ++i) ::sigaction(FatalSignals[i], &sa, &gPrevious[i]);
#if defined(__SANITIZE_ADDRESS__)
    __sanitizer_set_death_callback(onSanitizerDeath);
#endif
    gCaptured = ::memfd_create("vdbmarch-guard-stderr", MFD_CLOEXEC);
    if (gCaptured >= 0) {
        std::fflush(stderr);
        gRealStderr = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 3);
        if (gRealStderr < 0 || ::dup2(gCaptured, STDERR_FILENO) < 0) {
            ::close(gCaptured);
            gCaptured = -1;
        }
    }
    const uint64_t start = residentMemoryBytes();
    const std::string whatCopy = what;
    mWatchdog = std::thread([this, seconds, memoryGrowth, start, whatCopy] {
        const auto begin = std::chrono::steady_clock::now();
        std::unique_lock<std::mutex> lock(mMutex);
        while (!mDone) {
            mWake.wait_for(lock, std::chrono::milliseconds(50));
            if (mDone) break;
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
            std::string why;
            if (elapsed > seconds) why = "did not finish in " + std::to_string(int(seconds + 0.5)) + " s (stopped)";
            const uint64_t now = residentMemoryBytes();
            if (why.empty() && memoryGrowth > 0 && now > start && now - start > memoryGrowth)
                why = "needed more than " + formatBytes(memoryGrowth) + " of memory (stopped)";
            if (why.empty()) continue;
            const std::string line = "vdbmarch: error: " + whatCopy + " " + why + "\n";
            writeAll(line.data(), line.size());
            replayCaptured("  ");
            ::_exit(1);
        }
    });
}

FatalGuard::~FatalGuard() {
    if (!mActive) return;
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mDone = true;
    }
    mWake.notify_all();
    mWatchdog.join();
#if defined(__SANITIZE_ADDRESS__)
    __sanitizer_set_death_callback(nullptr);
#endif
    if (gCaptured >= 0) {
        std::fflush(stderr);
        replayCaptured("");
        ::dup2(gRealStderr, STDERR_FILENO);
        ::close(gRealStderr);
        ::close(gCaptured);
        gRealStderr = gCaptured = -1;
    }
    for (size_t i = 0; i < std::size(FatalSignals); ++i) ::sigaction(FatalSignals[i], &gPrevious[i], nullptr);
    stack_t ss{};
    ss.ss_flags = SS_DISABLE;
    ::sigaltstack(&ss, nullptr);
    gGuardActive = false;
}

}  // namespace vdbmarch
