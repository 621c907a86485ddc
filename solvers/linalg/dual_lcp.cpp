// W = J A^-1 J' and q = J A^-1 b - c (see dual_lcp.hpp).
#include "solvers/linalg/dual_lcp.hpp"

namespace cb {

bool DualLcp::form(const QpView& qp, Counters& counters, std::string& error)
{
    if (!m_delassus.factor(SpMatCol(qp.A), counters)) {
        error = "CHOLMOD could not factor A (not positive definite to working precision)";
        return false;
    }
    m_x_free = m_delassus.solve(qp.b, counters);
    m_q = qp.J * m_x_free - qp.c;
    m_delassus.form_dense(qp.J, m_W, counters);
    return true;
}

Vec DualLcp::primal(const QpView& qp, const Vec& lambda, Counters& counters) const
{
    return m_delassus.solve(Vec(qp.b + qp.J.transpose() * lambda), counters);
}

}  // namespace cb
