#pragma once
/// Rows as bounds: the one reading of a J whose every row has at most one nonzero (a x_j >= c is
/// x_j >= c/a for a > 0, x_j <= c/a for a < 0), its policy for what it cannot take, and the
/// multipliers of a point. Used by `template`, `mprgp-box` and `tao-tron`.
#include "solvers/core/qp.hpp"
#include "solvers/core/solver.hpp"

#include <string>
#include <vector>

namespace cb {

struct RowBounds {
    Vec lower, upper;                                ///< -inf / +inf where no row binds
    Vec coef;                                        ///< per row: its nonzero (0 for a zero row)
    std::vector<Eigen::Index> lower_row, upper_row;  ///< per DOF: the row that sets the bound, or -1
    /// NOT_RUN: usable. NOT_APPLICABLE: a row with two nonzeros (a problem class a bounds solver
    /// does not take). INFEASIBLE: a zero row with c > 0, or a lower bound above an upper one (the
    /// feasible set is empty: certified by the rows themselves).
    SolveStatus status = SolveStatus::NOT_RUN;
    std::string why;  ///< what the status rests on ("row 3 of J has 2 nonzeros ..."), without a solver name
};

/// Reads the rows of qp.J as bounds; stops at the first row or DOF that makes `status` not NOT_RUN.
RowBounds bounds_from_rows(const QpView& qp);

/// Multipliers at x (g = Ax - b): a DOF's gradient is its binding row's force, lambda = g_j / a,
/// on the lower bound's row when g_j > 0 and the upper bound's when g_j < 0; every other row 0.
Vec bound_multipliers(const QpView& qp, const RowBounds& bounds, const Vec& g);

}  // namespace cb
