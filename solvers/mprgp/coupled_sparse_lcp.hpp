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

/// sum over k in [begin, end) of value[k] y[inner[k]] (a column of a compressed matrix times y), in
/// four partial sums (entry k into sum (k - begin) mod 4, added as (s0 + s1) + (s2 + s3)): one sum
/// waits on every addition, and the large components' sweep starts are made of these columns.
inline double sparse_column_dot(int begin, int end, const int* inner, const double* value, const double* y)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int k = begin;
    for (; k + 4 <= end; k += 4) {
        s0 += value[k] * y[inner[k]];
        s1 += value[k + 1] * y[inner[k + 1]];
        s2 += value[k + 2] * y[inner[k + 2]];
        s3 += value[k + 3] * y[inner[k + 3]];
    }
    if (k < end) s0 += value[k] * y[inner[k]];
    if (k + 1 < end) s1 += value[k + 1] * y[inner[k + 1]];
    if (k + 2 < end) s2 += value[k + 2] * y[inner[k + 2]];
    return (s0 + s1) + (s2 + s3);
}

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
