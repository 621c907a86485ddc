#pragma once
/// Runs an external program as a child process: no shell (argv goes to execvp as given), its
/// standard output and error into files, in a process group of its own so that a deadline kills
/// it and whatever it started. The wall time is the harness's clock around the child, start-up
/// included.
#include <string>
#include <vector>

namespace cb {

struct ProgramOutcome {
    bool timed_out = false;       ///< the deadline passed; the process group was killed
    bool exec_failed = false;     ///< the program could not be started (exit status 127, reason in stderr)
    int exit_status = -1;         ///< when it exited normally
    int signal = 0;               ///< when a signal ended it (other than our kill at the deadline)
    double wall_s = 0.0;          ///< fork to reaping, on the harness's clock
    std::string failure() const;  ///< "" for exit 0, else "exited with status 3", "was killed by signal 11 (...)"
};

/// Runs argv[0] (looked up in PATH when it has no '/') with arguments argv[1..]; stdin is
/// /dev/null. time_limit_s <= 0: no limit. Throws std::runtime_error when fork fails and
/// std::invalid_argument on an empty argv.
ProgramOutcome run_program(const std::vector<std::string>& argv, const std::string& stdout_path,
                           const std::string& stderr_path, double time_limit_s);

}  // namespace cb
