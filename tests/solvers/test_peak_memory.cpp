// Peak resident memory (solvers/core/peak_memory.hpp): the reset makes a run's peak its own, not the
// process's, and a child's peak is seen by the parent.
#include "solvers/core/peak_memory.hpp"
#include "solvers/peers/child_process.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

using namespace cb;

namespace {

constexpr long MIB = 1024L * 1024L;

/// Touches `bytes` of fresh memory (so that it is resident), then frees it.
void touch_and_free(long bytes)
{
    std::vector<char> block(static_cast<size_t>(bytes));
    std::memset(block.data(), 1, block.size());
    volatile char sink = block[block.size() / 2];
    (void)sink;
}

}  // namespace

TEST(PeakMemory, ResetForgetsAnEarlierPeak)
{
    reset_peak_memory();
    touch_and_free(256 * MIB);
    const PeakMemory before = read_peak_memory();
    ASSERT_GE(before.process_bytes, 256 * MIB);  // the block was resident
    reset_peak_memory();
    const PeakMemory after = read_peak_memory();
    if (!after.reset) GTEST_SKIP() << "/proc/self/clear_refs is not writable here: peaks are lifetime peaks";
    // The 256 MiB were returned to the system (a block that large is its own mapping), so the
    // peak after the reset is the current RSS: well below the earlier peak.
    EXPECT_LT(after.process_bytes, before.process_bytes - 200 * MIB);
    EXPECT_EQ(after.children_bytes, 0);
}

TEST(PeakMemory, AChildsPeakIsSeenByTheParent)
{
    reset_peak_memory();
    const Stopwatch watch;
    const ChildOutcome outcome = run_in_child(
        [] {
            touch_and_free(192 * MIB);
            return std::vector<char>{'o', 'k'};
        },
        watch, 60.0);
    ASSERT_FALSE(outcome.failed) << outcome.failure;
    const PeakMemory peak = read_peak_memory();
    EXPECT_GE(peak.children_bytes, 192 * MIB);
    // The parent did not allocate the block: its own peak stays below it (plus the gtest binary).
    if (peak.reset) {
        EXPECT_LT(peak.process_bytes, peak.children_bytes);
    }
}
