#pragma once
/// The stress suite (`contactbench stress`): every solver x every stress case (problems/stress.hpp)
/// through run_solver with a time limit per run, each run in a forked child process by default so
/// that a crash or a hang is recorded as an outcome instead of ending the suite.
/// Output: DIR/stability.csv (one row per run), DIR/stability.md (a table and the wrong statuses),
/// DIR/runs/<case>__<solver>.json (the per-run record, without history). All writes are atomic.
#include "problems/stress.hpp"

#include <iosfwd>
#include <string>
#include <vector>

namespace cb {

struct StressOptions {
    std::string out_dir;              ///< "" = write nothing
    double time_limit_s = 5.0;        ///< per run (solver time)
    double tol = 1e-6;                ///< common relative KKT tolerance given to every solver
    std::vector<std::string> solvers; ///< empty = every registered solver
    std::vector<std::string> cases;   ///< ids or families; empty = all (of the quick set if quick)
    bool quick = false;               ///< the 4-case subset
    bool isolate = true;              ///< fork a child per run (crash and hang safe)
    std::ostream* progress = nullptr; ///< one line per run (stderr from the command)
};

/// One run: the columns of stability.csv.
struct StressRow {
    std::string solver, case_id, family;
    int severity = 0;
    std::string status;               ///< a SolveStatus name, or "crashed" / "hung" / "error"
    double kkt = 0.0;                 ///< relative common KKT error at the returned point
    double tol = 0.0;
    double violation = 0.0;           ///< max(0, c - Jx), length units
    bool nonfinite = false, monotone = true;
    double time_s = 0.0;              ///< setup + solve
    long iterations = 0;
    bool status_confirmed = true;     ///< "converged" confirmed by the common KKT
    std::string message;
    long n = 0, m = 0;
    std::string criterion;
    long m_solved = 0;                ///< rows the solver saw (fewer than m when the harness decoupled J)

    /// An honest outcome: a confirmed "converged", or any non-converged solver status with a
    /// message (invalid_input and infeasible included). Crashes and hangs are not.
    bool honest() const;
};

struct StressReport {
    std::vector<StressRow> rows;
    double wall_s = 0.0;
    double time_limit_s = 0.0, tol = 0.0;
};

/// Runs the suite (throws InputError on an unknown solver or case name).
StressReport run_stress(const StressOptions& options);

/// Columns: solver, case, severity, status, kkt, tol, violation, nonfinite, monotone, time_s,
/// iterations, status_confirmed, message, family, n, m, criterion, m_solved.
std::string stability_csv(const std::vector<StressRow>& rows);
/// A case x solver table (status and KKT reached) and a summary of wrong statuses.
std::string stability_markdown(const StressReport& report);

} // namespace cb
