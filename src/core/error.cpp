#include "core/error.h"

#include <atomic>
#include <iostream>
#include <mutex>

namespace vdbmarch {

namespace {
std::mutex gWarnMutex;
std::atomic<int> gWarnCount{0};
std::string gLastWarning;
bool gQuiet = false;
}  // namespace

void warn(const std::string& message) {
    std::lock_guard<std::mutex> lock(gWarnMutex);
    ++gWarnCount;
    gLastWarning = message;
    if (!gQuiet) std::cerr << "vdbmarch: warning: " << message << "\n";
}

int warningCount() { return gWarnCount.load(); }

std::string lastWarning() {
    std::lock_guard<std::mutex> lock(gWarnMutex);
    return gLastWarning;
}

void setWarningsQuiet(bool quiet) {
    std::lock_guard<std::mutex> lock(gWarnMutex);
    gQuiet = quiet;
}

}  // namespace vdbmarch
