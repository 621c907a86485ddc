#pragma once
/// The LCPs of a sparse (CHOLMOD) block of the coupled face operators (solvers/mprgp/
/// coupled_sparse_blocks.cpp; the dense blocks share the pivoting's set update): 0 <= lambda perp M lambda - q >= 0
/// with M a Gram matrix J_B J_B', by block principal pivoting (Judice and Pires 1994) with Murty's single pivot, and
/// projected Gauss-Seidel as its fallback and as the large components' sweep start.
#include "solvers/core/solver.hpp"
#include "solvers/core/types.hpp"

#include <Eigen/CholmodSupport>
#include <memory>
#include <vector>

namespace cb {

using Cholmod = Eigen::CholmodDecomposition<SpMatCol, Eigen::Lower>;

/// The principal submatrix M(idx, idx).
SpMatCol submatrix(const SpMatCol& M, const std::vector<int>& idx);

/// A CHOLMOD factor of a Gram matrix scaled to unit diagonal and shifted by GRAM_SHIFT (the global
/// oracle's operators, as before issue 31: analysis and factorisation on every face and LCP set).
struct SparseFactor {
    std::unique_ptr<Cholmod> chol;
    Vec scale;  ///< 1 / sqrt(diag)
    bool ok = false;
    bool compute(const SpMatCol& S, Counters& cnt);
    Vec solve(const Vec& rhs, Counters& cnt);
};

/// Projected Gauss-Seidel on 0 <= lambda perp M lambda - q >= 0 from lambda (clipped), the
/// fallback of the principal pivoting; `set` becomes the rows with lambda > 0 (and the fixed ones).
bool projected_gauss_seidel(const SpMatCol& M, const Vec& q, const char* fixed, std::vector<char>& set, Vec& lambda,
                            Counters& cnt, long max_sweeps);

/// The principal pivoting's set update (Judice and Pires 1994), of the sparse and the dense blocks:
/// flip every infeasible row while their count drops (three more chances otherwise), then Murty's
/// single flip of the last one.
void flip_infeasible(const std::vector<int>& bad, std::vector<char>& set, long& best, int& chances);

/// Solves 0 <= lambda  perp  M lambda - q >= 0 by block principal pivoting, warm-started from
/// `set` (in/out); falls back to projected Gauss-Seidel. @return false when neither met the tolerance.
bool sparse_lcp(const SpMatCol& M, const Vec& q, const char* fixed, std::vector<char>& set, Vec& lambda, Counters& cnt,
                long max_pivots, long max_sweeps, long& pgs_fallbacks);

}  // namespace cb
