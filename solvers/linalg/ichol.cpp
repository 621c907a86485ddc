// Incomplete Cholesky preconditioner and its face form (docs/preconditioners.md).
#include "solvers/linalg/ichol.hpp"
#include "solvers/measure/work_units.hpp"

#include <cmath>

namespace cb {

bool IncompleteCholeskyPreconditioner::factor(const SpMat& B, std::string& error, double* work_flops)
{
    m_ready = false;
    const SpMatCol lower = SpMatCol(B).triangularView<Eigen::Lower>();
    m_ic.compute(lower);
    if (m_ic.info() != Eigen::Success) {
        error = "incomplete Cholesky failed (the matrix is not positive definite even after 10 diagonal shifts)";
        return false;
    }
    m_factor_nonzeros = static_cast<long>(m_ic.matrixL().nonZeros());
    m_factor_flops = 0.0;
    for (Eigen::Index j = 0; j < m_ic.matrixL().outerSize(); ++j) {
        const double column = static_cast<double>(m_ic.matrixL().col(j).nonZeros());
        m_factor_flops += column * column;
    }
    if (work_flops) *work_flops += m_factor_flops;
    m_ready = true;
    return true;
}

void IncompleteCholeskyPreconditioner::apply(const Vec& r, Vec& z) const { z = m_ic.solve(r); }

SpMat face_matrix(const SpMat& A, const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active,
                  double* work_flops)
{
    if (work_flops) *work_flops += sparse_product_flops(static_cast<double>(A.nonZeros()), 2.0);
    // Q as a sparse matrix: identity plus -n n' blocks on the active rows' DOFs.
    std::vector<Triplet> q;
    std::vector<char> touched(static_cast<size_t>(A.rows()), 0);
    std::vector<Triplet> normal_part;
    const int* outer = J.outerIndexPtr();
    const int* inner = J.innerIndexPtr();
    const double* val = J.valuePtr();
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
        if (!active[static_cast<size_t>(i)] || rows.s[i] <= 0.0) continue;
        // d_i = n'An with n = J_i'/||J_i||: keeps the normal block at A's scale.
        double nan = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k)
            for (int l = outer[i]; l < outer[i + 1]; ++l) nan += val[k] * A.coeff(inner[k], inner[l]) * val[l];
        const double d = nan * rows.inv_s[i] > 0.0 ? nan * rows.inv_s[i] : 1.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            touched[static_cast<size_t>(inner[k])] = 1;
            for (int l = outer[i]; l < outer[i + 1]; ++l) {
                const double nn = val[k] * val[l] * rows.inv_s[i];
                q.emplace_back(inner[k], inner[l], -nn);
                normal_part.emplace_back(inner[k], inner[l], d * nn);
            }
        }
    }
    for (Eigen::Index j = 0; j < A.rows(); ++j) q.emplace_back(static_cast<int>(j), static_cast<int>(j), 1.0);
    SpMat Q(A.rows(), A.cols());
    Q.setFromTriplets(q.begin(), q.end());
    SpMat N(A.rows(), A.cols());
    N.setFromTriplets(normal_part.begin(), normal_part.end());
    const SpMat AQ = A * Q;
    SpMat B = Q * AQ;
    B += N;
    return B;
}

void ichol_face_precondition(const IncompleteCholeskyPreconditioner& ic, const SpMat& J, const DecoupledRows& rows,
                             const std::vector<char>& active, const Vec& g, Vec& work, Vec& z, double* work_flops)
{
    if (work_flops) *work_flops += ic.apply_flops();
    free_gradient(J, rows, active, g, work);  // Q g (orthogonal projection, rows share no DOF)
    ic.apply(work, z);
    // Q again: J_A z = 0 to rounding whatever the incomplete factor's error.
    for (Eigen::Index i = 0; i < J.rows(); ++i)
        if (active[static_cast<size_t>(i)]) row_axpy(J, i, -row_dot(J, i, z) * rows.inv_s[i], z);
}

}  // namespace cb
