// The guard around reading untrusted files (core/fatal_guard.h): a crash, a
// hang or a runaway allocation inside the guarded work ends the process with
// exit status 1 and one message naming what was being read; outside a guard
// nothing changes. Death tests: each case runs in a forked child.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <cstring>
#include <thread>
#include <vector>

#include "core/fatal_guard.h"

using namespace vdbmarch;

TEST(FatalGuardDeathTest, ACrashIsOneMessageAndExitStatusOne) {
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_EXIT(
        {
            FatalGuard guard("x.vdb: damaged VDB file: reading it", 60, 0);
            ::raise(SIGSEGV);
        },
        ::testing::ExitedWithCode(1), "vdbmarch: error: x.vdb: damaged VDB file: reading it crashed \\(Segmentation");
    EXPECT_EXIT(
        {
            FatalGuard guard("y.vdb: damaged VDB file: reading it", 60, 0);
            std::abort();
        },
        ::testing::ExitedWithCode(1), "y.vdb: damaged VDB file: reading it crashed \\(Aborted");
}

TEST(FatalGuardDeathTest, WorkPastItsTimeIsStopped) {
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_EXIT(
        {
            FatalGuard guard("slow.vdb: reading it", 0.3, 0);
            std::this_thread::sleep_for(std::chrono::seconds(30));
        },
        ::testing::ExitedWithCode(1), "slow.vdb: reading it did not finish in 0 s \\(stopped\\)");
}

TEST(FatalGuardDeathTest, MemoryBeyondTheLimitIsStopped) {
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_EXIT(
        {
            FatalGuard guard("big.vdb: reading it", 60, uint64_t(64) << 20);
            std::vector<std::vector<char>> blocks;
            for (int i = 0; i < 400; ++i) {  // 1.6 GB at most, touched
                blocks.emplace_back(size_t(4) << 20, char(1));
                std::this_thread::sleep_for(std::chrono::milliseconds(5));
            }
        },
        ::testing::ExitedWithCode(1), "big.vdb: reading it needed more than 64 MiB of memory \\(stopped\\)");
}

TEST(FatalGuard, EndsCleanlyAndRestoresTheSignalHandlers) {
    struct sigaction before {}, after {};
    ::sigaction(SIGSEGV, nullptr, &before);
    {
        FatalGuard guard("ok.vdb: reading it", 60, 0);
        EXPECT_TRUE(FatalGuard::active());
        FatalGuard nested("inner", 0.01, 1);  // does nothing while the outer one lives
        std::this_thread::sleep_for(std::chrono::milliseconds(120));
    }
    EXPECT_FALSE(FatalGuard::active());
    ::sigaction(SIGSEGV, nullptr, &after);
    EXPECT_EQ(before.sa_handler, after.sa_handler);
}
