// The command restarts itself with glibc's heap on huge pages
// (app/huge_page_heap.h): the plan from the environment, the restart seen
// from outside (render --stats), the caller's choices kept, and pixels
// that do not depend on the heap.
#include <gtest/gtest.h>

#include <fstream>
#include <initializer_list>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/huge_page_heap.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using namespace test;
using Action = HeapRestartPlan::Action;

TEST(HugePageHeap, FirstStartRestartsWithTheTunableAndSavesTheCallersValue) {
    const HeapRestartPlan none = planHeapRestart(nullptr, nullptr, nullptr);
    EXPECT_EQ(none.action, Action::Restart);
    EXPECT_EQ(none.tunables, "glibc.malloc.hugetlb=1");
    EXPECT_EQ(none.saved, "unset");

    const HeapRestartPlan other = planHeapRestart("glibc.mem.tagging=0", nullptr, nullptr);
    EXPECT_EQ(other.action, Action::Restart);
    EXPECT_EQ(other.tunables, "glibc.mem.tagging=0:glibc.malloc.hugetlb=1");
    EXPECT_EQ(other.saved, "set:glibc.mem.tagging=0");

    const HeapRestartPlan empty = planHeapRestart("", nullptr, nullptr);
    EXPECT_EQ(empty.tunables, "glibc.malloc.hugetlb=1");
    EXPECT_EQ(empty.saved, "set:");
}

TEST(HugePageHeap, TheRestartedProcessRestoresTheCallersValue) {
    const HeapRestartPlan unset = planHeapRestart("glibc.malloc.hugetlb=1", "unset", nullptr);
    EXPECT_EQ(unset.action, Action::Restore);
    EXPECT_FALSE(unset.restored.has_value());

    const HeapRestartPlan set = planHeapRestart("glibc.mem.tagging=0:glibc.malloc.hugetlb=1", "set:glibc.mem.tagging=0",
                                                nullptr);
    EXPECT_EQ(set.action, Action::Restore);
    ASSERT_TRUE(set.restored.has_value());
    EXPECT_EQ(*set.restored, "glibc.mem.tagging=0");
}

TEST(HugePageHeap, TheCallersChoiceIsKept) {
    EXPECT_EQ(planHeapRestart("glibc.malloc.hugetlb=0", nullptr, nullptr).action, Action::None);
    EXPECT_EQ(planHeapRestart("glibc.malloc.hugetlb=2", nullptr, nullptr).action, Action::None);
    EXPECT_EQ(planHeapRestart(nullptr, nullptr, "default").action, Action::None);
    EXPECT_EQ(planHeapRestart(nullptr, nullptr, "huge").action, Action::Restart);
}

TEST(HugePageHeap, OnlyCommandsThatReadGridsRestart) {
    auto reads = [](std::initializer_list<const char*> args) {
        std::vector<const char*> argv{"vdbmarch"};
        argv.insert(argv.end(), args.begin(), args.end());
        return commandReadsGrids(int(argv.size()), argv.data());
    };
    EXPECT_TRUE(reads({"render", "scene.json", "-o", "out.exr"}));
    EXPECT_TRUE(reads({"bake", "scene.json", "-o", "cache.vdb"}));
    EXPECT_TRUE(reads({"bench", "scene.json", "-o", "out"}));
    EXPECT_TRUE(reads({"info", "cloud.vdb"}));
    EXPECT_TRUE(reads({"inspect", "cache.vdb"}));
    EXPECT_TRUE(reads({"check", "--in-process", "cloud.vdb"}));
    EXPECT_FALSE(reads({"check", "cloud.vdb"}));
    EXPECT_FALSE(reads({"compare", "a.exr", "b.exr"}));
    EXPECT_FALSE(reads({"merge", "a.exr", "-o", "b.exr"}));
    EXPECT_FALSE(reads({"--version"}));
    EXPECT_FALSE(reads({}));
}

class HugePageHeapCli : public ::testing::Test {
protected:
    TempDir dir{"hugepage"}, capture{"hugepage_capture"};
};

bool onHugePages(const std::string& statsFile) {
    std::ifstream in(statsFile);
    const nlohmann::json stats = nlohmann::json::parse(in);
    return stats.at("memory").at("heap_on_huge_pages").get<bool>();
}

TEST_F(HugePageHeapCli, PixelsDoNotDependOnTheHeap) {
#if !defined(__GLIBC__) || defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    GTEST_SKIP() << "the restart is glibc's and off in sanitizer builds";
#endif
    writeText(dir / "scene.json", homogeneousScene());
    const std::string render = shellQuote(vdbmarchBinary()) + " render scene.json --res 24x18 --spp 4 -q --no-denoise";
    CliResult huge = runShell(render + " -o huge.exr --stats huge.json", dir.path(), capture.path());
    ASSERT_EQ(huge.exitCode, 0) << huge.err;
    CliResult plain =
        runShell("env VDBMARCH_HEAP=default " + render + " -o plain.exr --stats plain.json", dir.path(), capture.path());
    ASSERT_EQ(plain.exitCode, 0) << plain.err;
    CliResult chosen = runShell("env GLIBC_TUNABLES=glibc.malloc.hugetlb=0 " + render + " -o chosen.exr --stats chosen.json",
                                dir.path(), capture.path());
    ASSERT_EQ(chosen.exitCode, 0) << chosen.err;
    EXPECT_TRUE(onHugePages(dir / "huge.json"));
    EXPECT_FALSE(onHugePages(dir / "plain.json"));
    EXPECT_FALSE(onHugePages(dir / "chosen.json"));
    const CliResult same = runCli({"compare", "--identical", "huge.exr", "plain.exr"}, dir.path(), capture.path());
    EXPECT_EQ(same.exitCode, 0) << same.out << same.err;
}

}  // namespace
}  // namespace vdbmarch
