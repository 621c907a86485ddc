#pragma once
/// The Delassus matrix W = H A^-1 H' of a set of rows H (n columns) and a symmetric positive
/// definite A (n x n): the one place that factors A by CHOLMOD and forms W from it, for the dual
/// solvers (pgs, nsgs-friction, DualLcp and its peers, FrictionDual), the frictional time step
/// (sim/friction_step) and the reduction of a global frictional problem (W = H' M^-1 H there: its
/// H is our H'). H has one row per contact (the normal rows J) or three (normal and two tangents,
/// interleaved: W's 3x3 blocks are the contacts'); the forming does not depend on which.
/// Every factorisation, solve and product is counted (cholmod_analyses, cholmod_factorizations,
/// cholmod_solves, work_flops; docs/work.md).
#include "solvers/core/solver.hpp"  // Counters

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>

#include <functional>

namespace cb {

/// How a dense W is formed: column block by column block (a block of right-hand sides per CHOLMOD solve).
struct DelassusForming {
    Eigen::Index block = 64;             ///< right-hand sides per CHOLMOD solve
    Eigen::MatrixXd* columns = nullptr;  ///< when set: receives A^-1 H' (n x rows), to recover x = A^-1 b + Y r
    std::function<bool()> time_up = {};  ///< asked after each block; true stops the forming
};

class Delassus {
public:
    /// Factors A (CHOLMOD supernodal LL'). Returns false when A is not positive definite to working precision; the
    /// analysis and the factorisation are counted either way.
    bool factor(const SpMatCol& A, Counters& counters);

    /// A^-1 rhs, counted as one solve (needs factor()).
    Vec solve(const Vec& rhs, Counters& counters) const;

    /// Dense W = H A^-1 H', symmetrised (the solves leave O(eps) asymmetry). Returns false when forming.time_up
    /// stopped it (W then holds only the blocks formed).
    bool form_dense(const SpMat& rows, Eigen::MatrixXd& W, Counters& counters,
                    const DelassusForming& forming = {}) const;

    /// Sparse W = H A^-1 H' (A^-1 H' solved with a sparse right-hand side): block sparse when A is block diagonal
    /// (rigid bodies). Not symmetrised: kept as the product computes it.
    SpMatCol form_sparse(const SpMat& rows, Counters& counters) const;

    const cholmod_common& cholmod() const { return const_cast<Factor&>(m_llt).cholmod(); }

private:
    using Factor = Eigen::CholmodSupernodalLLT<SpMatCol, Eigen::Lower>;
    Factor m_llt;
    double m_solve_flops = 0.0;  ///< one solve with L and L' (docs/work.md)
};

}  // namespace cb
