#include "harness/runner.hpp"

#include "harness/history.hpp"
#include "harness/provenance.hpp"
#include "solvers/decouple.hpp"
#include "solvers/registry.hpp"

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

nlohmann::json kkt_json(const KktResiduals& k)
{
    nlohmann::json j = k.to_json();
    for (auto& item : j.items())
        if (item.value().is_number_float() && !std::isfinite(item.value().get<double>())) item.value() = nullptr;
    return j;
}

} // namespace

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
                      const nlohmann::json& settings_in, const RunOptions& options,
                      const nlohmann::json& snapshot_info, const SolveContext& warm)
{
    nlohmann::json settings = settings_in.is_object() ? settings_in : nlohmann::json::object();
    if (!settings_in.is_null() && !settings_in.is_object())
        throw_input_error(solver_name, "settings", "expected a JSON object, got " + settings_in.dump());
    if (options.time_limit_s > 0.0) settings["time_limit_s"] = options.time_limit_s;
    if (options.repeat < 1) throw_input_error(solver_name, "repeat", "must be >= 1, got " + std::to_string(options.repeat));
    // Creating the solver validates the settings (InputError names the key).
    std::unique_ptr<Solver> solver = registry.create(solver_name, settings);

    // Decoupling: a problem transform applied before the solver sees the QP.
    const Qp* qp = &original;
    Qp decoupled;
    std::vector<int> decoupled_rows;
    nlohmann::json decouple = {{"order", options.decouple}, {"seed", options.decouple_seed},
                               {"rows_before", original.m()}, {"rows_after", original.m()}, {"applied", false}};
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
    const KktScale scale = kkt_scale(view);

    // Warm state: multipliers only when they fit the rows (matched by row index).
    const std::vector<int>& kept_rows = decoupled_rows;
    Vec lambda0_kept;
    const Vec* lambda0 = nullptr;
    if (warm.lambda0 && qp != &original && warm.lambda0->size() == original.m()) {
        lambda0_kept.resize(static_cast<Eigen::Index>(kept_rows.size()));
        for (size_t k = 0; k < kept_rows.size(); ++k) lambda0_kept[static_cast<Eigen::Index>(k)] = (*warm.lambda0)[kept_rows[k]];
        lambda0 = &lambda0_kept;
    } else if (warm.lambda0 && warm.lambda0->size() == qp->m()) {
        lambda0 = warm.lambda0;
    }
    Vec eigen_in;
    if (warm.eigenvector) eigen_in = *warm.eigenvector;

    RunOutcome out;
    HistoryMonitor history(view, scale, options.history_max, options.record_history);
    std::vector<double> setup_times, solve_times, totals;
    nlohmann::json effective = solver->settings();
    for (int r = 0; r < options.repeat; ++r) {
        if (r > 0) {
            solver = registry.create(solver_name, settings);  // no state carried between repeats
            if (warm.eigenvector) *warm.eigenvector = eigen_in;
        }
        SolveContext context;
        context.monitor = r == 0 ? &history : nullptr;
        context.lambda0 = lambda0;
        context.eigenvector = warm.eigenvector;
        SolverResult result = solver->solve(view, context);
        setup_times.push_back(result.setup_s);
        solve_times.push_back(result.solve_s);
        totals.push_back(result.setup_s + result.solve_s);
        if (r == 0) out.result = std::move(result);
    }
    const SolverResult& result = out.result;

    // The common metric at the returned point, measured by the harness.
    Vec x = result.x;
    std::string note;
    if (x.size() != qp->n()) {
        note = "solver returned x of size " + std::to_string(x.size()) + ", measured at x0";
        x = qp->x0;
    }
    const Vec g = qp->A * x - qp->b;
    Vec lambda = result.lambda;
    bool fitted = result.lambda_fitted;
    if (lambda.size() != qp->m() || result.lambda_fitted) {
        lambda = fit_multipliers(view, x, g);
        fitted = true;
    }
    out.kept_rows = kept_rows;
    if (qp != &original) {
        out.lambda_full = Vec::Zero(original.m());
        for (size_t k = 0; k < kept_rows.size() && static_cast<Eigen::Index>(k) < lambda.size(); ++k)
            out.lambda_full[kept_rows[k]] = lambda[static_cast<Eigen::Index>(k)];
    } else {
        out.lambda_full = lambda;
    }
    out.kkt = kkt_residuals_from_gradient(view, x, g, lambda);
    out.kkt_relative = out.kkt.scaled(scale.inverse_reference);
    out.objective = 0.5 * x.dot(g) - 0.5 * qp->b.dot(x);
    out.violation = max_violation(view, x);
    history.finish(x, lambda, result.iterations, result.setup_s + result.solve_s, result.counters.a_products,
                   result.native_residual);
    out.nonfinite = history.nonfinite() || !std::isfinite(out.objective) || !std::isfinite(out.kkt.max());
    out.monotone = history.monotone();

    const double tol = effective.value("tol", 1e-6);
    const double kkt_rel = out.kkt_relative.max();
    const bool kkt_ok = std::isfinite(kkt_rel) && kkt_rel <= tol * (1.0 + 1e-9);
    const bool native_ok = std::isfinite(result.native_residual) && result.native_residual <= tol * (1.0 + 1e-9);
    // A solver that ignores J (cg, the Fig. 8 baseline) solves the unconstrained problem: its
    // "converged" is judged on that problem's KKT error (stationarity relative to x0), while the
    // constrained KKT error above stays what the results report.
    const bool ignores_constraints = result.info.is_object() && result.info.value("ignores_constraints", false);
    double unconstrained_rel = 0.0;
    if (ignores_constraints) {
        const double g0 = (qp->A * qp->x0 - qp->b).lpNorm<Eigen::Infinity>();
        unconstrained_rel = g0 > 0.0 ? g.lpNorm<Eigen::Infinity>() / g0 : 0.0;
    }
    const bool unconstrained_ok = std::isfinite(unconstrained_rel) && unconstrained_rel <= tol * (1.0 + 1e-9);
    if (result.status != SolveStatus::CONVERGED) out.status_confirmed = true;
    else if (ignores_constraints) out.status_confirmed = unconstrained_ok;
    else if (result.criterion == "kkt") out.status_confirmed = kkt_ok;
    else if (result.criterion == "native") out.status_confirmed = kkt_ok;  // the common metric must agree too
    else out.status_confirmed = kkt_ok;

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
    rec["status"] = to_string(result.status);
    rec["criterion"] = result.criterion;
    rec["message"] = note.empty() ? result.message : result.message + (result.message.empty() ? "" : "; ") + note;
    rec["iterations"] = result.iterations;
    rec["objective"] = finite_or_null(out.objective);
    rec["objective_x0"] = finite_or_null(objective(view, qp->x0));
    rec["kkt"] = kkt_json(out.kkt);
    rec["kkt_relative"] = kkt_json(out.kkt_relative);
    rec["kkt_reference"] = finite_or_null(scale.reference);
    rec["violation"] = finite_or_null(out.violation);
    // Dropped rows still matter to the user: the violation of the full J at the returned x.
    if (qp != &original) rec["violation_original"] = finite_or_null(max_violation(original.view(), x));
    rec["native_residual"] = finite_or_null(result.native_residual);
    rec["lambda_fitted"] = fitted;
    rec["nonfinite"] = out.nonfinite;
    rec["monotone"] = out.monotone;
    rec["status_confirmed"] = out.status_confirmed;
    if (ignores_constraints) {
        rec["confirmed_on"] = "unconstrained";
        rec["kkt_unconstrained_relative"] = finite_or_null(unconstrained_rel);
    }
    if (result.status == SolveStatus::CONVERGED && result.criterion == "native")
        rec["native_confirmed"] = native_ok;
    rec["tol"] = tol;
    rec["counters"] = result.counters.to_json();
    nlohmann::json time = {{"setup_s", median(setup_times)}, {"solve_s", median(solve_times)},
                           {"total_s", median(totals)}, {"repeat", options.repeat}};
    if (options.repeat > 1) {
        time["min_total_s"] = *std::min_element(totals.begin(), totals.end());
        time["max_total_s"] = *std::max_element(totals.begin(), totals.end());
        time["samples_total_s"] = totals;
    }
    rec["time"] = time;
    rec["info"] = result.info.is_null() ? nlohmann::json::object() : result.info;
    if (options.record_history) rec["history"] = history.to_json();
    rec["provenance"] = provenance();
    return out;
}

nlohmann::json run_identity(const nlohmann::json& snapshot_hash, const std::string& solver,
                            const nlohmann::json& settings, const nlohmann::json& entry)
{
    return {{"snapshot_hash", snapshot_hash}, {"solver", solver}, {"settings", settings}, {"entry", entry},
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

} // namespace cb
