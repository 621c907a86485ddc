#pragma once
/// The stress suite (`contactbench stress`): every solver x every stress case (harness/stress_families.hpp)
/// through run_solver with a time limit per run, each run in a forked child process by default so
/// that a crash or a hang is recorded as an outcome instead of ending the suite.
/// Output: DIR/stability.csv (one row per run), DIR/stability.md (a table and the wrong statuses),
/// DIR/runs/<case>__<solver>.json (the per-run record, without history). All writes are atomic.
#include "harness/stress_families.hpp"

#include <iosfwd>
#include <string>
#include <vector>

namespace cb {

struct StressOptions {
    std::string out_dir;               ///< "" = write nothing
    double time_limit_s = 5.0;         ///< per run (solver time)
    double tol = 1e-6;                 ///< tolerance on the accuracy error e given to every solver
    bool reference = true;             ///< solve each case with active-set (tol 1e-10) for F* and the energy gap
    std::vector<std::string> solvers;  ///< empty = every registered solver
    std::vector<std::string> cases;    ///< ids or families; empty = all (of the quick set if quick)
    bool quick = false;                ///< the 4-case subset
    bool isolate = true;               ///< fork a child per run (crash and hang safe)
    std::ostream* progress = nullptr;  ///< one line per run (stderr from the command)
};

/// One run: the columns of stability.csv.
struct StressRow {
    std::string solver, case_id, family;
    int severity = 0;
    std::string status;            ///< the run's status (harness/runner.hpp), or "crashed" / "hung" / "error"
    std::string solver_status;     ///< the solver's own word (a SolveStatus name), "" when it gave none
    double accuracy = 0.0;         ///< the accuracy error e on the original QP at the returned point
    double accuracy_solved = 0.0;  ///< e on the QP the solver solved (decoupled / unconstrained)
    double tol = 0.0;
    double violation = 0.0;   ///< max(0, c - Jx) on the original rows, length units
    double primal = 0.0;      ///< the same as a fraction of the scene size (e's primal part)
    double energy_gap = 0.0;  ///< |F - F*| / (d_ref l^2), NaN without a reference
    bool nonfinite = false, monotone = true;
    double time_s = 0.0;  ///< setup + solve
    long iterations = 0;
    bool status_confirmed = true;  ///< false for "unconfirmed" (the solver's claim fails on its own QP)
    std::string message;
    long n = 0, m = 0;
    std::string criterion;
    long m_solved = 0;  ///< rows the solver saw (fewer than m when the harness decoupled J)

    /// An honest outcome: "converged" (which the measure confirmed), "solved_relaxation" (the
    /// solver's claim holds on the problem it solved, and the status says so), or any
    /// non-converged solver status with a message (invalid_input and infeasible included).
    /// "unconfirmed", crashes and hangs are not.
    bool honest() const;
};

struct StressReport {
    std::vector<StressRow> rows;
    double wall_s = 0.0;
    double time_limit_s = 0.0, tol = 0.0;
};

/// Runs the suite (throws InputError on an unknown solver or case name).
StressReport run_stress(const StressOptions& options);

/// Columns: solver, case, severity, status, accuracy, tol, violation, nonfinite, monotone, time_s,
/// iterations, status_confirmed, message, family, n, m, criterion, m_solved, solver_status,
/// accuracy_solved, primal, energy_gap.  (accuracy = the error e on the original QP.)
std::string stability_csv(const std::vector<StressRow>& rows);
/// A case x solver table (status and KKT reached) and a summary of wrong statuses.
std::string stability_markdown(const StressReport& report);

}  // namespace cb
