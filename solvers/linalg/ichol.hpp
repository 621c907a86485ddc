#pragma once
/// Incomplete Cholesky preconditioner (`precond = ichol` of cg and mprgp), and its face form for
/// MPRGP's decoupled rows (docs/preconditioners.md).
/// Ref: Lin & More, "Incomplete Cholesky factorizations with limited memory", SIAM J. Sci.
///      Comput. 21(1), 1999 (Eigen's IncompleteCholesky: AMD ordering, diagonal scaling, shift).
#include "solvers/core/types.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <string>
#include <vector>

namespace cb {

/// M = L L' ~ B for an SPD B, with as many nonzeros per column of L as B has (no extra fill).
class IncompleteCholeskyPreconditioner {
public:
    /// Factors B (full symmetric, both triangles). Returns false and sets `error` on failure.
    /// Adds factor_flops() to *work_flops when given (docs/work.md).
    bool factor(const SpMat& B, std::string& error, double* work_flops = nullptr);
    /// z = M^-1 r.
    void apply(const Vec& r, Vec& z) const;
    long factor_nonzeros() const { return m_factor_nonzeros; }
    /// Flops of the last factor(): sum over the columns of L of nnz(column)^2 (docs/work.md).
    double factor_flops() const { return m_factor_flops; }
    /// Flops of one apply(): forward and back substitution, 4 nnz(L).
    double apply_flops() const { return 4.0 * static_cast<double>(m_factor_nonzeros); }
    bool ready() const { return m_ready; }

private:
    Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>> m_ic;
    long m_factor_nonzeros = 0;
    double m_factor_flops = 0.0;
    bool m_ready = false;
};

/// The face matrix of decoupled rows: B = Q A Q + sum_{i active} d_i n_i n_i', with
/// Q = I - sum_{i active} n_i n_i' (n_i = J_i' / ||J_i||, rows share no DOF) and
/// d_i = n_i' A n_i. B is SPD, block diagonal on range(Q) + null(Q), and equals Q A Q on the
/// face: B^-1 phi = (Q A Q)^+ phi for phi in range(Q).
/// Forming it costs about two products with A (A Q, then Q (A Q)), added to *work_flops when given.
SpMat face_matrix(const SpMat& A, const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active,
                  double* work_flops = nullptr);

/// The face preconditioner z = Q M^-1 Q g (M ~ face_matrix): symmetric, positive definite on
/// the face, and J_A z = 0 exactly. `work` is scratch of size n; the application's flops are added
/// to *work_flops when given.
void ichol_face_precondition(const IncompleteCholeskyPreconditioner& ic, const SpMat& J, const DecoupledRows& rows,
                             const std::vector<char>& active, const Vec& g, Vec& work, Vec& z,
                             double* work_flops = nullptr);

}  // namespace cb
