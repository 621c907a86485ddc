// The local problem of a global frictional problem, by a sparse Cholesky of M (see
// friction_global_reduction.hpp).
#include "solvers/friction/friction_global_reduction.hpp"

namespace cb {

GlobalReduction::GlobalReduction(const FrictionGlobal& problem) : m_problem(problem)
{
    Counters counters;  // the reduction is the caller's setup; its work is not reported
    if (!m_delassus.factor(SpMatCol(problem.M), counters))
        throw InputError(problem.name +
                         ": /fclib_global/M: not positive definite (its sparse Cholesky factorisation failed): the "
                         "global problem cannot be reduced to W = H' M^-1 H");
    // FCLIB's H is n x 3m (our rows transposed); M^-1 H with a sparse right-hand side stays sparse when M is block
    // diagonal (rigid bodies), as in most real files.
    m_local.W = m_delassus.form_sparse(SpMat(problem.H.transpose()), counters);
    m_local.q = problem.w + problem.H.transpose() * m_delassus.solve(problem.f, counters);
    m_local.mu = problem.mu;
    m_local.name = problem.name;
}

Vec GlobalReduction::velocity(const Vec& r) const
{
    Counters counters;
    return m_delassus.solve(Vec(m_problem.H * r + m_problem.f), counters);
}

}  // namespace cb
