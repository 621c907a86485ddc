// Rows as bounds (see bounds.hpp).
#include "solvers/mprgp/bounds.hpp"

#include "solvers/measure/accuracy.hpp"

#include <limits>
#include <sstream>

namespace cb {

RowBounds bounds_from_rows(const QpView& qp)
{
    const Eigen::Index n = qp.n(), m = qp.m();
    const double inf = std::numeric_limits<double>::infinity();
    RowBounds b;
    b.lower = Vec::Constant(n, -inf);
    b.upper = Vec::Constant(n, inf);
    b.coef = Vec::Zero(m);
    b.lower_row.assign(static_cast<size_t>(n), -1);
    b.upper_row.assign(static_cast<size_t>(n), -1);
    for (Eigen::Index i = 0; i < m; ++i) {
        int nonzeros = 0;
        Eigen::Index j = -1;
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) {
            if (it.value() == 0.0) continue;
            ++nonzeros;
            j = it.col();
            b.coef[i] = it.value();
        }
        if (nonzeros > 1) {
            b.status = SolveStatus::NOT_APPLICABLE;
            b.why = "row " + std::to_string(i) + " of J has " + std::to_string(nonzeros) +
                    " nonzeros (bound rows only: one nonzero per row, a x_j >= c)";
            return b;
        }
        if (nonzeros == 0) {
            if (qp.c[i] > active_tolerance(qp.c[i])) {
                b.status = SolveStatus::INFEASIBLE;
                b.why = "row " + std::to_string(i) + " is zero but c > 0: empty feasible set";
                return b;
            }
            continue;
        }
        const double bound = qp.c[i] / b.coef[i] + 0.0;  // + 0.0: no "-0" in messages
        const size_t js = static_cast<size_t>(j);
        if (b.coef[i] > 0.0 && bound > b.lower[j]) {
            b.lower[j] = bound;
            b.lower_row[js] = i;
        } else if (b.coef[i] < 0.0 && bound < b.upper[j]) {
            b.upper[j] = bound;
            b.upper_row[js] = i;
        }
    }
    for (Eigen::Index j = 0; j < n; ++j)
        if (b.lower[j] > b.upper[j]) {
            std::ostringstream msg;
            msg << "DOF " << j << " has lower bound " << b.lower[j] << " > upper bound " << b.upper[j];
            b.status = SolveStatus::INFEASIBLE;
            b.why = msg.str();
            return b;
        }
    return b;
}

Vec bound_multipliers(const QpView& qp, const RowBounds& b, const Vec& g)
{
    Vec lambda = Vec::Zero(qp.m());
    for (Eigen::Index j = 0; j < qp.n(); ++j) {
        const size_t js = static_cast<size_t>(j);
        const Eigen::Index row = g[j] > 0.0 ? b.lower_row[js] : (g[j] < 0.0 ? b.upper_row[js] : -1);
        if (row >= 0) lambda[row] = g[j] / b.coef[row];
    }
    return lambda;
}

}  // namespace cb
