#include "harness/run_record.hpp"

#include "harness/provenance.hpp"

#include <algorithm>
#include <cmath>

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

nlohmann::json time_json(const RepeatTimes& t, int repeat)
{
    nlohmann::json time = {{"setup_s", median(t.setup_s)},
                           {"solve_s", median(t.solve_s)},
                           {"total_s", median(t.total_s)},
                           {"repeat", repeat}};
    if (repeat > 1) {
        time["min_total_s"] = *std::min_element(t.total_s.begin(), t.total_s.end());
        time["max_total_s"] = *std::max_element(t.total_s.begin(), t.total_s.end());
        time["samples_total_s"] = t.total_s;
    }
    return time;
}

}  // namespace

nlohmann::json run_record(const RunOutcome& out, const RunFacts& facts, int repeat)
{
    const SolverResult& result = out.result;
    nlohmann::json snapshot = facts.snapshot.is_object() ? facts.snapshot : nlohmann::json::object();
    nlohmann::json rec;
    rec["solver"] = facts.solver;
    rec["label"] = facts.solver;
    rec["settings"] = facts.settings;
    rec["snapshot"] = snapshot;
    rec["decouple"] = facts.decouple;
    rec["warm"] = {{"lambda0", facts.warm_lambda0}, {"eigenvector", facts.warm_eigenvector}};
    rec["status"] = out.status;
    rec["solver_status"] = to_string(result.status);
    rec["criterion"] = to_string(result.criterion);
    rec["message"] =
        facts.note.empty() ? result.message : result.message + (result.message.empty() ? "" : "; ") + facts.note;
    rec["iterations"] = result.iterations;
    rec["objective"] = finite_or_null(out.objective);
    rec["objective_x0"] = finite_or_null(facts.objective_x0);
    rec["accuracy"] = out.accuracy.to_json();
    rec["accuracy_tol"] = facts.accuracy_tol;
    rec["length_scale"] = finite_or_null(out.scale.length);
    rec["length_scale_source"] = out.scale.length_source;
    rec["stiffness_scale"] = finite_or_null(out.scale.stiffness);
    rec["m_solved"] = out.m_solved;
    if (facts.changed) {
        rec["accuracy_solved"] = out.accuracy_solved.to_json();
        rec["solved_problem"] = facts.ignores_constraints ? "unconstrained"
                                : facts.decouple_applied  ? "decoupled"
                                                          : "frictionless";
    }
    // A frictional problem (some mu > 0): FCLIB's relative natural-map error beside e (issue 48).
    if (facts.frictional) {
        rec["fclib_error"] = finite_or_null(out.fclib_error);
        rec["friction"] = {{"mu_min", facts.mu_min}, {"mu_max", facts.mu_max}};
    }
    rec["violation"] = finite_or_null(out.violation);
    rec["violation_original"] = finite_or_null(out.violation);
    rec["native_residual"] = finite_or_null(result.native_residual);
    rec["lambda_fitted"] = facts.lambda_fitted;
    rec["nonfinite"] = out.nonfinite;
    rec["monotone"] = out.monotone;
    rec["status_confirmed"] = out.status_confirmed;
    if (result.status == SolveStatus::CONVERGED && facts.native) rec["native_confirmed"] = facts.native_ok;
    rec["tol"] = facts.tol;
    rec["counters"] = result.counters.to_json();
    rec["counters"]["a_products_harness"] = facts.a_products_harness;  // counted by the harness, not the solver
    rec["counters"]["work"] = facts.work;                              // A-product equivalents (docs/work.md)
    rec["time"] = time_json(facts.times, repeat);
    rec["memory"] = memory_json(facts.peak);
    rec["info"] = result.info.is_null() ? nlohmann::json::object() : result.info;
    if (!facts.history.is_null()) rec["history"] = facts.history;
    // An external program works in its own process: its work is not counted (null), never 0,
    // which would draw it as solving every problem for free (docs/work.md).
    rec["work_counted"] = !(result.info.is_object() && result.info.contains("command"));
    if (!rec["work_counted"].get<bool>()) {
        for (const char* key : {"a_products", "work", "work_flops"}) rec["counters"][key] = nullptr;
        if (rec.contains("history")) {
            const nlohmann::json& columns = rec["history"]["columns"];
            for (size_t c = 0; c < columns.size(); ++c)
                if (columns[c] == "a_products" || columns[c] == "work")
                    for (auto& row : rec["history"]["rows"]) row[c] = nullptr;
        }
    }
    rec["provenance"] = provenance();
    return rec;
}

nlohmann::json failed_record(const std::string& solver, const std::string& label, const nlohmann::json& settings,
                             const nlohmann::json& snapshot, const std::string& status, const std::string& message,
                             double tol)
{
    const nlohmann::json no_accuracy = {{"stationarity", nullptr},    {"primal", nullptr}, {"dual", nullptr},
                                        {"complementarity", nullptr}, {"gap", nullptr},    {"max", nullptr}};
    return {{"solver", solver},
            {"label", label},
            {"settings", settings},
            {"snapshot", snapshot},
            {"decouple", {{"applied", false}}},
            {"status", status},
            {"criterion", ""},
            {"message", message},
            {"iterations", 0},
            {"objective", nullptr},
            {"accuracy", no_accuracy},
            {"violation", nullptr},
            {"native_residual", nullptr},
            {"lambda_fitted", false},
            {"nonfinite", false},
            {"monotone", true},
            {"status_confirmed", true},
            {"tol", tol},
            {"counters", Counters{}.to_json()},
            {"time", {{"setup_s", 0.0}, {"solve_s", 0.0}, {"total_s", 0.0}, {"repeat", 0}}},
            {"info", nlohmann::json::object()},
            {"provenance", provenance()}};
}

}  // namespace cb
