// The local frictional problem of a frictional snapshot (see friction_dual.hpp).
#include "solvers/friction_dual.hpp"

#include <vector>

namespace cb {

FrictionDual::FrictionDual(const QpView& qp, const std::string& name) : m_qp(qp)
{
    if (!qp.friction || qp.friction->mu.size() != qp.m())
        throw InputError(name + ": mu: missing: a frictional snapshot has a friction coefficient per contact row");
    const Friction& f = *qp.friction;
    const Eigen::Index m = qp.m(), n = qp.n();
    // H's rows interleaved per contact, so that W's 3x3 blocks are the contacts'.
    std::vector<Eigen::Triplet<double>> entries;
    for (Eigen::Index i = 0; i < m; ++i) {
        for (SpMat::InnerIterator it(qp.J, i); it; ++it)
            entries.emplace_back(static_cast<int>(3 * i), static_cast<int>(it.col()), it.value());
        for (int k = 0; k < 2; ++k)
            for (SpMat::InnerIterator it(f.T, 2 * i + k); it; ++it)
                entries.emplace_back(static_cast<int>(3 * i + 1 + k), static_cast<int>(it.col()), it.value());
    }
    m_H.resize(3 * m, n);
    m_H.setFromTriplets(entries.begin(), entries.end());
    m_cH = Vec::Zero(3 * m);
    for (Eigen::Index i = 0; i < m; ++i) {
        m_cH[3 * i] = qp.c[i];
        if (f.cT.size() == 2 * m) {
            m_cH[3 * i + 1] = f.cT[2 * i];
            m_cH[3 * i + 2] = f.cT[2 * i + 1];
        }
    }
    const QpView rows{qp.A, qp.b, m_H, m_cH, qp.x0, nullptr, nullptr};
    std::string error;
    if (!m_dual.form(rows, m_counters, error)) throw InputError(name + ": A: " + error);
    m_local.W = m_dual.matrix().sparseView();
    m_local.q = m_dual.q();
    m_local.mu = f.mu;
    m_local.name = name;
}

Vec FrictionDual::primal(const Vec& r)
{
    const QpView rows{m_qp.A, m_qp.b, m_H, m_cH, m_qp.x0, nullptr, nullptr};
    return m_dual.primal(rows, r, m_counters);
}

}  // namespace cb
