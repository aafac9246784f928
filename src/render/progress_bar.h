// The progress bar of a render on stderr (render --progress).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <mutex>

namespace vdbmarch {

// Counts ticks from the worker threads (tick) or takes a fraction (set), and
// redraws only when the percentage changes.
class ProgressBar {
public:
    ProgressBar(bool enabled, int total) : mEnabled(enabled), mTotal(total) {}
    void tick() {
        if (!mEnabled) return;
        show(++mDone);
    }
    // Fraction in [0, 1] (time budgets).
    void set(double fraction) {
        if (!mEnabled) return;
        show(int(std::min(1.0, std::max(0.0, fraction)) * mTotal));
    }

private:
    void show(int done) {
        int percent = int(100LL * done / mTotal);
        std::lock_guard<std::mutex> lock(mMutex);
        if (percent == mShown) return;
        mShown = percent;
        int bars = percent / 4;
        std::fprintf(stderr, "\r[%-25.*s] %3d%%", bars, "=========================", percent);
        if (done == mTotal) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

    bool mEnabled;
    int mTotal;
    std::atomic<int> mDone{0};
    std::mutex mMutex;
    int mShown = -1;
};

}  // namespace vdbmarch
