// W = H A^-1 H' from a CHOLMOD factor of A (see delassus.hpp).
#include "solvers/linalg/delassus.hpp"

#include "solvers/measure/work_units.hpp"

#include <algorithm>

namespace cb {

bool Delassus::factor(const SpMatCol& A, Counters& counters)
{
    m_llt.compute(A);
    ++counters.cholmod_analyses;
    ++counters.cholmod_factorizations;
    counters.work_flops += cholmod_factor_flops(m_llt.cholmod());
    if (m_llt.info() != Eigen::Success) return false;
    m_solve_flops = cholmod_solve_flops(m_llt.cholmod());
    return true;
}

Vec Delassus::solve(const Vec& rhs, Counters& counters) const
{
    ++counters.cholmod_solves;
    counters.work_flops += m_solve_flops;
    return m_llt.solve(rhs);
}

bool Delassus::form_dense(const SpMat& rows, Eigen::MatrixXd& W, Counters& counters,
                          const DelassusForming& forming) const
{
    const Eigen::Index k = rows.rows();
    W.resize(k, k);
    if (forming.columns) forming.columns->resize(rows.cols(), k);
    const SpMatCol rows_t = SpMatCol(rows.transpose());
    const double nonzeros = static_cast<double>(rows.nonZeros());
    for (Eigen::Index j0 = 0; j0 < k; j0 += forming.block) {
        const Eigen::Index b = std::min<Eigen::Index>(forming.block, k - j0);
        const Eigen::MatrixXd Y = m_llt.solve(Eigen::MatrixXd(rows_t.middleCols(j0, b)));
        counters.cholmod_solves += b;  // one per right-hand side
        counters.work_flops +=
            cholmod_solve_flops(cholmod(), b) + sparse_product_flops(nonzeros, static_cast<double>(b));
        W.middleCols(j0, b) = rows * Y;
        if (forming.columns) forming.columns->middleCols(j0, b) = Y;
        if (forming.time_up && forming.time_up()) return false;
    }
    W = 0.5 * (W + W.transpose()).eval();
    return true;
}

SpMatCol Delassus::form_sparse(const SpMat& rows, Counters& counters) const
{
    const SpMatCol rows_t = SpMatCol(rows.transpose());
    const SpMatCol Y = m_llt.solve(rows_t);
    counters.cholmod_solves += rows.rows();
    counters.work_flops += cholmod_solve_flops(cholmod(), rows.rows()) +
                           sparse_product_flops(static_cast<double>(rows.nonZeros()), static_cast<double>(rows.rows()));
    SpMatCol W = SpMatCol(rows) * Y;
    W.makeCompressed();
    return W;
}

}  // namespace cb
