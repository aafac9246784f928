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

std::string printableExcerpt(const std::string& text, size_t max) {
    std::string out;
    for (char c : text) {
        if (out.size() >= max) return out + "...";
        const unsigned char u = static_cast<unsigned char>(c);
        out.push_back(u >= 32 && u < 127 ? c : '?');
    }
    return out;
}

}  // namespace vdbmarch
