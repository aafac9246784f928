// One error policy: the library throws these; tools/vdbmarch.cpp catches them,
// prints "vdbmarch: error: <what>" and exits non-zero. Messages name the file,
// key or grid and the bad value.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace vdbmarch {

// Bad user input: scene files, command-line values, VDB contents.
struct InputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// A bad value at a key of a JSON document: `keyPath` (e.g. "media[0].g") lets
// the parser add the line and column where the key is written.
struct SceneKeyError : InputError {
    SceneKeyError(const std::string& file, const std::string& keyPath, const std::string& message)
        : InputError(file + ": " + message), file(file), keyPath(keyPath), detail(message) {}
    std::string file, keyPath, detail;  // what() = file + ": " + detail
};

// The file system refused: cannot open, read or write.
struct IoError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Formats all arguments with operator<< into one string.
template <typename... Args>
std::string str(const Args&... args) {
    std::ostringstream os;
    (os << ... << args);
    return os.str();
}

// Warnings go through one sink so tests can capture them and counts stay honest.
void warn(const std::string& message);

// A library's message fit to quote in ours: control and non-ASCII bytes
// become '?', and past `max` characters it is cut with "..." (a damaged
// file can put kilobytes of garbage into an exception's text).
std::string printableExcerpt(const std::string& text, size_t max = 240);
// Number of warnings issued since the program started (for tests).
int warningCount();
// Last warning text (for tests).
std::string lastWarning();
// When quiet, warnings are counted but not printed.
void setWarningsQuiet(bool quiet);

}  // namespace vdbmarch
