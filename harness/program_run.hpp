#pragma once
/// Runs an external program as a child process on a leash (issue 40). No shell: argv goes to
/// execvp as given. The program runs in a process group of its own, started in its own work
/// folder, under a small guard process that
///  - kills the group at the time limit;
///  - forwards SIGINT, SIGTERM and SIGHUP that the harness receives while the program runs to the
///    group, and SIGKILLs it 2 s later if it is still there (the harness then ends by the same
///    signal, see end_by_signal);
///  - is a child subreaper (PR_SET_CHILD_SUBREAPER, no privileges needed): descendants that left
///    the group (setsid) are re-parented to it when their parent ends, and are killed and reaped
///    once the program has ended, so nothing the program started outlives it;
///  - reaps the program with wait4, so its peak resident memory (and that of every descendant)
///    is known (with a floor: ProgramOutcome::start_rss_bytes);
///  - tells exec failures (a CLOEXEC pipe carries errno) from a program that itself exits 127.
/// The harness reads the program's stdout and stderr through pipes into two files, each capped
/// at PROGRAM_OUTPUT_CAP_BYTES: beyond it the bytes are drained and counted, not stored, and the
/// last PROGRAM_OUTPUT_TAIL_BYTES are appended after a note, so an error at the end is kept.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace cb {

/// Bytes of the program's stdout, and of its stderr, kept in their files (1 MiB each).
inline constexpr std::size_t PROGRAM_OUTPUT_CAP_BYTES = std::size_t(1) << 20;
/// The last bytes of a capped stream, kept after the note.
inline constexpr std::size_t PROGRAM_OUTPUT_TAIL_BYTES = 4096;

struct ProgramOptions {
    double time_limit_s = 0.0;  ///< <= 0: no limit
    std::string workdir;        ///< the program's current folder ("": the harness's)
    std::size_t output_cap_bytes = PROGRAM_OUTPUT_CAP_BYTES;
    double grace_s = 2.0;  ///< after a forwarded signal, before SIGKILL
};

struct ProgramOutcome {
    bool timed_out = false;    ///< the deadline passed; the process group was killed
    bool exec_failed = false;  ///< the program could not be started (exec_error says why)
    std::string exec_error;    ///< "chdir WORKDIR: ..." or "exec: No such file or directory"
    int exit_status = -1;      ///< when it exited normally (127 of its own is its own)
    int signal = 0;            ///< when a signal ended it (other than our kill at the deadline)
    int interrupted = 0;       ///< SIGINT/SIGTERM/SIGHUP the harness received and forwarded (0: none)
    double wall_s = 0.0;       ///< fork to reaping, on the guard's clock
    long peak_rss_bytes = -1;  ///< largest peak resident set of the program and its descendants
    /// This process's anonymous resident memory (RssAnon) when the program was started. Linux
    /// counts the pages a forked child holds before exec in its peak, so peak_rss_bytes is at least about this much
    /// even for a tiny program: a peak at this floor means the program's own peak is at most it.
    long start_rss_bytes = -1;
    int orphans_killed = 0;                            ///< descendants still running after the program ended, killed
    std::uint64_t stdout_bytes = 0, stderr_bytes = 0;  ///< as written by the program
    bool stdout_capped = false, stderr_capped = false;
    std::string failure() const;  ///< "" for exit 0, else "exited with status 3", "was killed by signal 11 (...)"
};

/// Runs argv[0] (looked up in PATH when it has no '/') with arguments argv[1..]; stdin is
/// /dev/null; stdout and stderr go to the two files (capped, see above). Throws
/// std::runtime_error when a pipe, a file or fork fails and std::invalid_argument on an empty argv.
ProgramOutcome run_program(const std::vector<std::string>& argv, const std::string& stdout_path,
                           const std::string& stderr_path, const ProgramOptions& options);

/// Ends this process by `sig` (default action), as if the harness had not caught it: for a caller
/// that cleaned up after run_program reported `interrupted`.
[[noreturn]] void end_by_signal(int sig);

}  // namespace cb
