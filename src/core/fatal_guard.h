// Guards work on untrusted input done by a library that trusts it (OpenVDB
// reading a damaged file can write past a buffer, spin, or allocate what a
// damaged size field asks for). While a FatalGuard lives, the process ends
// with one clear message on stderr and exit status 1, the status of every
// other input error, instead of crashing, hanging or being killed for memory:
// - a fatal signal (SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT: glibc aborts on
//   the heap corruption such writes leave), or an AddressSanitizer report;
// - the work running past `seconds`;
// - the resident memory growing by more than `memoryGrowth` bytes.
// The message is "vdbmarch: error: <what> <how it ended>", e.g.
// "x.vdb: damaged VDB file: reading it crashed (Segmentation fault, signal 11)".
// Nothing is written to outputs before inputs are read, so nothing is lost.
// One guard at a time: a guard made while another lives does nothing.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

namespace vdbmarch {

class FatalGuard {
public:
    FatalGuard(const std::string& what, double seconds, uint64_t memoryGrowth);
    ~FatalGuard();
    FatalGuard(const FatalGuard&) = delete;
    FatalGuard& operator=(const FatalGuard&) = delete;
    // True while a guard is active (in any thread).
    static bool active();

private:
    bool mActive = false;
    std::mutex mMutex;
    std::condition_variable mWake;
    bool mDone = false;
    std::thread mWatchdog;
};

}  // namespace vdbmarch
