#pragma once
/// `run --jobs N`: jobs run in child processes, at most N at a time. A child is a fork of the
/// run loop: it has the loaded snapshot and the settings, does one job, writes its own results
/// file (atomically, as always) and exits; nothing flows back, so only jobs that need no state
/// from earlier jobs (no chains) may be delegated. With N = 1 every job runs in this process.
#include <set>
#include <string>
#include <sys/types.h>

namespace cb {

class ProcessPool {
public:
    explicit ProcessPool(long limit);
    ~ProcessPool();
    ProcessPool(const ProcessPool&) = delete;
    ProcessPool& operator=(const ProcessPool&) = delete;

    bool parallel() const { return m_limit > 1; }
    /// Parallel: waits for a free slot, forks, and returns true in the parent (the child does the
    /// job) and false in the child. Serial: returns false (do the job here).
    bool delegate();
    /// Ends a child after its job (exit status 0); does nothing in the parent or when serial.
    void job_done() const;
    /// Waits for every child; returns how many failed (non-zero exit or a signal).
    size_t wait_all();

private:
    void reap_one();
    long m_limit;
    bool m_in_child = false;
    std::set<pid_t> m_children;
    size_t m_failed = 0;
};

}  // namespace cb

namespace cb {

/// How many jobs of a suite `run --jobs N` may run at once, and a line saying so (empty when N
/// is 1): N for a suite whose times are not judged ("timed": false) or with --jobs-timed, 1 for
/// a timed suite (its runs share no core) and for a chain (each job needs the previous one's state).
long concurrent_jobs(long jobs, bool suite_timed, bool chain, bool jobs_timed, std::string& note);

/// A warning when `jobs` runs at a time, each with up to `threads` threads (the solvers' common
/// setting), ask for more than the machine's `cores`: their times then measure the sharing, not
/// the solvers. Empty when they fit (or cores is unknown, 0).
std::string oversubscription_warning(long jobs, long threads, long cores);

}  // namespace cb
