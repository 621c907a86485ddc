#include "harness/run_problem.hpp"

#include "solvers/mprgp/decouple.hpp"

namespace cb {

void choose_solver_problem(const Qp& original, bool requires_decoupled, const RunOptions& options,
                           SolverProblem& problem)
{
    problem.original = &original;
    problem.kept_rows.clear();
    problem.applied = false;
    problem.decouple = {{"order", options.decouple},
                        {"seed", options.decouple_seed},
                        {"rows_before", original.m()},
                        {"rows_after", original.m()},
                        {"applied", false}};
    bool want = false;
    DecoupleOrder order = DecoupleOrder::AUTHORS;
    if (options.decouple == "auto") {
        want = requires_decoupled && original.m() > 0 && !is_decoupled(original.J);
    } else if (options.decouple != "none") {
        order = decouple_order_from_string(options.decouple);
        want = original.m() > 0;
    }
    if (!want) return;
    const DecoupleReport report = decouple_rows(original.view(), original.contacts, order, options.decouple_seed);
    problem.decouple["order"] = to_string(order);
    problem.decouple["rows_after"] = report.rows_after;
    problem.decouple["already_decoupled"] = report.already_decoupled;
    if (!report.already_decoupled && static_cast<long>(report.kept_rows.size()) < original.m()) {
        problem.kept_rows = report.kept_rows;
        select_constraint_rows(original, report.kept_rows, problem.decoupled_J, problem.decoupled_c);
        problem.applied = true;
        problem.decouple["applied"] = true;
        problem.decouple["rows_after"] = problem.decoupled_J.rows();
    }
}

const Vec* warm_multipliers(const Vec* lambda0, const Qp& original, const SolverProblem& problem, Vec& storage)
{
    if (!lambda0) return nullptr;
    if (!problem.is_original() && lambda0->size() == original.m()) {
        storage.resize(static_cast<Eigen::Index>(problem.kept_rows.size()));
        for (size_t k = 0; k < problem.kept_rows.size(); ++k)
            storage[static_cast<Eigen::Index>(k)] = (*lambda0)[problem.kept_rows[k]];
        return &storage;
    }
    if (lambda0->size() == problem.view().m()) return lambda0;
    return nullptr;
}

}  // namespace cb
