// The up-front memory check: jobs that cannot fit are refused with how much
// they need and how much there is.
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/memory.h"

namespace vdbmarch {
namespace {

TEST(Memory, AvailableIsTheMachinesOrItsLimit) {
    const uint64_t m = availableMemoryBytes();
    EXPECT_GT(m, uint64_t(64) << 20);  // any machine that runs the tests has more than 64 MiB
    EXPECT_LT(m, uint64_t(1) << 50);
}

TEST(Memory, TooMuchIsRefusedWithBothFigures) {
    const uint64_t m = availableMemoryBytes();
    EXPECT_NO_THROW(checkMemory(m / 4, "a quarter"));
    try {
        checkMemory(2 * m + (uint64_t(1) << 30), "photons.count = 7");
        FAIL() << "not refused";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("photons.count = 7"), std::string::npos) << msg;
        EXPECT_NE(msg.find(formatBytes(2 * m + (uint64_t(1) << 30))), std::string::npos) << msg;
        EXPECT_NE(msg.find(formatBytes(m)), std::string::npos) << msg;
    }
    EXPECT_EQ(formatBytes(uint64_t(3) << 30), "3.0 GiB");
    EXPECT_EQ(formatBytes(uint64_t(5) << 20), "5 MiB");
}

}  // namespace
}  // namespace vdbmarch
