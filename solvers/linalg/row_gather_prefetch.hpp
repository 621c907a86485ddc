#pragma once
/// A pass over J's rows reads each row's entries of several n-vectors. On a million DOFs the rows'
/// DOFs lie far apart and those reads missed the caches one after another; the entries of the row
/// some rows on are asked for as the pass starts a row (docs/a_product.md). No value changes. Below
/// ROW_GATHER_MIN_DOFS the vectors mostly sit in the caches and the pass skips the prefetch.
#include "solvers/core/types.hpp"

#include <array>
#include <cstddef>

namespace cb {

constexpr Eigen::Index ROW_GATHER_AHEAD = 16;
constexpr Eigen::Index ROW_GATHER_MIN_DOFS = Eigen::Index{1} << 17;

/// __builtin_prefetch, in a form the optimiser keeps: GCC 12 removed a loop of nothing but
/// __builtin_prefetch calls as a loop without effect.
inline void prefetch_kept(const void* address)
{
#if defined(__x86_64__) && defined(__GNUC__)
    asm volatile("prefetcht0 %0" : : "m"(*static_cast<const char*>(address)));
#else
    __builtin_prefetch(address);
#endif
}

/// Whether a row pass over n-vectors of this length prefetches.
inline bool row_gather_prefetches(Eigen::Index n) { return n >= ROW_GATHER_MIN_DOFS; }

/// Asks for row (i + ROW_GATHER_AHEAD)'s entries of each vector, when there is such a row.
template <std::size_t K>
inline void prefetch_row_ahead(const SpMat& J, Eigen::Index i, const std::array<const double*, K>& vectors)
{
    const Eigen::Index row = i + ROW_GATHER_AHEAD;
    if (row >= J.rows()) return;
    const int* outer = J.outerIndexPtr();
    const int* inner = J.innerIndexPtr();
    for (int k = outer[row]; k < outer[row + 1]; ++k)
        for (const double* v : vectors) prefetch_kept(v + inner[k]);
}

}  // namespace cb
