#include "harness/runner.hpp"

#include "harness/history.hpp"
#include "harness/provenance.hpp"
#include "harness/run_problem.hpp"
#include "harness/run_record.hpp"
#include "solvers/core/peak_memory.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/friction_snapshot_error.hpp"
#include "solvers/measure/work_units.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace cb {

AccuracyParts measure_point(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g,
                            const Vec* own_lambda, double tol, Vec& lambda, bool& fitted, const Vec* lambda_t)
{
    AccuracyParts best;
    bool have = false;
    if (own_lambda && own_lambda->size() == qp.m()) {
        lambda = *own_lambda;
        best = accuracy_from_gradient(qp, scale, x, g, lambda, lambda_t);
        have = true;
    }
    if (!have || !(best.max() <= tol)) {
        const bool tangential =
            lambda_t && qp.friction && lambda_t->size() == qp.friction->T.rows() && qp.friction->T.cols() == g.size();
        const Vec candidate =
            fit_multipliers(qp, scale, x, tangential ? Vec(g - qp.friction->T.transpose() * *lambda_t) : g);
        const AccuracyParts with_fit = accuracy_from_gradient(qp, scale, x, g, candidate, lambda_t);
        if (!have || with_fit.max() < best.max()) {
            best = with_fit;
            lambda = candidate;
            fitted = true;
        }
    }
    return best;
}

RunOutcome run_solver(const Qp& qp, const std::string& solver_name, const nlohmann::json& settings,
                      const RunOptions& options, const nlohmann::json& snapshot_info)
{
    return run_solver(builtin_registry(), qp, solver_name, settings, options, snapshot_info, SolveContext{});
}

RunOutcome run_solver(const Qp& qp, const std::string& solver_name, const nlohmann::json& settings,
                      const RunOptions& options, const nlohmann::json& snapshot_info, const SolveContext& warm)
{
    return run_solver(builtin_registry(), qp, solver_name, settings, options, snapshot_info, warm);
}

namespace {

/// The settings a run gives its solver: the caller's object, the run's defaults for the keys it
/// does not set, and the run's time limit. The one place where the harness adds settings.
nlohmann::json run_settings(const std::string& solver_name, const nlohmann::json& settings_in,
                            const RunOptions& options)
{
    if (!settings_in.is_null() && !settings_in.is_object())
        throw_input_error(solver_name, "settings", "expected a JSON object, got " + settings_in.dump());
    nlohmann::json settings = settings_with_defaults(settings_in, options.defaults);
    if (options.time_limit_s > 0.0) settings["time_limit_s"] = options.time_limit_s;
    if (options.repeat < 1)
        throw_input_error(solver_name, "repeat", "must be >= 1, got " + std::to_string(options.repeat));
    return settings;
}

/// What the repeats of one solve leave: the first repeat's result (the one the monitor saw), the
/// times of all of them, the products counted by the harness in the first, and the run's peak memory.
struct Repeats {
    SolverResult first;
    RepeatTimes times;
    long a_products_harness = 0;
    PeakMemory peak;
};

/// Solves `options.repeat` times with a fresh solver each time (no state carried between
/// repeats); only the first has the monitor.
Repeats solve_repeats(const SolverRegistry& registry, const std::string& solver_name, const nlohmann::json& settings,
                      std::unique_ptr<Solver> solver, const QpView& view, const RunOptions& options, const Vec* lambda0,
                      const SolveContext& warm, Monitor* monitor)
{
    Repeats out;
    Vec eigen_in;
    if (warm.eigenvector) eigen_in = *warm.eigenvector;
    reset_peak_memory();  // this run's peak, not the process's (solvers/core/peak_memory.hpp)
    for (int r = 0; r < options.repeat; ++r) {
        if (r > 0) {
            solver = registry.create(solver_name, settings);
            if (warm.eigenvector) *warm.eigenvector = eigen_in;
        }
        SolveContext context;
        context.monitor = r == 0 ? monitor : nullptr;
        context.lambda0 = lambda0;
        context.eigenvector = warm.eigenvector;
        const long products_before = a_product_count();
        SolverResult result = solver->solve(view, context);
        if (r == 0) out.a_products_harness = a_product_count() - products_before;
        out.times.setup_s.push_back(result.setup_s);
        out.times.solve_s.push_back(result.solve_s);
        out.times.total_s.push_back(result.setup_s + result.solve_s);
        if (r == 0) out.first = std::move(result);
    }
    out.peak = read_peak_memory();
    return out;
}

/// The solver's multipliers on the original rows (0 on rows it did not see); empty when it gave
/// none of the right size or fitted them.
Vec own_multipliers(const SolverResult& result, const Qp& original, const SolverProblem& problem)
{
    if (result.lambda_fitted || result.lambda.size() != problem.view().m()) return Vec();
    if (problem.is_original()) return result.lambda;
    Vec full = Vec::Zero(original.m());
    for (size_t k = 0; k < problem.kept_rows.size(); ++k)
        full[problem.kept_rows[k]] = result.lambda[static_cast<Eigen::Index>(k)];
    return full;
}

/// The run's status (runner.hpp) from the solver's word and the measure. stop=native stops on the
/// paper's residual, whose tol is in another unit: its "converged" must still reach the default
/// accuracy on e.
void judge_status(RunOutcome& out, bool changed, double accuracy_tol, bool frictionless_relaxation)
{
    const double slack = 1.0 + 1e-9;  // the solver's own arithmetic may round the last digit differently
    const bool original_ok = std::isfinite(out.accuracy.max()) && out.accuracy.max() <= accuracy_tol * slack;
    const bool solved_ok =
        std::isfinite(out.accuracy_solved.max()) && out.accuracy_solved.max() <= accuracy_tol * slack;
    if (out.result.status != SolveStatus::CONVERGED) {
        out.status = to_string(out.result.status);
    } else if (original_ok && !frictionless_relaxation) {
        out.status = to_string(SolveStatus::CONVERGED);
    } else if (changed && solved_ok) {
        out.status = STATUS_SOLVED_RELAXATION;
    } else {
        out.status = STATUS_UNCONFIRMED;
        out.status_confirmed = false;
    }
}

/// The measure at the returned point, by the harness: e on the ORIGINAL QP (out.accuracy, with the
/// best multipliers at hand), e on the QP the solver solved when it changed it (out.accuracy_solved),
/// F, the violation, and the history's last row, NaN and monotonicity verdicts. Sets the facts the
/// measure decides (tol, accuracy_tol, the note on a wrong-sized x, changed, lambda_fitted).
void measure_outcome(RunOutcome& out, RunFacts& facts, const CommonSettings& common, const Qp& original,
                     const SolverProblem& problem, HistoryMonitor& history, bool handles_friction)
{
    const SolverResult& result = out.result;
    const QpView original_view = original.view();
    const QpView view = problem.view();
    const AccuracyScale& scale = out.scale;
    Vec x = result.x;
    if (x.size() != view.n()) {
        facts.note = "solver returned x of size " + std::to_string(x.size()) + ", measured at x0";
        x = view.x0;
    }
    const Vec g = original.A * x - original.b;  // decoupling keeps A and b
    facts.tol = common.tol;
    // stop=native: tol is in the solver's (or program's) own units, whatever it says it stopped
    // on, so every such run, the command solver's included, must reach the default accuracy.
    facts.native = result.criterion == StopCriterion::NATIVE || common.stops_on_native();
    facts.accuracy_tol = facts.native ? DEFAULT_ACCURACY_TOL : facts.tol;
    const bool own_valid = !result.lambda_fitted && result.lambda.size() == view.m();
    const Vec own_full = own_multipliers(result, original, problem);
    bool fitted = result.lambda_fitted;
    Vec lambda;
    // A frictional solver's tangential multipliers, on the problem as given (decoupling drops friction).
    const bool own_t = problem.is_original() && original.friction.T.rows() == 2 * original.m() &&
                       result.lambda_t.size() == 2 * original.m();
    if (own_t) out.lambda_t = result.lambda_t;
    const Vec* lambda_t = own_t ? &out.lambda_t : nullptr;
    out.accuracy = measure_point(original_view, scale, x, g, own_valid ? &own_full : nullptr, facts.accuracy_tol,
                                 lambda, fitted, lambda_t);
    if (original.frictional())
        out.fclib_error = friction_snapshot_error(original_view, x, lambda, own_t ? out.lambda_t : Vec(),
                                                  friction_local_q_norm(original_view));
    out.kept_rows = problem.kept_rows;
    out.lambda_full = lambda;
    out.objective = 0.5 * x.dot(g) - 0.5 * original.b.dot(x);
    out.violation = max_violation(original_view, x);

    // The problem the solver solved, when it differs: the decoupled rows, or no rows at all for
    // a solver that ignores J (cg's unconstrained relaxation).
    facts.ignores_constraints = result.info.is_object() && result.info.value("ignores_constraints", false);
    // A frictionless solver on a frictional problem solved the problem with mu = 0; so did a
    // frictional one that returned no tangential multipliers (a `command` program's x alone):
    // measured with lambda_T = 0 it would be judged on a problem it never claimed to solve.
    facts.frictionless = original.frictional() && !(handles_friction && own_t) && !facts.ignores_constraints;
    facts.decouple_applied = !problem.is_original();
    facts.frictional = original.frictional();
    if (facts.frictional)
        facts.mu_min = original.friction.mu.minCoeff(), facts.mu_max = original.friction.mu.maxCoeff();
    facts.changed = !problem.is_original() || (facts.ignores_constraints && original.m() > 0) || facts.frictionless;
    out.m_solved = facts.ignores_constraints ? 0 : view.m();
    if (!facts.changed) {
        out.accuracy_solved = out.accuracy;
    } else if (facts.ignores_constraints) {
        const SpMat no_rows(0, original.n());
        const Vec no_c(0);
        const QpView relaxed{original.A,  original.b,       no_rows, no_c,
                             original.x0, &original.length, nullptr, original.a_symmetric};
        out.accuracy_solved = accuracy_from_gradient(relaxed, accuracy_scale_with_rows(scale, relaxed), x, g, Vec(0));
    } else {
        // The decoupled rows, or the rows without their friction: the view with no friction fields.
        const QpView solved{view.A, view.b, view.J, view.c, view.x0, view.length, nullptr, view.a_symmetric};
        Vec lambda_solved;
        bool fitted_solved = result.lambda_fitted;
        // The same A, b and x0 as the problem's own scale: only the rows' parts are formed again.
        out.accuracy_solved = measure_point(solved, accuracy_scale_with_rows(scale, solved), x, g,
                                            own_valid ? &result.lambda : nullptr,
                                            facts.accuracy_tol, lambda_solved, fitted_solved);
    }
    history.finish(x, lambda, result.iterations, result.setup_s, result.solve_s, result.counters.a_products,
                   result.native_residual, result.counters.work_flops, lambda_t);
    out.nonfinite = history.nonfinite() || !std::isfinite(out.objective) || !std::isfinite(out.accuracy.max());
    out.monotone = history.monotone();
    facts.lambda_fitted = fitted;
}

}  // namespace

nlohmann::json settings_with_defaults(const nlohmann::json& settings_in, const SettingDefaults& defaults)
{
    nlohmann::json settings = settings_in.is_object() ? settings_in : nlohmann::json::object();
    if (defaults.tol && !settings.contains("tol")) settings["tol"] = *defaults.tol;
    if (defaults.time_limit_s && !settings.contains("time_limit_s")) settings["time_limit_s"] = *defaults.time_limit_s;
    return settings;
}

RunOutcome run_solver(const SolverRegistry& registry, const Qp& original, const std::string& solver_name,
                      const nlohmann::json& settings_in, const RunOptions& options, const nlohmann::json& snapshot_info,
                      const SolveContext& warm)
{
    const nlohmann::json settings = run_settings(solver_name, settings_in, options);
    // Creating the solver validates the settings (InputError names the key).
    std::unique_ptr<Solver> solver = registry.create(solver_name, settings);
    const bool handles_friction = solver->handles_friction();
    RunFacts facts;
    facts.solver = solver_name;
    facts.settings = solver->settings();
    // The solver's effective common block, typed by the one reader of solvers/core/settings.hpp (its
    // defaults, not the harness's: active-set's tol defaults to 1e-10).
    const CommonSettings common = SettingsReader(facts.settings, solver_name).common();

    // Decoupling: a problem transform applied before the solver sees the QP.
    SolverProblem problem;
    choose_solver_problem(original, solver->requires_decoupled(), options, problem);
    // A frictionless solver is given the problem it solves, without the friction (mu = 0): its
    // own stop test then measures that problem, and the harness's verdict says so.
    QpView view = problem.view();
    if (!handles_friction) view.friction = nullptr;
    const QpView original_view = original.view();
    Vec lambda0_kept;
    const Vec* lambda0 = warm_multipliers(warm.lambda0, original, problem, lambda0_kept);

    // The harness's own scale, the measure the solver cannot have changed (one for both problems:
    // decoupling keeps A, b and x0, so D and l are the original's). It is built after the solve
    // unless the monitor measures iterates during it: the solver builds its own for its stop test,
    // and holding both at once held the body modes twice (n x 6 doubles, 50 MB at a million DOFs).
    RunOutcome out;
    if (options.record_history) out.scale = accuracy_scale(original_view);
    HistoryMonitor history(original_view, out.scale, options.history_max, options.record_history, problem.kept_rows);
    Repeats repeats =
        solve_repeats(registry, solver_name, settings, std::move(solver), view, options, lambda0, warm, &history);
    if (!options.record_history) out.scale = accuracy_scale(original_view);
    out.result = std::move(repeats.first);
    const SolverResult& result = out.result;

    measure_outcome(out, facts, common, original, problem, history, handles_friction);
    judge_status(out, facts.changed, facts.accuracy_tol, facts.frictionless);

    facts.snapshot = snapshot_info.is_object() ? snapshot_info : nlohmann::json::object();
    if (!facts.snapshot.contains("n")) facts.snapshot["n"] = original.n();
    if (!facts.snapshot.contains("m")) facts.snapshot["m"] = original.m();
    facts.decouple = problem.decouple;
    facts.warm_lambda0 = lambda0 != nullptr;
    facts.warm_eigenvector = warm.eigenvector != nullptr;
    facts.native_ok = std::isfinite(result.native_residual) && result.native_residual <= facts.tol * (1.0 + 1e-9);
    facts.objective_x0 = objective(original_view, original.x0);
    facts.a_products_harness = repeats.a_products_harness;
    facts.work = work_units(result.counters, original.A);
    facts.times = std::move(repeats.times);
    facts.peak = repeats.peak;
    if (options.record_history) facts.history = history.to_json();
    out.record = run_record(out, facts, options.repeat);
    return out;
}

nlohmann::json run_identity(const nlohmann::json& snapshot_hash, const std::string& solver,
                            const nlohmann::json& settings, const nlohmann::json& entry)
{
    return {{"snapshot_hash", snapshot_hash},
            {"solver", solver},
            {"settings", settings},
            {"entry", entry},
            {"build", build_identity()}};
}

std::string stale_reason(const nlohmann::json& record, const nlohmann::json& identity)
{
    if (!record.is_object()) return "the run file is not a JSON object";
    if (!record.value("final", true))
        return "it failed for an input or harness error (" + record.value("status", std::string("?")) + "), retried";
    const auto it = record.find("identity");
    if (it == record.end() || !it->is_object()) return "it has no run identity (written by an older contactbench)";
    const nlohmann::json& old = *it;
    auto differs = [&](const char* key) { return !old.contains(key) || old[key] != identity[key]; };
    if (differs("snapshot_hash")) return "the snapshot's content changed";
    if (differs("solver")) return "the solver changed";
    if (differs("settings")) return "the settings changed";
    if (differs("entry")) return "the suite entry changed";
    if (differs("build")) return "the build changed (commit or binary)";
    if (old != identity) return "its identity differs";
    return "";
}

}  // namespace cb
