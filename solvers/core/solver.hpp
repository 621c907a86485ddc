#pragma once
/// The one interface every solver implements, with its status, counters and monitor.
#include "solvers/core/qp.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/stopwatch.hpp"
#include "solvers/measure/accuracy.hpp"

#include <nlohmann/json.hpp>
#include <memory>
#include <string>

namespace cb {

/// Why a solve ended. Numerical failure is a status, never an exception.
enum class SolveStatus {
    NOT_RUN,
    CONVERGED,  ///< the stop rule it was given was met (see SolverResult::criterion)
    MAX_ITERATIONS,
    TIME_LIMIT,
    STALLED,         ///< no progress possible (e.g. a zero step), criterion not met
    DIVERGED,        ///< NaN/Inf or an objective that blew up
    INFEASIBLE,      ///< the constraint set is empty (detected)
    INVALID_INPUT,   ///< the problem does not satisfy the solver's preconditions
    NOT_APPLICABLE,  ///< a problem class the solver does not take (general rows for mprgp-box, m > max_rows for pgs)
    STOPPED_BY_MONITOR,
};
const char* to_string(SolveStatus status);
SolveStatus solve_status_from_string(const std::string& name);  ///< throws InputError

/// Which stop rule a converged solve met (SolverResult::criterion); only SolveLoop::finish sets it
/// (a harness solver that trusts its program: PROGRAM).
enum class StopCriterion {
    NONE,      ///< not converged
    ACCURACY,  ///< stop=kkt: the accuracy error e of docs/accuracy.md <= tol
    NATIVE,    ///< stop=native: the solver's own residual <= tol
    PROGRAM,   ///< the external program's own verdict (harness/command_solver)
};
/// "", "kkt", "native", "program": the record's `criterion` text (stop=kkt keeps its name).
const char* to_string(StopCriterion criterion);

/// What the last step of an iteration was (reported to the Monitor and in histories).
enum class StepKind { START, CG, EXPANSION, PROPORTIONING, SAFEGUARD, PGS_SWEEP, PIVOT, OUTER, FINAL };
const char* to_string(StepKind kind);

/// Deterministic work counters. CI regression compares these exactly.
struct Counters {
    long iterations = 0;
    long cg_steps = 0;
    long expansion_steps = 0;
    long proportioning_steps = 0;
    long safeguard_steps = 0;  ///< Alg. 3 safeguard firings
    long a_products = 0;       ///< products with A (or equivalents, e.g. one GS sweep = 1)
    long precond_applications = 0;
    long precond_factorizations = 0;  ///< incomplete Cholesky factorizations (precond = ichol)
    long projections = 0;
    long power_products = 0;  ///< A-products spent in the power method (also in a_products)
    long cholmod_analyses = 0;
    long cholmod_factorizations = 0;
    long cholmod_solves = 0;
    long lcp_iterations = 0;  ///< inner LCP pivots or PGS sweeps
    long pgs_sweeps = 0;
    long pivots = 0;          ///< active-set changes
    double work_flops = 0.0;  ///< flops of work other than A-products (solvers/measure/work_units.hpp, docs/work.md)
    nlohmann::json to_json() const;
};

/// One monitor call. Pointers are valid only during the call.
struct IterationInfo {
    long iteration = 0;
    StepKind step = StepKind::START;
    const Vec* x = nullptr;        ///< current primal iterate (may be infeasible)
    const Vec* lambda = nullptr;   ///< multiplier estimate, or nullptr (harness then fits one)
    double native_residual = 0.0;  ///< the solver's own residual (MPRGP ||phi+beta||, ICA ||Ax-b-J'l||)
    long active_set_size = -1;     ///< -1 when the solver has no notion of it
    const Counters* counters = nullptr;
    double elapsed_s = 0.0;         ///< solver time since the start of its setup (monitor time excluded)
    double setup_s = 0.0;           ///< the setup's share of elapsed_s (elapsed_s - setup_s: the iterations)
    const Vec* lambda_t = nullptr;  ///< a frictional solver's 2m tangential multipliers, or nullptr
};

/// Called at every outer iteration; its time is excluded from the solver's time (SolveLoop::notify).
class Monitor {
public:
    virtual ~Monitor() = default;
    /// @return false to stop the solve (status STOPPED_BY_MONITOR).
    virtual bool on_iteration(const IterationInfo& info) = 0;
    /// Whether the next on_iteration call will read the iterate. When false, work done only to
    /// form it (SolveLoop::notify's `prepare`, e.g. pgs's x from lambda) is skipped and the call
    /// gets info.x = nullptr: a recorder on a stride should not pay for rows it drops.
    virtual bool wants_iterate() const { return true; }
};

/// Options the harness passes along with the problem (warm starts across a chain).
struct SolveContext {
    Monitor* monitor = nullptr;
    const Vec* lambda0 = nullptr;  ///< warm-start multipliers, or nullptr
    Vec* eigenvector = nullptr;    ///< in/out: power-method vector kept along a time-step chain
};

struct SolverResult {
    Vec x, lambda;
    SolveStatus status = SolveStatus::NOT_RUN;
    StopCriterion criterion = StopCriterion::NONE;  ///< which stop rule was met (set by SolveLoop::finish)
    std::string message;                            ///< human-readable detail (why it stopped, what was dropped)
    long iterations = 0;
    Counters counters;
    double setup_s = 0.0;          ///< start of solve() to the end of setup (factorisations, power method ...)
    double solve_s = 0.0;          ///< the iterations (setup_s + solve_s: the solver's time, monitor excluded)
    double native_residual = 0.0;  ///< at the returned x
    bool lambda_fitted = false;    ///< true when lambda came from fit_multipliers, not the solver
    nlohmann::json info = nlohmann::json::object();  ///< solver-specific facts (power method, rows dropped ...)
    Vec lambda_t;  ///< a frictional solver's tangential multipliers (2m, qp.friction's T rows); empty: 0
};

class Solver {
public:
    virtual ~Solver() = default;
    virtual std::string name() const = 0;
    /// The effective settings (defaults filled in), recorded in every results file.
    virtual nlohmann::json settings() const = 0;
    /// True when the solver needs a decoupled J (at most one row per vertex); the harness
    /// then applies the decoupling transform first.
    virtual bool requires_decoupled() const { return false; }
    /// True when the solver solves the Coulomb problem of a snapshot with friction (qp.friction).
    /// Otherwise it solves the frictionless problem (mu = 0) and the harness says so: status
    /// `solved_relaxation` at best, never `converged` (docs/accuracy.md "e for Coulomb friction").
    virtual bool handles_friction() const { return false; }
    virtual SolverResult solve(const QpView& qp, const SolveContext& context) = 0;
};

/// Calls the monitor with `watch` paused (elapsed_s = watch.seconds()). Solvers use
/// SolveLoop::notify (solvers/core/solve_loop.hpp), which stamps the time from the start of setup.
/// @return false when the monitor asked to stop.
bool notify_monitor(const SolveContext& context, Stopwatch& watch, IterationInfo info);
/// SolveLoop::notify's body: pauses `watch`, runs `prepare` (work done only for the monitor, which
/// may fill in `info`; skipped, and info.x set to nullptr, when the monitor does not want this
/// iterate), stamps info.elapsed_s = watch.seconds() and info.setup_s, calls the monitor. One named,
/// out-of-line function, so that a profiler can leave all monitor work out of a solver's count
/// (tools/perf_gate.py toggles callgrind's collection on cb::notify_monitor).
bool notify_monitor(const SolveContext& context, Stopwatch& watch, IterationInfo& info, double setup_s,
                    void (*prepare)(void*) = nullptr, void* prepare_data = nullptr);

/// The accuracy test by itself (docs/accuracy.md), for tests and tools: true when the accuracy
/// error e of (x, lambda) on `qp` (gradient g = Ax - b given) is <= tol. A solver never calls it:
/// its stop is SolveLoop's rule (check, verdict, rule_holds), which also honours stop=native.
bool accuracy_converged(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g, const Vec& lambda,
                        double tol);

}  // namespace cb
