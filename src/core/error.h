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
// Number of warnings issued since the program started (for tests).
int warningCount();
// Last warning text (for tests).
std::string lastWarning();
// When quiet, warnings are counted but not printed.
void setWarningsQuiet(bool quiet);

}  // namespace vdbmarch
