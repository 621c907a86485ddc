// The local frictional problem of a frictional snapshot (see friction_dual.hpp).
#include "solvers/friction/friction_dual.hpp"

#include "solvers/measure/friction_snapshot_error.hpp"

namespace cb {

FrictionDual::FrictionDual(const QpView& qp, const std::string& name) : m_qp(qp)
{
    if (!qp.friction || qp.friction->mu.size() != qp.m())
        throw InputError(name + ": mu: missing: a frictional snapshot has a friction coefficient per contact row");
    // H's rows interleaved per contact, so that W's 3x3 blocks are the contacts'.
    m_H = contact_frame_rows(qp, &m_cH);
    const QpView rows{qp.A, qp.b, m_H, m_cH, qp.x0, nullptr, nullptr};
    std::string error;
    if (!m_dual.form(rows, m_counters, error)) throw InputError(name + ": A: " + error);
    m_local.W = m_dual.matrix().sparseView();
    m_local.q = m_dual.q();
    m_local.mu = qp.friction->mu;
    m_local.name = name;
}

Vec FrictionDual::primal(const Vec& r)
{
    const QpView rows{m_qp.A, m_qp.b, m_H, m_cH, m_qp.x0, nullptr, nullptr};
    return m_dual.primal(rows, r, m_counters);
}

}  // namespace cb
