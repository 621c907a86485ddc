#pragma once
/// The problem a solver is given in a run (harness/runner.hpp): the QP in the file, or its
/// decoupled rows when the run asks for it or the solver requires it, and the warm-start
/// multipliers restricted to the rows it sees.
#include "harness/runner.hpp"
#include "solvers/core/qp.hpp"

#include <nlohmann/json.hpp>
#include <vector>

namespace cb {

/// The QP a solver sees: the original, or its kept rows of J and c with the original's A, b and
/// x0 viewed, not copied (a copy of A was the largest array of a decoupled run's setup).
/// Filled in place and never copied (view() refers to its members).
struct SolverProblem {
    const Qp* original = nullptr;
    SpMat decoupled_J;           ///< the kept rows of J, when decoupling applied
    Vec decoupled_c;             ///< and their c
    std::vector<int> kept_rows;  ///< rows of the original J the solver sees (empty: all of them)
    bool applied = false;        ///< decoupling removed rows: view() has decoupled_J and decoupled_c
    nlohmann::json decouple;     ///< the record's "decouple" object
    bool is_original() const { return !applied; }
    QpView view() const
    {
        if (!applied) return original->view();
        // Friction's rows are the original's: a decoupled solver is frictionless and gets none.
        return QpView{original->A,  original->b,       decoupled_J, decoupled_c,
                      original->x0, &original->length, nullptr,     original->a_symmetric};
    }
};

/// Decoupling as RunOptions::decouple asks: "auto" when the solver requires a decoupled J that the
/// QP does not have, "none" never, an order name always (when there are rows).
void choose_solver_problem(const Qp& original, bool requires_decoupled, const RunOptions& options,
                           SolverProblem& problem);

/// Warm-start multipliers that fit the rows the solver sees (matched by row index), or nullptr:
/// `lambda0` of the original m (restricted to the kept rows) or of the solved QP's m. `storage`
/// holds the restricted copy.
const Vec* warm_multipliers(const Vec* lambda0, const Qp& original, const SolverProblem& problem, Vec& storage);

}  // namespace cb
