// `judge`'s core: the measure of a given point, its verdict, and the run's status from a record.
#include "harness/judge.hpp"

#include "harness/reference.hpp"
#include "harness/runner.hpp"
#include "solvers/measure/friction_snapshot_error.hpp"
#include "solvers/mprgp/decouple.hpp"

#include <cmath>
#include <limits>

namespace cb {

namespace {

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

/// The record's string at `key`, or an InputError naming the record and the field.
std::string record_string(const JudgeOptions& options, const char* key)
{
    const auto it = options.record.find(key);
    if (it == options.record.end() || !it->is_string())
        throw_input_error(options.record_path, std::string("/") + key,
                          "missing or not a string: is this a run record (solve --json, a suite's runs/*.json)?");
    return it->get<std::string>();
}

/// The record must name the snapshot it ran on, and it must be this one: a record without
/// /snapshot/hash proves nothing about the point (and a number there is a wrong record, not a
/// skipped check).
void check_record_snapshot(const JudgeOptions& options)
{
    const auto snap = options.record.find("snapshot");
    if (snap == options.record.end() || !snap->is_object())
        throw_input_error(options.record_path, "/snapshot",
                          "missing or not an object: is this a run record (solve --json, a suite's runs/*.json)?");
    const auto hash = snap->find("hash");
    if (hash == snap->end() || !hash->is_string() || hash->get<std::string>().empty())
        throw_input_error(options.record_path, "/snapshot/hash",
                          "missing or not a non-empty string: the record does not say which snapshot it ran on");
    const std::string h = hash->get<std::string>();
    if (!options.snapshot_hash.empty() && h != options.snapshot_hash)
        throw_input_error(options.record_path, "/snapshot/hash",
                          "the run was on another snapshot (hash " + h + ", this one " + options.snapshot_hash + ")");
}

/// `runner.cpp`'s rule: a solver's own arithmetic may round the last digit differently.
bool within(double e, double tol) { return std::isfinite(e) && e <= tol * (1.0 + 1e-9); }

}  // namespace

nlohmann::json Judgement::to_json() const
{
    nlohmann::json j;
    j["accuracy"] = accuracy.to_json();
    j["tol"] = tol;
    j["verdict"] = !meets_tol ? "not_converged" : relaxation ? "solved_relaxation" : "converged";
    j["judged_problem"] = !frictional ? "as_given" : relaxation ? "frictionless_relaxation" : "frictional";
    if (frictional) j["fclib_error"] = finite_or_null(fclib_error);
    j["lambda_fitted"] = lambda_fitted;
    j["objective"] = finite_or_null(objective);
    j["violation"] = finite_or_null(violation);
    j["length_scale"] = finite_or_null(scale.length);
    j["length_scale_source"] = scale.length_source;
    j["stiffness_scale"] = finite_or_null(scale.stiffness);
    j["status"] = status.empty() ? nlohmann::json() : nlohmann::json(status);
    if (have_solved) j["accuracy_solved"] = accuracy_solved.to_json();
    j["reference"] = reference;
    j["energy_gap"] = finite_or_null(energy_gap);
    return j;
}

Judgement judge_point(const Qp& qp, const SolutionPoint& point, const JudgeOptions& options)
{
    const bool have_record = !options.record.is_null();
    if (have_record && !options.record.is_object())
        throw_input_error(options.record_path, "", "expected a run record (a JSON object)");
    if (have_record) check_record_snapshot(options);
    Judgement out;
    out.tol = options.tol;
    if (!(out.tol > 0.0) && have_record) {
        const auto it = options.record.find("accuracy_tol");
        if (it == options.record.end() || !it->is_number() || !(it->get<double>() > 0.0))
            throw_input_error(options.record_path, "/accuracy_tol", "missing or not a positive number");
        out.tol = it->get<double>();
    }
    if (!(out.tol > 0.0)) out.tol = DEFAULT_ACCURACY_TOL;

    // A frictional snapshot is judged with its friction only when the point carries lambda_t:
    // otherwise lambda_T = 0 would be measured, a point nobody claimed; the relaxation is named.
    out.frictional = qp.frictional();
    const bool tangential = qp.friction.T.rows() > 0 && point.lambda_t.size() == qp.friction.T.rows();
    out.relaxation = out.frictional && !tangential;
    QpView view = qp.view();
    if (out.relaxation) view.friction = nullptr;
    out.scale = accuracy_scale(view);
    const Vec& x = point.x;
    const Vec g = qp.A * x - qp.b;
    const bool own = point.lambda.size() == qp.m() && !point.lambda_path.empty();
    out.lambda_fitted = !own;
    out.accuracy = measure_point(view, out.scale, x, g, own ? &point.lambda : nullptr, out.tol, out.lambda,
                                 out.lambda_fitted, tangential ? &point.lambda_t : nullptr);
    out.meets_tol = within(out.accuracy.max(), out.tol);
    out.fclib_error = out.frictional && tangential ? friction_snapshot_error(qp.view(), x, out.lambda, point.lambda_t,
                                                                             friction_local_q_norm(qp.view()))
                                                   : std::numeric_limits<double>::quiet_NaN();
    out.objective = 0.5 * x.dot(g) - 0.5 * qp.b.dot(x);
    out.violation = max_violation(view, x);

    if (have_record) {
        const std::string solver_status = record_string(options, "solver_status");
        solve_status_from_string(solver_status);  // an unknown name is an InputError
        // A frictionless solver on a frictional problem is never `converged` (docs/accuracy.md).
        const auto solved_at = options.record.find("solved_problem");
        const bool frictionless = solved_at != options.record.end() && solved_at->is_string() &&
                                  solved_at->get<std::string>() == "frictionless";
        if (solver_status != to_string(SolveStatus::CONVERGED)) {
            out.status = solver_status;
        } else if (out.meets_tol && !frictionless && !out.relaxation) {
            out.status = to_string(SolveStatus::CONVERGED);
        } else {
            // The solver said converged and the point misses tol on the original QP: on the
            // problem it solved (when it changed the problem) it may still have met it.
            const auto solved_it = options.record.find("solved_problem");
            if (solved_it != options.record.end() && !solved_it->is_string() && !solved_it->is_null())
                throw_input_error(options.record_path, "/solved_problem",
                                  "expected a string, got " + std::string(solved_it->type_name()));
            const std::string solved =
                solved_it != options.record.end() && solved_it->is_string() ? solved_it->get<std::string>() : "";
            if (solved == "unconstrained") {
                const SpMat no_rows(0, qp.n());
                const Vec no_c(0);
                const QpView relaxed{qp.A, qp.b, no_rows, no_c, qp.x0, &qp.length, nullptr, qp.a_symmetric};
                out.accuracy_solved = accuracy_from_gradient(relaxed, accuracy_scale(relaxed), x, g, Vec(0));
                out.have_solved = true;
            } else if (solved == "decoupled") {
                const nlohmann::json decouple = options.record.value("decouple", nlohmann::json::object());
                if (!decouple.is_object())
                    throw_input_error(options.record_path, "/decouple",
                                      "expected an object, got " + std::string(decouple.type_name()));
                const nlohmann::json order_json = decouple.value("order", nlohmann::json(""));
                if (!order_json.is_string())
                    throw_input_error(options.record_path, "/decouple/order",
                                      "expected a string, got " + std::string(order_json.type_name()));
                const std::string order = order_json.get<std::string>();
                const nlohmann::json seed_json = decouple.value("seed", nlohmann::json(0));
                if (!seed_json.is_number_unsigned() &&
                    !(seed_json.is_number_integer() && seed_json.get<long long>() >= 0))
                    throw_input_error(options.record_path, "/decouple/seed",
                                      "expected a non-negative integer, got " + seed_json.dump());
                const auto seed = seed_json.get<std::uint64_t>();
                DecoupleOrder decouple_order{};
                try {
                    decouple_order = decouple_order_from_string(order);
                } catch (const InputError&) {
                    throw_input_error(options.record_path, "/decouple/order",
                                      "expected one of authors, random, depth, got '" + order + "'");
                }
                const DecoupleReport report = decouple_rows(view, qp.contacts, decouple_order, seed);
                // The kept rows over the snapshot's own A, b and x0 (a view: A is not copied).
                SpMat J_kept;
                Vec c_kept;
                select_constraint_rows(qp, report.kept_rows, J_kept, c_kept);
                Vec lambda_kept(static_cast<Eigen::Index>(report.kept_rows.size()));
                for (size_t k = 0; k < report.kept_rows.size(); ++k)
                    lambda_kept[static_cast<Eigen::Index>(k)] = out.lambda[report.kept_rows[k]];
                const QpView reduced_view{qp.A, qp.b, J_kept, c_kept, qp.x0, &qp.length, nullptr, qp.a_symmetric};
                Vec used;
                bool fitted = false;
                out.accuracy_solved = measure_point(reduced_view, accuracy_scale(reduced_view), x, g, &lambda_kept,
                                                    out.tol, used, fitted);
                out.have_solved = true;
            } else if (solved == "frictionless") {
                // A frictionless solver on a frictional problem: the problem without its friction.
                QpView relaxed = view;
                relaxed.friction = nullptr;
                Vec used;
                bool fitted = false;
                out.accuracy_solved =
                    measure_point(relaxed, accuracy_scale(relaxed), x, g, &out.lambda, out.tol, used, fitted);
                out.have_solved = true;
            } else if (solved.empty() && out.relaxation) {
                // A frictional run judged without lambda_t: the point answers the relaxation at best.
                out.accuracy_solved = out.accuracy;
                out.have_solved = true;
            } else if (!solved.empty()) {
                throw_input_error(options.record_path, "/solved_problem",
                                  "expected unconstrained, decoupled or frictionless, got '" + solved + "'");
            }
            out.status = out.have_solved && within(out.accuracy_solved.max(), out.tol) ? STATUS_SOLVED_RELAXATION
                                                                                       : STATUS_UNCONFIRMED;
        }
    }

    out.energy_gap = std::numeric_limits<double>::quiet_NaN();
    if (options.look_up_reference && !options.snapshot_hash.empty()) {
        out.reference = cached_reference(options.snapshot_hash);
        if (out.reference.is_object() && out.reference["objective"].is_number())
            out.energy_gap = energy_gap(out.scale, out.objective, out.reference["objective"].get<double>());
    }
    return out;
}

}  // namespace cb
