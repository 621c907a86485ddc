// The local problem of a global frictional problem, by a sparse Cholesky of M (see
// friction_global_reduction.hpp).
#include "solvers/friction_global_reduction.hpp"

namespace cb {

GlobalReduction::GlobalReduction(const FrictionGlobal& problem) : m_problem(problem)
{
    const SpMatCol M = problem.M;
    m_cholesky.compute(M);
    if (m_cholesky.info() != Eigen::Success)
        throw InputError(problem.name +
                         ": /fclib_global/M: not positive definite (its sparse Cholesky factorisation failed): the "
                         "global problem cannot be reduced to W = H' M^-1 H");
    const SpMatCol H = problem.H;
    // M^-1 H column by column (Eigen solves a sparse right-hand side in dense panels); sparse when
    // M is block diagonal (rigid bodies), as in most real files.
    const SpMatCol MinvH = m_cholesky.solve(H);
    const SpMatCol W = SpMatCol(H.transpose()) * MinvH;
    m_local.W = W;
    m_local.W.makeCompressed();
    const Vec Minvf = m_cholesky.solve(problem.f);
    m_local.q = problem.w + problem.H.transpose() * Minvf;
    m_local.mu = problem.mu;
    m_local.name = problem.name;
}

Vec GlobalReduction::velocity(const Vec& r) const { return m_cholesky.solve(m_problem.H * r + m_problem.f); }

}  // namespace cb
