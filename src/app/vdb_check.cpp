#include "app/vdb_check.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "core/error.h"
#include "volume/medium.h"

extern char** environ;

namespace vdbmarch {

namespace {

std::string& checkExecutable() {
    static std::string path;
    return path;
}

std::string signalName(int sig) {
    const char* s = strsignal(sig);
    return s ? str(s, " (signal ", sig, ")") : str("signal ", sig);
}

// The last line the child wrote on stderr, without the "vdbmarch: error: " prefix.
std::string lastLine(const std::string& text) {
    std::string t = text;
    while (!t.empty() && (t.back() == '\n' || t.back() == '\r')) t.pop_back();
    size_t nl = t.rfind('\n');
    std::string line = nl == std::string::npos ? t : t.substr(nl + 1);
    const std::string prefix = "vdbmarch: error: ";
    if (line.compare(0, prefix.size(), prefix) == 0) line = line.substr(prefix.size());
    return line;
}

}  // namespace

void checkVdbFileIsolated(const std::string& path, double timeoutSeconds) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) throw IoError(str(path, ": cannot open VDB file: ", std::strerror(errno)));
    if (timeoutSeconds <= 0) timeoutSeconds = vdbCheckTimeout(uint64_t(st.st_size), measureReadSpeed(path));

    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw IoError(str("cannot create a pipe to check ", path, ": ", std::strerror(errno)));
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    std::string self = checkExecutable().empty() ? std::string("/proc/self/exe") : checkExecutable(), arg0 = "vdbmarch", cmd = "check", inProcess = "--in-process",
                quiet = "--quiet";
    std::string file = path;
    char* argv[] = {arg0.data(), cmd.data(), inProcess.data(), quiet.data(), file.data(), nullptr};
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, self.c_str(), &actions, nullptr, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[1]);
    if (rc != 0) {
        ::close(fds[0]);
        throw IoError(str("cannot start a process to check ", path, ": ", std::strerror(rc)));
    }
    // Collect the child's stderr until it exits or the time is up.
    std::string output;
    const auto start = std::chrono::steady_clock::now();
    bool timedOut = false;
    for (;;) {
        const double left =
            timeoutSeconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (left <= 0) {
            timedOut = true;
            break;
        }
        pollfd p{fds[0], POLLIN, 0};
        const int n = ::poll(&p, 1, int(std::min(left * 1000, 1000.0)) + 1);
        if (n < 0 && errno != EINTR) break;
        if (n <= 0) continue;
        char buf[4096];
        const ssize_t got = ::read(fds[0], buf, sizeof buf);
        if (got <= 0) break;  // the child closed stderr: it is exiting
        if (output.size() < 65536) output.append(buf, size_t(got));
    }
    ::close(fds[0]);
    if (timedOut) ::kill(pid, SIGKILL);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (timedOut)
        throw InputError(str(path, ": damaged VDB file: reading it did not finish in ", timeoutSeconds,
                             " s (stopped)"));
    if (WIFSIGNALED(status))
        throw InputError(str(path, ": damaged VDB file: reading it crashed OpenVDB's reader (",
                             signalName(WTERMSIG(status)), ")"));
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::string why = lastLine(output);
        if (why.empty()) why = str("exit status ", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
        // The child's message already names the file.
        throw InputError(why.find(path) != std::string::npos ? why : str(path, ": ", why));
    }
}

void setVdbCheckExecutable(const std::string& path) { checkExecutable() = path; }

void checkVdbFilesIsolated(const std::vector<std::string>& files) {
    if (checkExecutable().empty()) return;
    const char* trust = std::getenv("VDBMARCH_TRUST_VDB");
    if (trust && std::string(trust) == "1") return;
    for (const std::string& f : files) checkVdbFileIsolated(f);
}

}  // namespace vdbmarch
