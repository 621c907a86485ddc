#pragma once
/// Peak resident memory of one run, beside its time (docs/INTERFACES.md, record key `memory`).
/// A process's high-water mark (VmHWM) only grows over its life, and a suite runs many solves in
/// one process (or in forks of it), so a run first resets it (`/proc/self/clear_refs`, "5": VmHWM
/// back to the current RSS). Work done in a forked child (the peers that run in a child process)
/// does not show in the parent's VmHWM: each child's own peak (ru_maxrss) is noted when it is
/// reaped, and the largest since the reset is reported beside the parent's.

namespace cb {

struct PeakMemory {
    long process_bytes = -1;  ///< VmHWM of this process since the reset; -1 when /proc is unreadable
    long children_bytes = 0;  ///< the largest peak of a child reaped since the reset
    bool reset = false;       ///< false: the reset failed, process_bytes is the process's lifetime peak
};

/// Starts a run's measurement: resets VmHWM (when the kernel allows) and forgets earlier children.
void reset_peak_memory();
/// Records a reaped child's peak (wait4's ru_maxrss, converted to bytes).
void note_child_peak_memory(long bytes);
/// The peaks since the last reset.
PeakMemory read_peak_memory();

}  // namespace cb
