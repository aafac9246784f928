// AtomicFile: a temporary file next to the target that replaces it only on
// commit, leaves nothing behind otherwise, and is removed when the process is
// interrupted (the signal handler removes the temporary files of live
// AtomicFiles, then the process dies by the signal); checkWritable.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "core/atomic_file.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

namespace fs = std::filesystem;
using test::errorOf;
using test::readBytes;
using test::writeText;

class AtomicFileTest : public ::testing::Test {
protected:
    std::string path(const std::string& name) const { return mDir / name; }
    std::set<std::string> listDir() const { return test::listDir(mDir.path()); }

    test::TempDir mDir{"atomic"};
};

TEST_F(AtomicFileTest, UncommittedAtomicFileLeavesNoFile) {
    std::string tmp;
    {
        AtomicFile file(path("out.exr"));
        tmp = file.tempPath();
        EXPECT_EQ(fs::path(tmp).parent_path(), fs::path(mDir.path()));
        EXPECT_NE(tmp, path("out.exr"));
        writeText(tmp, "partial");
        ASSERT_TRUE(fs::exists(tmp));
    }
    EXPECT_FALSE(fs::exists(tmp));
    EXPECT_FALSE(fs::exists(path("out.exr")));
    EXPECT_TRUE(listDir().empty());
}

TEST_F(AtomicFileTest, UncommittedAtomicFileDoesNotClobberExisting) {
    writeText(path("out.txt"), "old");
    {
        AtomicFile file(path("out.txt"));
        writeText(file.tempPath(), "new");
    }
    EXPECT_EQ(readBytes(path("out.txt")), "old");
    EXPECT_EQ(listDir(), std::set<std::string>{"out.txt"});
}

TEST_F(AtomicFileTest, CommittedAtomicFileReplacesExisting) {
    writeText(path("out.txt"), "old");
    AtomicFile a(path("out.txt")), b(path("out.txt"));
    EXPECT_NE(a.tempPath(), b.tempPath());  // concurrent writers do not collide
    writeText(a.tempPath(), "new");
    a.commit();
    EXPECT_EQ(readBytes(path("out.txt")), "new");
    EXPECT_FALSE(fs::exists(a.tempPath()));
}

TEST_F(AtomicFileTest, CommitWithoutTempFileThrowsNamingPath) {
    AtomicFile file(path("never.txt"));
    EXPECT_CONTAINS(errorOf<IoError>([&] { file.commit(); }), path("never.txt"));
    EXPECT_FALSE(fs::exists(path("never.txt")));
}

TEST_F(AtomicFileTest, CheckWritable) {
    EXPECT_NO_THROW(checkWritable(path("new.exr")));
    writeText(path("existing.exr"), "x");
    EXPECT_NO_THROW(checkWritable(path("existing.exr")));
    EXPECT_THROW(checkWritable(path("missing/new.exr")), IoError);
    EXPECT_THROW(checkWritable(path("existing.exr/new.exr")), IoError);  // parent is a file
    fs::create_directory(path("sub"));
    EXPECT_THROW(checkWritable(path("sub")), IoError);  // target is a directory
    EXPECT_CONTAINS(errorOf<IoError>([&] { checkWritable(path("missing/new.exr")); }), path("missing/new.exr"));
}

TEST(AtomicFileInterrupt, SigtermRemovesTheTemporaryFileAndKeepsTheOldOutput) {
    test::TempDir dir("interrupt");
    const std::string final = dir.write("out.exr", "previous render");
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
    EXPECT_FALSE(fs::exists(std::string(buf, size_t(n)))) << "temporary file left behind";
    EXPECT_EQ(readBytes(final), "previous render");
}

}  // namespace
}  // namespace vdbmarch
