// An interrupted run leaves no partial file: the signal handler removes the
// temporary files of live AtomicFiles, then the process dies by the signal.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>

#include "core/atomic_file.h"

namespace vdbmarch {
namespace {

bool exists(const std::string& p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0;
}

TEST(AtomicFileInterrupt, SigtermRemovesTheTemporaryFileAndKeepsTheOldOutput) {
    std::string dir = ::testing::TempDir() + "vdbmarch_int_" + std::to_string(::getpid());
    ::mkdir(dir.c_str(), 0700);
    const std::string final = dir + "/out.exr";
    { std::ofstream(final) << "previous render"; }
    int pipeFd[2];
    ASSERT_EQ(::pipe(pipeFd), 0);
    pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        removeTemporaryFilesOnInterrupt();
        AtomicFile f(final);
        { std::ofstream(f.tempPath()) << "half an image"; }
        std::string temp = f.tempPath();
        (void)!::write(pipeFd[1], temp.c_str(), temp.size());
        ::close(pipeFd[1]);
        std::raise(SIGTERM);
        ::_exit(0);  // not reached
    }
    ::close(pipeFd[1]);
    char buf[4096] = {0};
    ssize_t n = ::read(pipeFd[0], buf, sizeof(buf) - 1);
    ::close(pipeFd[0]);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
    ASSERT_GT(n, 0);
    EXPECT_FALSE(exists(std::string(buf, size_t(n)))) << "temporary file left behind";
    std::ifstream in(final);
    std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(content, "previous render");
    ::unlink(final.c_str());
    ::rmdir(dir.c_str());
}

}  // namespace
}  // namespace vdbmarch
