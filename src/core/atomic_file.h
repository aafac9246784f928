// Write-then-rename output: a failed or interrupted run never leaves a partial
// image at the final path nor clobbers an existing one.
#pragma once

#include <string>

namespace vdbmarch {

class AtomicFile {
public:
    explicit AtomicFile(std::string finalPath);
    // Removes the temporary file unless commit() succeeded.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    // Unique path in the same directory as the final path (".<name>.tmp-<pid>-<n>"),
    // so the rename never crosses file systems. The writer creates the file.
    const std::string& tempPath() const { return mTempPath; }
    const std::string& finalPath() const { return mFinalPath; }

    // Flushes the temporary file to disk and renames it onto the final path.
    // Throws IoError naming the final path on failure.
    void commit();

private:
    std::string mFinalPath;
    std::string mTempPath;
    bool mCommitted = false;
    int mSlot = -1;  // registration for removeTemporaryFilesOnInterrupt()
};

// Installs SIGINT/SIGTERM/SIGHUP handlers that delete the temporary files of
// live AtomicFiles and then die by the same signal: an interrupted run leaves
// no partial file behind.
void removeTemporaryFilesOnInterrupt();

// For renders that checkpoint: the first SIGINT, SIGTERM or SIGUSR1 only
// records the signal (stopSignal() returns it; 0 before), so the render can
// save its state at the next sample boundary and exit; a second one, a
// second or more after the first, removes the temporary files and dies, as
// removeTemporaryFilesOnInterrupt does (a second SIGUSR1 dies by SIGTERM).
// Repeats within that second are one signal delivered twice (`timeout`
// forwards a signal to its child and to its process group; Slurm signals
// every process of a step). SIGHUP keeps dying at once.
void stopGracefullyOnSignals();
int stopSignal();

// Throws IoError if the directory that would hold `path` does not exist or is
// not writable, or if `path` is itself a directory. Called before rendering so
// a long render does not fail at the very end.
void checkWritable(const std::string& path);

// Writes `text` to `path` through an AtomicFile.
void writeTextFileAtomic(const std::string& path, const std::string& text);

}  // namespace vdbmarch
