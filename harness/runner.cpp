#include "harness/runner.hpp"

#include "harness/history.hpp"
#include "harness/provenance.hpp"
#include "solvers/a_product.hpp"
#include "solvers/decouple.hpp"
#include "solvers/peak_memory.hpp"
#include "solvers/registry.hpp"
#include "solvers/work_units.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace cb {

namespace {

double median(std::vector<double> v)
{
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t mid = v.size() / 2;
    return v.size() % 2 ? v[mid] : 0.5 * (v[mid - 1] + v[mid]);
}

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

// Peak resident memory in MiB. The run's peak is the process's plus its largest child's: an upper
// bound, since pages a forked child shares with the parent and touches count in both (the parent
// waits while its child solves, so both peaks are held at once).
nlohmann::json memory_json(const PeakMemory& peak)
{
    constexpr double MIB = 1024.0 * 1024.0;
    auto mib = [&](long bytes) { return bytes >= 0 ? nlohmann::json(bytes / MIB) : nlohmann::json(); };
    const long total = peak.process_bytes < 0 ? -1 : peak.process_bytes + peak.children_bytes;
    return {{"peak_rss_mb", mib(total)},
            {"process_peak_rss_mb", mib(peak.process_bytes)},
            {"children_peak_rss_mb", mib(peak.children_bytes)},
            {"peak_reset", peak.reset}};
}

}  // namespace

AccuracyParts measure_point(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g,
                            const Vec* own_lambda, double tol, Vec& lambda, bool& fitted)
{
    AccuracyParts best;
    bool have = false;
    if (own_lambda && own_lambda->size() == qp.m()) {
        lambda = *own_lambda;
        best = accuracy_from_gradient(qp, scale, x, g, lambda);
        have = true;
    }
    if (!have || !(best.max() <= tol)) {
        const Vec candidate = fit_multipliers(qp, scale, x, g);
        const AccuracyParts with_fit = accuracy_from_gradient(qp, scale, x, g, candidate);
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

RunOutcome run_solver(const SolverRegistry& registry, const Qp& original, const std::string& solver_name,
                      const nlohmann::json& settings_in, const RunOptions& options, const nlohmann::json& snapshot_info,
                      const SolveContext& warm)
{
    nlohmann::json settings = settings_in.is_object() ? settings_in : nlohmann::json::object();
    if (!settings_in.is_null() && !settings_in.is_object())
        throw_input_error(solver_name, "settings", "expected a JSON object, got " + settings_in.dump());
    if (options.time_limit_s > 0.0) settings["time_limit_s"] = options.time_limit_s;
    if (options.repeat < 1)
        throw_input_error(solver_name, "repeat", "must be >= 1, got " + std::to_string(options.repeat));
    // Creating the solver validates the settings (InputError names the key).
    std::unique_ptr<Solver> solver = registry.create(solver_name, settings);

    // Decoupling: a problem transform applied before the solver sees the QP.
    const Qp* qp = &original;
    Qp decoupled;
    std::vector<int> decoupled_rows;
    nlohmann::json decouple = {{"order", options.decouple},
                               {"seed", options.decouple_seed},
                               {"rows_before", original.m()},
                               {"rows_after", original.m()},
                               {"applied", false}};
    bool want = false;
    DecoupleOrder order = DecoupleOrder::AUTHORS;
    if (options.decouple == "auto") {
        want = solver->requires_decoupled() && original.m() > 0 && !is_decoupled(original.J);
    } else if (options.decouple != "none") {
        order = decouple_order_from_string(options.decouple);
        want = original.m() > 0;
    }
    if (want) {
        const DecoupleReport report = decouple_rows(original.view(), original.contacts, order, options.decouple_seed);
        decouple["order"] = to_string(order);
        decouple["rows_after"] = report.rows_after;
        decouple["already_decoupled"] = report.already_decoupled;
        if (!report.already_decoupled && static_cast<long>(report.kept_rows.size()) < original.m()) {
            decoupled_rows = report.kept_rows;
            decoupled = select_rows(original, report.kept_rows);
            qp = &decoupled;
            decouple["applied"] = true;
            decouple["rows_after"] = decoupled.m();
        }
    }
    const QpView view = qp->view();
    const QpView original_view = original.view();
    // One scale for both: decoupling keeps A, b and x0, so D and l are the original's.
    const AccuracyScale scale = accuracy_scale(original_view);
    const AccuracyScale solved_scale = qp != &original ? accuracy_scale(view) : scale;

    // Warm state: multipliers only when they fit the rows (matched by row index).
    const std::vector<int>& kept_rows = decoupled_rows;
    Vec lambda0_kept;
    const Vec* lambda0 = nullptr;
    if (warm.lambda0 && qp != &original && warm.lambda0->size() == original.m()) {
        lambda0_kept.resize(static_cast<Eigen::Index>(kept_rows.size()));
        for (size_t k = 0; k < kept_rows.size(); ++k)
            lambda0_kept[static_cast<Eigen::Index>(k)] = (*warm.lambda0)[kept_rows[k]];
        lambda0 = &lambda0_kept;
    } else if (warm.lambda0 && warm.lambda0->size() == qp->m()) {
        lambda0 = warm.lambda0;
    }
    Vec eigen_in;
    if (warm.eigenvector) eigen_in = *warm.eigenvector;

    RunOutcome out;
    HistoryMonitor history(original_view, scale, options.history_max, options.record_history, kept_rows);
    std::vector<double> setup_times, solve_times, totals;
    nlohmann::json effective = solver->settings();
    long a_products_harness = 0;  // products through solvers/a_product during the (first) solve
    reset_peak_memory();          // this run's peak, not the process's (solvers/peak_memory.hpp)
    for (int r = 0; r < options.repeat; ++r) {
        if (r > 0) {
            solver = registry.create(solver_name, settings);  // no state carried between repeats
            if (warm.eigenvector) *warm.eigenvector = eigen_in;
        }
        SolveContext context;
        context.monitor = r == 0 ? &history : nullptr;
        context.lambda0 = lambda0;
        context.eigenvector = warm.eigenvector;
        const long products_before = a_product_count();
        SolverResult result = solver->solve(view, context);
        if (r == 0) a_products_harness = a_product_count() - products_before;
        setup_times.push_back(result.setup_s);
        solve_times.push_back(result.solve_s);
        totals.push_back(result.setup_s + result.solve_s);
        if (r == 0) out.result = std::move(result);
    }
    const SolverResult& result = out.result;
    const PeakMemory peak = read_peak_memory();

    // The measure at the returned point, by the harness, on the ORIGINAL QP.
    Vec x = result.x;
    std::string note;
    if (x.size() != qp->n()) {
        note = "solver returned x of size " + std::to_string(x.size()) + ", measured at x0";
        x = qp->x0;
    }
    const Vec g = original.A * x - original.b;  // decoupling keeps A and b
    const double tol = effective.value("tol", DEFAULT_ACCURACY_TOL);
    const bool native = result.criterion == StopCriterion::NATIVE;
    const double accuracy_tol = native ? DEFAULT_ACCURACY_TOL : tol;
    const bool own_valid = !result.lambda_fitted && result.lambda.size() == qp->m();
    // The solver's multipliers on the original rows (0 on rows it did not see).
    Vec own_full;
    if (own_valid && qp != &original) {
        own_full = Vec::Zero(original.m());
        for (size_t k = 0; k < kept_rows.size(); ++k)
            own_full[kept_rows[k]] = result.lambda[static_cast<Eigen::Index>(k)];
    } else if (own_valid) {
        own_full = result.lambda;
    }
    bool fitted = result.lambda_fitted;
    Vec lambda;
    out.accuracy =
        measure_point(original_view, scale, x, g, own_valid ? &own_full : nullptr, accuracy_tol, lambda, fitted);
    out.kept_rows = kept_rows;
    out.lambda_full = lambda;
    out.scale = scale;
    out.objective = 0.5 * x.dot(g) - 0.5 * original.b.dot(x);
    out.violation = max_violation(original_view, x);

    // The problem the solver solved, when it differs: the decoupled rows, or no rows at all for
    // a solver that ignores J (cg's unconstrained relaxation).
    const bool ignores_constraints = result.info.is_object() && result.info.value("ignores_constraints", false);
    const SpMat no_rows(0, original.n());
    const Vec no_c(0);
    const bool changed = qp != &original || (ignores_constraints && original.m() > 0);
    out.m_solved = ignores_constraints ? 0 : qp->m();
    if (!changed) {
        out.accuracy_solved = out.accuracy;
    } else if (ignores_constraints) {
        const QpView relaxed{original.A, original.b, no_rows, no_c, original.x0};
        out.accuracy_solved = accuracy_from_gradient(relaxed, accuracy_scale(relaxed), x, g, Vec(0));
    } else {
        Vec lambda_solved;
        bool fitted_solved = result.lambda_fitted;
        out.accuracy_solved = measure_point(view, solved_scale, x, g, own_valid ? &result.lambda : nullptr,
                                            accuracy_tol, lambda_solved, fitted_solved);
    }
    history.finish(x, lambda, result.iterations, result.setup_s, result.solve_s, result.counters.a_products,
                   result.native_residual, result.counters.work_flops);
    out.nonfinite = history.nonfinite() || !std::isfinite(out.objective) || !std::isfinite(out.accuracy.max());
    out.monotone = history.monotone();

    // The run's status (runner.hpp). stop=native stops on the paper's residual, whose tol is in
    // another unit: its "converged" must still reach the default accuracy on e.
    const double slack = 1.0 + 1e-9;  // the solver's own arithmetic may round the last digit differently
    const bool original_ok = std::isfinite(out.accuracy.max()) && out.accuracy.max() <= accuracy_tol * slack;
    const bool solved_ok =
        std::isfinite(out.accuracy_solved.max()) && out.accuracy_solved.max() <= accuracy_tol * slack;
    const bool native_ok = std::isfinite(result.native_residual) && result.native_residual <= tol * slack;
    if (result.status != SolveStatus::CONVERGED) {
        out.status = to_string(result.status);
    } else if (original_ok) {
        out.status = to_string(SolveStatus::CONVERGED);
    } else if (changed && solved_ok) {
        out.status = STATUS_SOLVED_RELAXATION;
    } else {
        out.status = STATUS_UNCONFIRMED;
        out.status_confirmed = false;
    }

    nlohmann::json snapshot = snapshot_info.is_object() ? snapshot_info : nlohmann::json::object();
    if (!snapshot.contains("n")) snapshot["n"] = original.n();
    if (!snapshot.contains("m")) snapshot["m"] = original.m();

    nlohmann::json& rec = out.record;
    rec["solver"] = solver_name;
    rec["label"] = solver_name;
    rec["settings"] = effective;
    rec["snapshot"] = snapshot;
    rec["decouple"] = decouple;
    rec["warm"] = {{"lambda0", lambda0 != nullptr}, {"eigenvector", warm.eigenvector != nullptr}};
    rec["status"] = out.status;
    rec["solver_status"] = to_string(result.status);
    rec["criterion"] = to_string(result.criterion);
    rec["message"] = note.empty() ? result.message : result.message + (result.message.empty() ? "" : "; ") + note;
    rec["iterations"] = result.iterations;
    rec["objective"] = finite_or_null(out.objective);
    rec["objective_x0"] = finite_or_null(objective(original_view, original.x0));
    rec["accuracy"] = out.accuracy.to_json();
    // The same object under its former name, read by `compare` and `run`'s progress line.
    rec["kkt_relative"] = rec["accuracy"];
    rec["accuracy_tol"] = accuracy_tol;
    rec["length_scale"] = finite_or_null(scale.length);
    rec["length_scale_source"] = scale.length_source;
    rec["stiffness_scale"] = finite_or_null(scale.stiffness);
    rec["m_solved"] = out.m_solved;
    if (changed) {
        rec["accuracy_solved"] = out.accuracy_solved.to_json();
        rec["solved_problem"] = ignores_constraints ? "unconstrained" : "decoupled";
    }
    rec["violation"] = finite_or_null(out.violation);
    rec["violation_original"] = finite_or_null(out.violation);
    rec["native_residual"] = finite_or_null(result.native_residual);
    rec["lambda_fitted"] = fitted;
    rec["nonfinite"] = out.nonfinite;
    rec["monotone"] = out.monotone;
    rec["status_confirmed"] = out.status_confirmed;
    if (result.status == SolveStatus::CONVERGED && native) rec["native_confirmed"] = native_ok;
    rec["tol"] = tol;
    rec["counters"] = result.counters.to_json();
    rec["counters"]["a_products_harness"] = a_products_harness;         // counted by the harness, not the solver
    rec["counters"]["work"] = work_units(result.counters, original.A);  // A-product equivalents (docs/work.md)
    nlohmann::json time = {{"setup_s", median(setup_times)},
                           {"solve_s", median(solve_times)},
                           {"total_s", median(totals)},
                           {"repeat", options.repeat}};
    if (options.repeat > 1) {
        time["min_total_s"] = *std::min_element(totals.begin(), totals.end());
        time["max_total_s"] = *std::max_element(totals.begin(), totals.end());
        time["samples_total_s"] = totals;
    }
    rec["time"] = time;
    rec["memory"] = memory_json(peak);
    rec["info"] = result.info.is_null() ? nlohmann::json::object() : result.info;
    if (options.record_history) rec["history"] = history.to_json();
    rec["provenance"] = provenance();
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
