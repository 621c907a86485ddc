// prefault_for_writing (solvers/linalg/prefault.hpp): faulting pages in ahead of the block build's
// writes keeps what they hold, and on this Linux kernel (>= 5.14) the call is taken.
#include "solvers/linalg/prefault.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <sys/utsname.h>

TEST(PrefaultForWriting, KeepsTheContentsOfThePages)
{
    constexpr std::size_t count = 3 * 4096 + 17;
    std::unique_ptr<double[]> buffer(new double[count]);
    for (std::size_t i = 0; i < count; ++i) buffer[i] = static_cast<double>(i) + 0.5;
    cb::prefault_for_writing(buffer.get(), count * sizeof(double));
    std::size_t differing = 0;
    for (std::size_t i = 0; i < count; ++i) differing += buffer[i] != static_cast<double>(i) + 0.5;
    EXPECT_EQ(differing, 0u);
    EXPECT_FALSE(cb::prefault_for_writing(buffer.get(), 100));  // no whole page inside
}

TEST(PrefaultForWriting, IsTakenOnALinuxKernelFrom514)
{
    utsname name{};
    ASSERT_EQ(uname(&name), 0);
    int major = 0, minor = 0;
    ASSERT_EQ(std::sscanf(name.release, "%d.%d", &major, &minor), 2) << name.release;
    if (major < 5 || (major == 5 && minor < 14))
        GTEST_SKIP() << "kernel " << name.release << " has no MADV_POPULATE_WRITE";
    std::unique_ptr<double[]> buffer(new double[1 << 16]);
    EXPECT_TRUE(cb::prefault_for_writing(buffer.get(), (1 << 16) * sizeof(double)));
}
