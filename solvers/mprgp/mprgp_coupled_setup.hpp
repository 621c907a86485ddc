#pragma once
/// `mprgp-coupled`'s setup pieces: the research counters of a run (one ResearchStats that fills
/// `info`), the preconditioner choice (precond = auto) and the scaled variables (precond = scaled).
#include "solvers/core/qp.hpp"
#include "solvers/linalg/row_components.hpp"
#include "solvers/linalg/row_search.hpp"
#include "solvers/mprgp/mprgp_coupled.hpp"
#include "solvers/mprgp/mprgp_parts.hpp"

#include <memory>
#include <optional>
#include <string>

namespace cb {

/// Why chains end (issue 31's question: why the coupled chain keeps expanding), counted.
struct ChainCounts {
    long rejected_infeasible_trials = 0;   ///< CG trial with a projected P(y) and F(P(y)) >= F(P(x)): expansion
    long rejected_feasible_trials = 0;     ///< CG trial at a feasible y with F(y) > F(P(x)) (rounding): expansion
    long infeasible_not_proportional = 0;  ///< not proportional at an infeasible chain iterate: expansion
    long face_done_expansions = 0;         ///< infeasible iterate whose face problem is solved: expansion
    long expansions_same_face = 0;         ///< expansions after which the face was the one before
    long drift_only_trials = 0;            ///< trials whose only violated rows were face rows within tau_i
    long accepted_infeasible_trials = 0;   ///< CG trials accepted although P moved y (the chain goes on)
    long violated_rows_accepted = 0;       ///< rows P moved, summed over the accepted infeasible trials
    long violated_rows_rejected = 0;       ///< rows P moved, summed over the rejected infeasible trials
    double rejected_gain = 0.0;            ///< sum of -(F(y) - F(x)) over the rejected infeasible trials
    double rejected_cost = 0.0;            ///< sum of the projection corrections F(P(y)) - F(y) over them
    nlohmann::json to_json() const
    {
        return {{"rejected_infeasible_trials", rejected_infeasible_trials},
                {"rejected_feasible_trials", rejected_feasible_trials},
                {"infeasible_not_proportional", infeasible_not_proportional},
                {"face_done_expansions", face_done_expansions},
                {"expansions_same_face", expansions_same_face},
                {"drift_only_trials", drift_only_trials},
                {"accepted_infeasible_trials", accepted_infeasible_trials},
                {"violated_rows_accepted", violated_rows_accepted},
                {"violated_rows_rejected", violated_rows_rejected},
                {"rejected_cost_over_gain", rejected_gain > 0.0 ? rejected_cost / rejected_gain : 0.0}};
    }
};

/// LCP pivots (Counters::lcp_iterations) by the operator that asked for them.
struct LcpPivotsByUse {
    long chopped = 0;           ///< the chopped gradient's LCP on the face (evaluate)
    long reduced_gradient = 0;  ///< P(x - alpha_bar phi) of the proportioning test
    long trial = 0;             ///< P(y) of a CG trial
    long iterate = 0;           ///< P(x) of an expansion, proportioning or safeguard step, and the returned point
    nlohmann::json to_json() const
    {
        return {{"chopped", chopped}, {"reduced_gradient", reduced_gradient}, {"trial", trial}, {"iterate", iterate}};
    }
};

/// The chopped gradient's LCP: solved, or deferred because bounds decided without it.
struct ChoppedCounts {
    long solved = 0;                     ///< chopped LCPs solved for the solver
    long deferred = 0;                   ///< evaluations that stopped at the bounds
    long proportional_by_bound = 0;      ///< proportionality decided by beta'beta's upper bound
    long proportional_without_beta = 0;  ///< no negative face multiplier at a feasible x
    long proportional_by_sweeps = 0;     ///< decided by the projected sweeps' bound
    long bound_sweeps = 0;               ///< those sweeps, counted
    nlohmann::json to_json() const
    {
        return {{"solved", solved},
                {"deferred", deferred},
                {"proportional_by_bound", proportional_by_bound},
                {"proportional_without_beta", proportional_without_beta},
                {"proportional_by_sweeps", proportional_by_sweeps},
                {"bound_sweeps", bound_sweeps}};
    }
};

/// The research counters of one run, in one place; they fill `info` and change no decision.
struct ResearchStats {
    ChainCounts chain;
    LcpPivotsByUse lcp_by_use;
    ChoppedCounts chopped;
    void fill(nlohmann::json& info) const
    {
        info["chain"] = chain.to_json();
        info["lcp_pivots_by_use"] = lcp_by_use.to_json();
        info["chopped_lcp"] = chopped.to_json();
    }
};

/// The preconditioner a run uses: `precond` itself, or for auto scaled or jacobi by the size of
/// the largest component of J's row graph (the settings' help and docs/preconditioners.md give why).
struct PrecondChoice {
    std::string name;  ///< the preconditioner used
    std::string rule;  ///< how auto chose (empty unless precond = auto)
    /// J's row components when auto found them; the face operators take them (a column scaling of
    /// J, as precond = scaled makes, has the same components), so they are found once per solve.
    std::optional<RowComponents> components;

    static PrecondChoice make(const QpView& qp, const MprgpCoupledSettings& st)
    {
        PrecondChoice c;
        if (st.precond != "auto") {
            c.name = st.precond;
        } else if (st.deflation != "none") {
            c.name = "jacobi";
            c.rule = "auto: jacobi (deflation = " + st.deflation + ")";
        } else {
            c.components = find_row_components(qp.J);
            const int largest = qp.m() > 0 ? c.components->largest() : 0;
            c.name = largest > st.dense_max_rows ? "scaled" : "jacobi";
            c.rule = "auto: " + c.name + " (largest component " + std::to_string(largest) + " rows, dense_max_rows " +
                     std::to_string(st.dense_max_rows) + ")";
        }
        return c;
    }
};

/// precond = scaled: the QP in the variables y = D^1/2 x (D = diag(A)): A -> U A U, J -> J U,
/// b -> U b, x0 -> x0 / U with U = D^-1/2; c and the multipliers are the same. U A U is not
/// formed: the run's AOperator applies U on both sides of each product (AOperator::scale_by) and
/// its sparse partial products scale the few entries they read, so A is not copied.
struct ScaledVariables {
    Vec unscale;  ///< U: x = U y
    SpMat J;
    Vec b, y0;
    /// null unless precond = scaled applies (deflation = none, a positive diagonal of A)
    static std::unique_ptr<ScaledVariables> make(const QpView& qp, const std::string& precond,
                                                 const MprgpCoupledSettings& st)
    {
        if (precond != "scaled" || st.deflation != "none") return nullptr;
        auto s = std::make_unique<ScaledVariables>();
        s->unscale = sorted_rows_diagonal(qp.A);  // D, once: a search per row of A (rows ahead prefetched)
        if (!(s->unscale.array() > 0.0).all()) return nullptr;  // jacobi_inverse_diagonal's refusal (NaN too)
        s->unscale = s->unscale.cwiseSqrt().cwiseInverse();     // D^-1/2 in place
        const Vec& u = s->unscale;
        s->J = qp.J;
        for (Eigen::Index i = 0; i < s->J.outerSize(); ++i)
            for (SpMat::InnerIterator it(s->J, i); it; ++it) it.valueRef() *= u[it.col()];
        s->b = u.cwiseProduct(qp.b);
        s->y0 = qp.x0.cwiseQuotient(u);
        return s;
    }
};

}  // namespace cb
