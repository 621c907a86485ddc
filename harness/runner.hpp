#pragma once
/// Runs one solver on one QP the way every harness command does: decoupling when needed, a
/// recording monitor on the solver's paused stopwatch, the accuracy measure (docs/accuracy.md)
/// recomputed on the ORIGINAL QP at the returned point, the run's status, and the per-run
/// results JSON (harness/README.md "Results").
///
/// The run's status: `converged` only when the solver says converged AND the error e on the
/// original QP is <= tol (for stop=native, <= DEFAULT_ACCURACY_TOL: the native tol is in another
/// unit); `solved_relaxation` when the solver changed the problem (the harness decoupled its rows,
/// or it ignores J) and met the tolerance on its own problem only; `unconfirmed` when it said
/// converged and the measure disagrees on the problem it solved; otherwise the solver's status.
/// On a frictional problem a solver solved the frictional problem only when it handles friction
/// and returned its 2m tangential multipliers; otherwise its problem was the frictionless
/// relaxation (record "solved_problem": "frictionless").
#include "solvers/core/qp.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"
#include "solvers/measure/accuracy.hpp"

#include <nlohmann/json.hpp>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace cb {

/// Defaults of common settings for every solver of a suite or stress run: given to a solver whose
/// settings do not set the key (its own setting wins).
struct SettingDefaults {
    std::optional<double> tol;           ///< the suite's `tol`
    std::optional<double> time_limit_s;  ///< the suite's `time_limit_s` (0 disables)
};

/// `settings` with the defaults added for the keys it does not set: what the solver of a run with
/// these defaults is given (run_solver applies it; a run's identity records it).
nlohmann::json settings_with_defaults(const nlohmann::json& settings, const SettingDefaults& defaults);

struct RunOptions {
    SettingDefaults defaults;
    double time_limit_s = 0.0;  ///< overrides the solver's time_limit_s when > 0
    long history_max = 2000;    ///< records kept (stride chosen to stay under it)
    bool record_history = true;
    std::string decouple = "auto";  ///< auto (decouple when the solver requires it) | none | authors | random | depth
    std::uint64_t decouple_seed = 0;
    int repeat = 1;  ///< median time of k runs
};

/// Run statuses beside the solver's own (SolveStatus names).
inline constexpr const char* STATUS_SOLVED_RELAXATION = "solved_relaxation";
inline constexpr const char* STATUS_UNCONFIRMED = "unconfirmed";
/// The accuracy a `stop=native` run must reach on e to count as converged: the default tol of
/// the common settings (solvers/core/settings.hpp), declared there once.
inline constexpr double DEFAULT_ACCURACY_TOL = DEFAULT_TOL;  // the one default (solvers/core/settings.hpp)

struct RunOutcome {
    SolverResult result;                  ///< as the solver returned it (result.status: the solver's word)
    std::string status;                   ///< the run's status (above); record "status"
    AccuracyScale scale;                  ///< of the original QP
    AccuracyParts accuracy;               ///< e on the ORIGINAL QP at the returned (x, lambda)
    AccuracyParts accuracy_solved;        ///< e on the QP the solver solved (== accuracy when unchanged)
    long m_solved = 0;                    ///< rows of the QP the solver solved (0 for a solver ignoring J)
    double objective = 0, violation = 0;  ///< F(x) and max(0, c - Jx) of the original QP
    bool nonfinite = false;               ///< NaN/Inf seen in any iterate or the result
    bool monotone = true;                 ///< objective non-increasing over the recorded feasible iterates
    bool status_confirmed = true;         ///< false only for `unconfirmed` (the solver's claim fails on its own QP)
    nlohmann::json record;                ///< the full per-run results JSON (schema below)
    // Extensions beyond INTERFACES.md:
    std::vector<int> kept_rows;  ///< rows of the original J the solver saw (empty: all of them)
    Vec lambda_full;             ///< lambda on the original rows (0 on rows dropped by decoupling)
    Vec lambda_t;                ///< the solver's tangential multipliers (2m) on a frictional problem, else empty
    /// FCLIB's relative natural-map error at (x, lambda, lambda_t) (solvers/measure/friction_snapshot_error.hpp);
    /// NaN unless the problem is frictional (some mu > 0).
    double fclib_error = std::numeric_limits<double>::quiet_NaN();
};

/// Runs one solver on one QP with the monitor recording history on a paused stopwatch.
RunOutcome run_solver(const Qp& qp, const std::string& solver_name, const nlohmann::json& settings,
                      const RunOptions& options, const nlohmann::json& snapshot_info = {});

/// Same, with warm state carried along a chain (context.lambda0 / context.eigenvector; its
/// monitor field is ignored: the harness installs its own). lambda0 is used when its size is
/// the original m (restricted to the kept rows when decoupling applies) or the solved QP's m.
RunOutcome run_solver(const Qp& qp, const std::string& solver_name, const nlohmann::json& settings,
                      const RunOptions& options, const nlohmann::json& snapshot_info, const SolveContext& warm);

/// The measure at x on `qp` with the best multipliers at hand: `own_lambda` (when given, of size
/// m); a least-squares fit when it is missing, or when it misses `tol` and the fit does better
/// (e judges the point x, so the harness takes the smaller). `lambda` gets the multipliers used,
/// `fitted` is set when they are the fit. `solve` and `judge` both measure with this.
/// `lambda_t` (a frictional solver's 2m tangential multipliers, or nullptr) enters every evaluation;
/// the fit then fits the normal multipliers to the gradient less T'lambda_t.
AccuracyParts measure_point(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g,
                            const Vec* own_lambda, double tol, Vec& lambda, bool& fitted,
                            const Vec* lambda_t = nullptr);

class SolverRegistry;
/// Same, with the solver taken from `registry` (tests register small local solvers).
RunOutcome run_solver(const SolverRegistry& registry, const Qp& qp, const std::string& solver_name,
                      const nlohmann::json& settings, const RunOptions& options, const nlohmann::json& snapshot_info,
                      const SolveContext& warm);

/// Identity of one job of a suite run: what its result depends on. A stored run is reused only
/// when its "identity" equals this one (harness/README.md "Resume and run identity").
///   snapshot_hash  content hash of the snapshot file (null when it could not be read)
///   solver, settings  the registry name and the settings given to it (suite defaults merged)
///   entry          the suite's entry: snapshot id and path, label, and the suite-wide options
///                  that change a run (tol, time_limit_s, repeat, history_max, reference,
///                  decouple, decouple_seed, chain)
///   build          build_identity(): commit and binary hash
nlohmann::json run_identity(const nlohmann::json& snapshot_hash, const std::string& solver,
                            const nlohmann::json& settings, const nlohmann::json& entry);

/// Why a stored run record cannot stand for `identity` ("" when it can be reused): a record
/// without an identity, a different snapshot / solver / settings / suite entry / build, or a run
/// that failed for an input or harness error ("final": false), which is always retried.
std::string stale_reason(const nlohmann::json& record, const nlohmann::json& identity);

}  // namespace cb
