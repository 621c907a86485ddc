#pragma once
/// diag(A) of a compressed row-major A by a binary search per row (columns increase along a row,
/// Eigen's invariant), with the values of a row some rows ahead prefetched: on a million rows the
/// load of each row's diagonal value waited on memory, one row after the other (Eigen's
/// A.diagonal() does the same searches without the prefetch; docs/setup_at_scale.md).
#include "solvers/core/types.hpp"

#include <algorithm>

namespace cb {

/// How many rows ahead sorted_rows_diagonal() prefetches.
constexpr Eigen::Index DIAGONAL_PREFETCH_AHEAD = 16;

/// Asks the cache for the middle of row i + DIAGONAL_PREFETCH_AHEAD of a compressed A (where a FEM
/// row's diagonal sits), so that a search per row does not wait on each row's value in turn.
inline void prefetch_diagonal_ahead(const int* outer, const double* val, Eigen::Index i, Eigen::Index rows)
{
    if (i + DIAGONAL_PREFETCH_AHEAD < rows)
        __builtin_prefetch(val + (outer[i + DIAGONAL_PREFETCH_AHEAD] + outer[i + DIAGONAL_PREFETCH_AHEAD + 1]) / 2);
}

/// A(i, i) where stored, else 0, as A.diagonal() gives it; any A (an uncompressed one through Eigen).
inline Vec sorted_rows_diagonal(const SpMat& A)
{
    if (!A.isCompressed()) return A.diagonal();
    const Eigen::Index n = std::min(A.rows(), A.cols());
    Vec d(n);
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const double* val = A.valuePtr();
    for (Eigen::Index i = 0; i < n; ++i) {
        prefetch_diagonal_ahead(outer, val, i, n);
        const int* end = inner + outer[i + 1];
        const int* at = std::lower_bound(inner + outer[i], end, static_cast<int>(i));
        d[i] = at != end && *at == i ? val[at - inner] : 0.0;
    }
    return d;
}

}  // namespace cb
