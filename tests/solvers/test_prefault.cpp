// prefault_for_writing (solvers/linalg/prefault.hpp): faulting pages in ahead of the block build's
// writes keeps what they hold, and on this Linux kernel (>= 5.14) the call is taken; huge pages: the
// range advised is the whole 2 MB pages inside a buffer, the advice is taken where the kernel has
// transparent huge pages, and a buffer prefaulted on them keeps its contents.
#include "solvers/linalg/prefault.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <sys/stat.h>
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

// Huge pages: huge_page_interior finds the 2 MB pages wholly inside a buffer, for buffers starting anywhere.
TEST(HugePages, InteriorIsTheWholeHugePagesInsideTheBuffer)
{
    constexpr std::size_t huge = std::size_t{2} << 20;
    for (std::uintptr_t start : {huge * 8, huge * 8 + 8, huge * 9 - 8, huge * 8 + 4096})
        for (std::size_t bytes : {2 * huge - 1, 2 * huge, 3 * huge + 100, 10 * huge}) {
            std::size_t begin = 0, end = 0;
            const bool any = cb::huge_page_interior(start, bytes, begin, end);
            // Expected: from the first multiple of 2 MB at or after start to the last at or before the end.
            const std::uintptr_t first = (start + huge - 1) / huge * huge, last = (start + bytes) / huge * huge;
            const bool expect_any = bytes >= 2 * huge && last > first;
            EXPECT_EQ(any, expect_any) << start << " " << bytes;
            if (!any || !expect_any) continue;
            EXPECT_EQ(start + begin, first) << start << " " << bytes;
            EXPECT_EQ(start + end, last) << start << " " << bytes;
        }
}

TEST(HugePages, AdviceIsTakenAndThePrefaultKeepsTheContents)
{
    struct stat info {};
    if (stat("/sys/kernel/mm/transparent_hugepage/enabled", &info) != 0)
        GTEST_SKIP() << "this kernel has no transparent huge pages (no /sys/kernel/mm/transparent_hugepage)";
    constexpr std::size_t count = (std::size_t{6} << 20) / sizeof(double) + 5;  // two whole huge pages at least
    std::unique_ptr<double[]> buffer(new double[count]);
    EXPECT_TRUE(cb::advise_huge_pages(buffer.get(), count * sizeof(double)));
    for (std::size_t i = 0; i < count; ++i) buffer[i] = static_cast<double>(i) * 0.25 - 3.0;
    cb::prefault_huge_for_writing(buffer.get(), count * sizeof(double));
    std::size_t differing = 0;
    for (std::size_t i = 0; i < count; ++i) differing += buffer[i] != static_cast<double>(i) * 0.25 - 3.0;
    EXPECT_EQ(differing, 0u);
    EXPECT_FALSE(cb::advise_huge_pages(buffer.get(), std::size_t{3} << 20));  // 3 MB: no two whole huge pages
}
