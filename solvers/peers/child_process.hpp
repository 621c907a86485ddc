#pragma once
/// Runs a piece of library work in a forked child process, so that an abort, failed assertion
/// or segfault in an external library becomes a recorded outcome instead of the end of a suite.
/// The child sends its answer back as bytes through a pipe; the parent kills it at the deadline.
#include "solvers/core/solve_loop.hpp"
#include "solvers/core/stopwatch.hpp"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace cb {

struct ChildOutcome {
    std::vector<char> bytes;  ///< what the child sent
    bool timed_out = false;   ///< the deadline passed; the child was killed
    bool failed = false;      ///< the child died (signal) or exited non-zero
    std::string failure;      ///< e.g. "was killed by signal 6 (Aborted)"
};

/// Forks; the child runs `work` and writes its bytes, then _exit(0). The parent collects them
/// until EOF or until `watch` reaches `time_limit_s` (0: no limit). Throws std::runtime_error
/// when pipe or fork fail.
ChildOutcome run_in_child(const std::function<std::vector<char>()>& work, const Stopwatch& watch, double time_limit_s);

/// The one reading of a child that did not answer in full: killed at the deadline -> TIME_LIMIT
/// ("...; the child process was killed"), died or sent other than `expected` bytes -> DIVERGED
/// naming `library` and the bytes received. Sets result.info["crashed"]. Returns the finished
/// result, or nothing when the child's answer is complete (then go on and read it).
std::optional<SolverResult> finish_failed_child(const ChildOutcome& child, size_t expected, const std::string& library,
                                                const SolveLoop& loop, SolverResult& result);

}  // namespace cb
