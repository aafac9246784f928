#include "app/huge_page_heap.h"

#include <cstdlib>
#include <cstring>
#include <string>

#include <unistd.h>

namespace vdbmarch {

namespace {

// Set for the restarted process: "unset", or "set:" and the caller's value.
constexpr const char* SavedVariable = "VDBMARCH_SAVED_GLIBC_TUNABLES";
constexpr const char* Tunable = "glibc.malloc.hugetlb=1";

constexpr bool sanitized() {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    return true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
    return true;
#else
    return false;
#endif
#else
    return false;
#endif
}

bool restarted = false;

void setOrUnset(const char* name, const std::optional<std::string>& value) {
    if (value) setenv(name, value->c_str(), 1);
    else unsetenv(name);
}

}  // namespace

HeapRestartPlan planHeapRestart(const char* glibcTunables, const char* savedTunables, const char* vdbmarchHeap) {
    HeapRestartPlan plan;
    if (savedTunables) {
        // The restarted process: glibc has read the tunable at start-up.
        plan.action = HeapRestartPlan::Action::Restore;
        if (std::strncmp(savedTunables, "set:", 4) == 0) plan.restored = std::string(savedTunables + 4);
        return plan;
    }
    if (vdbmarchHeap && std::strcmp(vdbmarchHeap, "default") == 0) return plan;
    if (glibcTunables && std::strstr(glibcTunables, "glibc.malloc.hugetlb")) return plan;  // the user's choice
    plan.action = HeapRestartPlan::Action::Restart;
    plan.saved = glibcTunables ? std::string("set:") + glibcTunables : std::string("unset");
    plan.tunables = glibcTunables && *glibcTunables ? std::string(glibcTunables) + ":" + Tunable : std::string(Tunable);
    return plan;
}

bool commandReadsGrids(int argc, const char* const* argv) {
    if (argc < 2) return false;
    const std::string command = argv[1];
    if (command == "render" || command == "bake" || command == "bench" || command == "info" || command == "inspect")
        return true;
    if (command != "check") return false;
    for (int i = 2; i < argc; ++i)
        if (std::strcmp(argv[i], "--in-process") == 0) return true;
    return false;
}

void restartWithHugePageHeap(int argc, char** argv) {
#if defined(__GLIBC__) && defined(__linux__)
    const char* current = std::getenv("GLIBC_TUNABLES");
    const HeapRestartPlan plan = planHeapRestart(current, std::getenv(SavedVariable), std::getenv("VDBMARCH_HEAP"));
    if (plan.action == HeapRestartPlan::Action::Restore) {
        setOrUnset("GLIBC_TUNABLES", plan.restored);
        unsetenv(SavedVariable);
        restarted = true;
    }
    if (plan.action != HeapRestartPlan::Action::Restart || sanitized() || !commandReadsGrids(argc, argv)) return;
    const std::optional<std::string> caller = current ? std::optional<std::string>(current) : std::nullopt;
    if (setenv(SavedVariable, plan.saved.c_str(), 1) == 0 && setenv("GLIBC_TUNABLES", plan.tunables.c_str(), 1) == 0)
        execv("/proc/self/exe", argv);
    // exec failed (no /proc): run on with the default heap.
    setOrUnset("GLIBC_TUNABLES", caller);
    unsetenv(SavedVariable);
#else
    (void)argc;
    (void)argv;
#endif
}

bool heapOnHugePages() { return restarted; }

}  // namespace vdbmarch
