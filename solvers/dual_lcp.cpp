// W = J A^-1 J' and q = J A^-1 b - c with CHOLMOD (see dual_lcp.hpp).
#include "solvers/dual_lcp.hpp"
#include "solvers/work_units.hpp"

#include <algorithm>

namespace cb {

bool DualLcp::form(const QpView& qp, Counters& counters, std::string& error)
{
    const Eigen::Index m = qp.m();
    {
        const SpMatCol A_col = qp.A;
        m_llt.compute(A_col);
    }
    ++counters.cholmod_analyses;
    ++counters.cholmod_factorizations;
    counters.work_flops += cholmod_factor_flops(m_llt.cholmod());
    if (m_llt.info() != Eigen::Success) {
        error = "CHOLMOD could not factor A (not positive definite to working precision)";
        return false;
    }
    m_solve_flops = cholmod_solve_flops(m_llt.cholmod());
    m_x_free = m_llt.solve(qp.b);
    ++counters.cholmod_solves;
    counters.work_flops += m_solve_flops;
    m_q = qp.J * m_x_free - qp.c;
    m_W.resize(m, m);
    const SpMatCol Jt = SpMatCol(qp.J.transpose());
    constexpr Eigen::Index BLOCK = 64;  // right-hand sides per CHOLMOD solve
    for (Eigen::Index j0 = 0; j0 < m; j0 += BLOCK) {
        const Eigen::Index k = std::min(BLOCK, m - j0);
        m_W.middleCols(j0, k) = qp.J * Eigen::MatrixXd(m_llt.solve(Eigen::MatrixXd(Jt.middleCols(j0, k))));
        counters.cholmod_solves += k;
        counters.work_flops += cholmod_solve_flops(m_llt.cholmod(), k) +
                               sparse_product_flops(static_cast<double>(qp.J.nonZeros()), static_cast<double>(k));
    }
    m_W = 0.5 * (m_W + m_W.transpose()).eval();
    return true;
}

Vec DualLcp::primal(const QpView& qp, const Vec& lambda, Counters& counters) const
{
    ++counters.cholmod_solves;
    counters.work_flops += m_solve_flops;
    return m_llt.solve(Vec(qp.b + qp.J.transpose() * lambda));
}

}  // namespace cb
