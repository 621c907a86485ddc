#pragma once
/// The QP's dual LCP formed on the harness's side, for the solvers that pivot on a dense matrix
/// (the peers `siconos-lemke` and `bullet-dantzig`; `pgs` and `ica` form the same W their own way):
///   w = W lambda + q >= 0,  lambda >= 0,  lambda'w = 0,   W = J A^-1 J',  q = J A^-1 b - c,
/// and the primal point x = A^-1 (b + J'lambda). W is formed by Delassus (solvers/linalg/delassus.hpp:
/// CHOLMOD, dense, symmetrised). All of it is the solvers' setup, and its work is counted
/// (cholmod_analyses, cholmod_factorizations, cholmod_solves, work_flops).
#include "solvers/core/solver.hpp"
#include "solvers/linalg/delassus.hpp"

#include <string>

namespace cb {

class DualLcp {
public:
    /// Factors A and forms W and q. Returns false, with `error` saying why, when CHOLMOD cannot
    /// factor A (not positive definite to working precision).
    bool form(const QpView& qp, Counters& counters, std::string& error);

    Eigen::MatrixXd& matrix() { return m_W; }  ///< W, m x m, column-major (= row-major: symmetric)
    Vec& q() { return m_q; }
    const Vec& unconstrained() const { return m_x_free; }  ///< A^-1 b, the answer when m = 0

    /// x = A^-1 (b + J'lambda), one more CHOLMOD solve.
    Vec primal(const QpView& qp, const Vec& lambda, Counters& counters) const;

private:
    Delassus m_delassus;
    Eigen::MatrixXd m_W;
    Vec m_q;
    Vec m_x_free;
};

}  // namespace cb
