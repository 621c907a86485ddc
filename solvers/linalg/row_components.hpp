#pragma once
/// Connected components of the row graph of J: two rows are joined when they touch a common
/// vertex (vertex = column / 3, explicit zeros ignored, as in solvers/mprgp/decouple.cpp). Rows of
/// different components share no column, so J J' and J D^-1 J' are block diagonal over the
/// components and every face operator of the coupled MPRGP splits into one small problem per
/// component (ALGORITHMS.md §4).
#include "solvers/core/types.hpp"

#include <vector>

namespace cb {

struct RowComponents {
    std::vector<int> start;   ///< count + 1 offsets into `rows`
    std::vector<int> rows;    ///< the rows of component k are rows[start[k] .. start[k+1]), ascending
    std::vector<int> of_row;  ///< m: the component of each row
    int count() const { return static_cast<int>(start.size()) - 1; }
    int size(int k) const { return start[static_cast<size_t>(k) + 1] - start[static_cast<size_t>(k)]; }
    int largest() const;
    int singletons() const;  ///< components of one row
};

/// The components of J's row graph; a zero row is a component of its own. O(nnz(J) log).
RowComponents find_row_components(const SpMat& J);

}  // namespace cb
